"""The datasheet of one design (``scalesynth datasheet RUN --design knee``; ``design`` writes it for the chosen
one): a self-contained HTML page in a robot vendor's format. Working range (side and top views of the reachable
workspace through the zone's centre, the working zone drawn inside it, the robot at the zone's centre from its link
geometry, dimensioned), picks per minute against payload, peak actuator speed and acceleration, motor margins,
deflection under load, dexterity, dimensions, footprint. A figure this scalesynth cannot compute for the mechanism
is printed as "not evaluated" with the reason, never estimated."""

from __future__ import annotations

import html as h
import math

import numpy as np

DATASHEET_PAYLOADS = (0.1, 1.0, 3.0)  # kg, besides the rated payload
MOTOR_UNITS = {"peak_torque": "N m", "rated_torque": "N m", "max_speed": "rad/s", "rotor_inertia": "kg m^2"}
GRID = 90  # points per axis of the working-range sections
# the page's style; its print (scalesynth.html_print, a browser's print dialog) is A4 with 12 mm margins, the two
# views side by side scaled to the page's width, a section's heading kept with its table, no table row split
# across pages, the headings' colour kept
STYLE = ("body{font-family:sans-serif;max-width:980px;margin:1.5em auto}"
         "table{border-collapse:collapse;width:100%;margin-bottom:.8em}th,td{border-bottom:1px solid #ddd;"
         "text-align:left;padding:3px 8px;font-size:13px}th{width:45%;font-weight:normal;color:#444}"
         "h1{margin-bottom:0}h2{font-size:15px;background:#1f5fbf;color:#fff;padding:3px 8px}"
         ".views{display:flex;gap:12px;flex-wrap:wrap}"
         "@page{size:A4;margin:12mm}"
         "@media print{body{max-width:none;margin:0;-webkit-print-color-adjust:exact;print-color-adjust:exact}"
         ".views{flex-wrap:nowrap;gap:2%;break-inside:avoid}.views svg{width:49%;height:auto}"
         "h2{break-after:avoid;page-break-after:avoid}tr{break-inside:avoid;page-break-inside:avoid}"
         "table{break-inside:avoid;page-break-inside:avoid}th,td{font-size:10.5pt}}")


def _fmt(v, unit: str = "", digits: int = 4) -> str:
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "-"
    return f"{v:.{digits}g}" + (f" {unit}" if unit else "")


def _section(mech, packed, lo, hi, axes: tuple[int, int], fixed: dict[int, float]) -> np.ndarray:
    """Reachability (GRID, GRID) bool of the plane through ``fixed`` spanned by task axes ``axes`` over [lo, hi]."""
    from scalesynth.kernels import grid

    u = np.linspace(lo[axes[0]], hi[axes[0]], GRID)
    v = np.linspace(lo[axes[1]], hi[axes[1]], GRID)
    U, V = np.meshgrid(u, v, indexing="xy")
    pts = np.zeros((GRID * GRID, 3))
    pts[:, axes[0]] = U.ravel()
    pts[:, axes[1]] = V.ravel()
    for ax, val in fixed.items():
        pts[:, ax] = val
    fields = grid.population_points_fields(mech.field_kernel, mech.n_fields, packed[None, :], pts)
    return (fields[0, :, 0] >= 0).reshape(GRID, GRID)


def _svg_view(reach, lo, hi, axes, names, zone, segments, unit, title, base_plane=False) -> str:
    """One view as SVG: reachable cells (grey), the working zone (blue rectangle), the robot's capsules (dark
    lines), a dimension line of the reachable width and the axes' ranges."""
    W, H, pad = 420, 360, 46
    x0, x1, y0, y1 = lo[axes[0]], hi[axes[0]], lo[axes[1]], hi[axes[1]]
    s = min((W - 2 * pad) / (x1 - x0), (H - 2 * pad) / (y1 - y0))

    def X(x):
        return pad + (x - x0) * s

    def Y(y):
        return H - pad - (y - y0) * s

    cw, ch = (x1 - x0) / (GRID - 1) * s, (y1 - y0) / (GRID - 1) * s
    parts = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{H}" viewBox="0 0 {W} {H}" class="view">',
             f'<text x="{W / 2}" y="16" text-anchor="middle" font-size="13">{h.escape(title)}</text>']
    ys, xs = np.nonzero(reach)
    u = np.linspace(x0, x1, GRID)
    v = np.linspace(y0, y1, GRID)
    for i, j in zip(ys, xs, strict=True):
        parts.append(f'<rect x="{X(u[j]) - cw / 2:.1f}" y="{Y(v[i]) - ch / 2:.1f}" width="{cw + 0.3:.1f}" '
                     f'height="{ch + 0.3:.1f}" fill="#d5d5d5"/>')
    (zx0, zx1), (zy0, zy1) = zone
    parts.append(f'<rect class="zone" x="{X(zx0):.1f}" y="{Y(zy1):.1f}" width="{(zx1 - zx0) * s:.1f}" '
                 f'height="{(zy1 - zy0) * s:.1f}" fill="none" stroke="#1f5fbf" stroke-width="2"/>')
    if base_plane and y0 < 0 < y1:  # the vertical axis of a side view: the robot's base plane at 0
        parts.append(f'<line class="base" x1="{pad}" y1="{Y(0):.1f}" x2="{W - pad}" y2="{Y(0):.1f}" stroke="#888" '
                     f'stroke-dasharray="5,3"/><text x="{W - pad}" y="{Y(0) - 3:.1f}" text-anchor="end" '
                     'font-size="10" fill="#666">base plane</text>')
    for a, b in segments:
        parts.append(f'<line class="link" x1="{X(a[axes[0]]):.1f}" y1="{Y(a[axes[1]]):.1f}" x2="{X(b[axes[0]]):.1f}"'
                     f' y2="{Y(b[axes[1]]):.1f}" stroke="#333" stroke-width="3" stroke-linecap="round"/>')
    if len(xs):
        ra, rb = u[xs.min()], u[xs.max()]
        yd = H - pad + 18
        parts.append(f'<line x1="{X(ra):.1f}" y1="{yd}" x2="{X(rb):.1f}" y2="{yd}" stroke="#000" '
                     'marker-start="url(#arr)" marker-end="url(#arr)"/>')
        parts.append(f'<text class="dim" x="{(X(ra) + X(rb)) / 2:.1f}" y="{yd - 4}" text-anchor="middle" '
                     f'font-size="11">{_fmt(rb - ra)} {unit}</text>')
    zw = zx1 - zx0
    parts.append(f'<text class="dim" x="{X(zx0):.1f}" y="{Y(zy1) - 4:.1f}" font-size="11" fill="#1f5fbf">zone '
                 f'{_fmt(zw)} x {_fmt(zy1 - zy0)} {unit}</text>')
    parts.append(f'<text x="{W - 4}" y="{H - 4}" text-anchor="end" font-size="10">{names[0]} [{_fmt(x0)}, '
                 f'{_fmt(x1)}], {names[1]} [{_fmt(y0)}, {_fmt(y1)}] {unit}</text>')
    parts.append('<defs><marker id="arr" markerWidth="8" markerHeight="8" refX="4" refY="4" orient="auto-start-'
                 'reverse"><path d="M0,1 L8,4 L0,7" fill="#000"/></marker></defs></svg>')
    return "".join(parts)


def _motor_text(motor) -> str:
    """The motors section without its gear ratio, e.g. 'peak torque 4.46 N m, ...' or 'catalogue builtin, model X'."""
    named = motor.model_dump(mode="json", exclude={"gear_ratio"}, exclude_none=True)
    return ", ".join(f"{k.replace('_', ' ')} {v}" + (f" {MOTOR_UNITS[k]}" if k in MOTOR_UNITS else "")
                     for k, v in named.items())


def _rate_rows(cfg, design) -> list[tuple[str, str]]:
    """(payload, picks per minute) rows: evaluated through the cycle analysis when the catalogue has the motor
    metrics and the config has a cycle and motors; else one row saying why not."""
    from scalesynth.metrics import catalogue

    cat = catalogue(cfg.mech, cfg.units.length)
    if "picks_per_minute" not in cat:
        return [("all", "not evaluated: this scalesynth has no motor model (no picks_per_minute metric)")]
    if cfg.cycle is None or getattr(cfg, "motors", None) is None:
        return [("all", "not evaluated: the run has no cycle with motors")]
    from scalesynth.cycle.population import population_metrics

    rated = cfg.cycle.payload
    rows = []
    for p in sorted({*DATASHEET_PAYLOADS, rated}):
        cyc = cfg.cycle.model_copy(update={"payload": p})
        vals = population_metrics(cfg.mech, [design], cfg.resolved_options(), cyc, cfg.units.length)
        rows.append((f"{p:g} kg" + (" (rated)" if p == rated else ""), _fmt(float(vals["picks_per_minute"][0]))))
    return rows


def build(result, row: int, spec=None, label: str | None = None) -> str:
    """The datasheet page (HTML text) of row ``row`` of a run's front."""
    from scalesynth.design.export import default_pose, geometry_at
    from scalesynth.errors import InvalidPose
    from scalesynth.metrics import DATASHEET_DEXTERITY, catalogue

    rec = result.pareto.iloc[row]
    cfg = result.config_of(rec)  # the row's own gear ratio when the search varies it (bounds.gear_ratio)
    mech = cfg.mech
    unit = cfg.units.length
    design = mech.resolve_design(result.design_of(rec))
    options = cfg.resolved_options()
    cat = catalogue(mech, unit)

    def value(name):
        m = cat.get(name)
        if m is None or m.column not in rec.index:
            return None
        try:
            v = float(rec[m.column])
        except (TypeError, ValueError):
            return None
        return v if math.isfinite(v) else None

    packed = np.asarray(mech.pack(design, options), dtype=float)
    lo, hi = (np.asarray(v, dtype=float) for v in mech.bounding_box(design, options))
    pose = default_pose(cfg)
    try:
        geometry = geometry_at(mech, design, options, pose)
    except InvalidPose:  # no task box and the bounding box's centre out of reach: the views show no robot
        geometry = None
    segs = [] if geometry is None else [(s.a, s.b) for s in geometry.segments]
    box = cfg.task.box if cfg.task is not None else {ax: (lo[i], hi[i]) for i, ax in enumerate(mech.task_axes)}
    axes_names = mech.task_axes
    views = []
    if len(axes_names) == 3:
        if segs:  # the drawing holds the robot too
            pts = np.array([p for s in segs for p in s])
            lo = np.minimum(lo, pts.min(axis=0))
            hi = np.maximum(hi, pts.max(axis=0))
        views.append(_svg_view(_section(mech, packed, lo, hi, (0, 2), {1: pose[1]}), lo, hi, (0, 2), ("x", "z"),
                               (box["x"], box["z"]), segs, unit, f"side view (x-z at y = {_fmt(pose[1])})", True))
        views.append(_svg_view(_section(mech, packed, lo, hi, (0, 1), {2: pose[2]}), lo, hi, (0, 1), ("x", "y"),
                               (box["x"], box["y"]), segs, unit, f"top view (x-y at z = {_fmt(pose[2])})"))
    elif len(axes_names) == 2:
        lo3, hi3 = lo.copy(), hi.copy()
        views.append(_svg_view(_section(mech, packed, lo3, hi3, (0, 1), {2: 0.0}), lo3, hi3, (0, 1), ("x", "y"),
                               (box["x"], box["y"]), segs, unit, "working range (x-y plane)", True))
    not_eval = "not evaluated"
    ratio = {n: value(n) for n in ("motor_peak_torque_ratio", "motor_rms_torque_ratio", "motor_speed_ratio")}
    motor = getattr(cfg, "motors", None)
    motor_rows = ([(f"{n.replace('motor_', '').replace('_ratio', '').replace('_', ' ')} margin",
                    _fmt(None if v is None else 100 * (1 - v), "%")) for n, v in ratio.items()]
                  if motor is not None and any(v is not None for v in ratio.values())
                  else [("motor and gear", f"{not_eval}: " + ("the run names no motors" if "picks_per_minute" in cat
                                                               else "this scalesynth has no motor model"))])
    if motor is not None:
        searched = " (searched: this design's own)" if result.problem.searches_gear_ratio else ""
        motor_rows[:0] = [("motor", _motor_text(motor)),
                          ("gear ratio" + searched, ", ".join(_fmt(float(n)) for n in np.atleast_1d(motor.gear_ratio)))]
    peaks = [(n.replace("cycle_max_actuator_", "peak actuator ").replace("_", " "), _fmt(value(n), cat[n].unit))
             for n in cat if n.startswith("cycle_max_actuator_") and value(n) is not None]
    if not peaks:
        peaks = [("peak speed and acceleration", f"{not_eval}: the run has no cycle (or the mechanism cannot run "
                  "one yet)")]
    defl = value("task_max_deflection")
    defl_text = (_fmt(defl, unit) + f" under {_fmt(float(np.linalg.norm(options.get('load'))), 'N')}"
                 if defl is not None else f"{not_eval}: " + ("no stiffness model for this mechanism yet"
                                                             if "task_max_deflection" not in cat
                                                             else "the run does not compute it"))
    rows: list[tuple[str, list[tuple[str, str]]]] = [
        ("Dimensions", [(k, _fmt(v, unit)) for k, v in design.items()]
         + [("link length sum", _fmt(value("link_length_sum"), unit)),
            ("footprint radius", _fmt(value("footprint_radius"), unit))]),
        ("Working range", [(f"working zone {ax}", f"[{_fmt(a)}, {_fmt(b)}] {unit}") for ax, (a, b) in box.items()]
         + [("zone covered", _fmt(None if value("task_coverage") is None else 100 * value("task_coverage"), "%")),
            ("workspace " + mech.measure_name(), _fmt(value("volume"), mech.measure_unit(unit)))]),
        ("Picks per minute against payload", _rate_rows(cfg, design)),
        ("Peak speed and acceleration (over the cycle)", peaks),
        ("Motor and gear", motor_rows),
        ("Stiffness", [("largest deflection over the zone", defl_text)]),
        ("Dexterity", [(text, _fmt(value(name))) for name, text in DATASHEET_DEXTERITY]),
        ("Mass", [("moving mass", f"{not_eval}: " + ("the run has no dynamics section"
                                                     if "picks_per_minute" in cat else "no mass model"))]),
    ]
    title = f"{getattr(mech, 'title', mech.name)}"
    which = label or f"row {row}"
    tables = "".join(f"<h2>{h.escape(t)}</h2><table>" + "".join(
        f"<tr><th>{h.escape(k)}</th><td>{h.escape(v)}</td></tr>" for k, v in rs)
        + "</table>" for t, rs in rows)
    src = f"spec {h.escape(spec.name)}, " if spec is not None else ""
    return ("<!DOCTYPE html><html><head><meta charset=\"utf-8\"><title>Datasheet: "
            f"{h.escape(mech.name)}</title><style>{STYLE}</style></head><body>"
            f"<h1>{h.escape(title)}</h1><p>{h.escape(mech.name)}, design {h.escape(which)} ({src}run "
            f"{h.escape(result.out_dir.name)}); lengths in {h.escape(unit)}. Grey: reachable workspace through the "
            "zone's centre; blue: the working zone; dark: the robot at the zone's centre.</p>"
            f"<div class=\"views\">{''.join(views)}</div>{tables}"
            "<p style=\"font-size:11px;color:#666\">Generated by scalesynth; every figure comes from the run's "
            "models (docs/design.md says which).</p></body></html>")
