"""A design's datasheet: picks per minute against payload, the tool's peak speed and acceleration, the motors'
torques and utilisation (cycle.json's ``datasheet``, ``scalesynth cycle --datasheet``, the run report).

Per payload (DATASHEET_PAYLOADS and the cycle's own payload): the fixed-law rate (``dynamics.motors``: the
shortest period of the cycle's motion law within every motor limit, plus the dwell) and the time-optimal one
(``dynamics.optimal``: toppra under peak torque and speed); at the fixed-law rate the peak speed and acceleration
of the payload point (m/s, m/s^2), the peak and RMS motor torque (N m, RMS over the motion and the dwell), the peak
motor speed (rad/s) and their ratios to the ratings (largest actuator). The payload is a point mass, so every force
is affine in its mass: two analyses (the cycle's payload and one more kilogram) give every payload exactly.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from scalesynth.cycle import config as ccfg

DATASHEET_PAYLOADS = (0.1, 1.0, 3.0)  # kg: a light product, the vendors' 1 kg rating, a heavy gripper and product


def payloads_of(cyc) -> list[float]:
    """DATASHEET_PAYLOADS and the cycle's payload, ascending, without repeats."""
    return sorted(set(DATASHEET_PAYLOADS) | {float(cyc.payload)})


def datasheet(mech, design, options, cyc, length_unit: str, res) -> dict[str, Any] | None:
    """The datasheet of an analysed cycle ``res`` (``cycle.analysis.analyse`` at ``cyc``), None without motors."""
    from scalesynth.cycle.analysis import analyse
    from scalesynth.dynamics import motors as dm
    from scalesynth.dynamics import optimal

    mot = dm.of_cycle(cyc, len(mech.joints))
    if mot is None:
        return None
    loads = payloads_of(cyc)
    other = analyse(mech, design, options, cyc.model_copy(update={"payload": cyc.payload + 1.0}), length_unit)
    extra = np.asarray(loads)[:, None, None] - cyc.payload  # kg beyond the analysed payload, (P, 1, 1)
    force = res.force[None] + extra * (other.force - res.force)[None]
    force_gravity = res.force_gravity[None] + extra * (other.force_gravity - res.force_gravity)[None]
    P = len(loads)
    qd, qdd = np.repeat(res.qd[None], P, 0), np.repeat(res.qdd[None], P, 0)
    vals, binding = dm.cycle_motor_metrics(mot, res.traj, cyc, res.joint_units, length_unit, qd, qdd, force,
                                           force_gravity)
    js = dm.joint_si(res.joint_units, length_unit)
    speed, g, a = dm.motor_side(mot, qd * js, qdd * js, force, force_gravity)
    best = optimal.of_design(mech, design, options, cyc, length_unit, loads)
    m_per_unit = ccfg.METRES_PER_UNIT[length_unit]
    tool_speed = float(np.max(np.linalg.norm(res.payload_velocity, axis=1))) * m_per_unit
    tool_accel = float(np.max(np.linalg.norm(res.payload_accel, axis=1))) * m_per_unit
    w = dm.time_weights(res.traj.t)
    rest = dm.rest_samples(res.traj, cyc.preset)
    dwell = 2.0 * cyc.dwell_s
    rows = []
    for i, load in enumerate(loads):
        row = {"payload_kg": load, "picks_per_minute": float(vals["picks_per_minute"][i]),
               "cycle_time_s": float(vals["cycle_time_s"][i]), "binding_limit": str(binding[i]),
               "time_optimal_picks_per_minute": best[i].picks_per_minute,
               "time_optimal_cycle_time_s": best[i].cycle_time_s,
               "time_optimal_binding_limit": best[i].binding,
               "time_optimal_rms_torque_ratio": best[i].rms_torque_ratio}
        motion = vals["cycle_time_s"][i] - dwell
        if vals["picks_per_minute"][i] > 0 and motion > 0:
            s = res.traj.period / motion  # the rate factor of the fastest fixed-law cycle
            tau = g[i] + s * s * a[i]
            g_rest2 = np.mean(g[i][list(rest)] ** 2, axis=0)
            rms = np.sqrt(dm.mean_square_torque(g[i][None], a[i][None], w, np.array([s]), dwell / res.traj.period,
                                   g_rest2[None]))[0]
            row.update({
                "peak_tool_speed_m_s": tool_speed * s, "peak_tool_accel_m_s2": tool_accel * s * s,
                "peak_motor_torque_Nm": float(np.max(np.abs(tau))), "rms_motor_torque_Nm": float(np.max(rms)),
                "peak_motor_speed_rad_s": float(np.max(np.abs(speed[i]))) * s,
                "motor_peak_torque_ratio": float(np.max(np.abs(tau) / mot.peak_torque)),
                "motor_rms_torque_ratio": float(np.max(rms / mot.rated_torque)),
                "motor_speed_ratio": float(np.max(np.abs(speed[i]) * s / mot.max_speed)),
            })
        else:
            row.update(dict.fromkeys(ROW_AT_RATE))
        rows.append(row)
    return {
        "motor": mot.model or "inline ratings",
        "gear_ratio": [float(v) for v in mot.gear_ratio],
        "peak_torque_Nm": float(np.max(mot.peak_torque)), "rated_torque_Nm": float(np.max(mot.rated_torque)),
        "max_speed_rad_s": float(np.max(mot.max_speed)),
        "cycle": cyc.preset or "path", "dwell_s": cyc.dwell_s, "rows": rows,
        "note": "picks_per_minute: the cycle's motion law at its fastest within peak torque, rated (RMS) torque and "
                "speed; time_optimal: toppra along the same path within peak torque and speed only; speeds, "
                "accelerations and motor values at the fixed-law rate",
    }


ROW_AT_RATE = ("peak_tool_speed_m_s", "peak_tool_accel_m_s2", "peak_motor_torque_Nm", "rms_motor_torque_Nm",
               "peak_motor_speed_rad_s", "motor_peak_torque_ratio", "motor_rms_torque_ratio", "motor_speed_ratio")
# the compact table: (column title, row key, format)
TABLE = (("kg", "payload_kg", "{:g}"), ("picks/min", "picks_per_minute", "{:.1f}"),
         ("optimal", "time_optimal_picks_per_minute", "{:.1f}"), ("tool m/s", "peak_tool_speed_m_s", "{:.2f}"),
         ("tool m/s2", "peak_tool_accel_m_s2", "{:.1f}"), ("peak Nm", "peak_motor_torque_Nm", "{:.2f}"),
         ("rms Nm", "rms_motor_torque_Nm", "{:.2f}"), ("peak %", "motor_peak_torque_ratio", "{:.0%}"),
         ("rms %", "motor_rms_torque_ratio", "{:.0%}"), ("speed %", "motor_speed_ratio", "{:.0%}"),
         ("binding", "binding_limit", "{}"))


def _cell(fmt: str, value) -> str:
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return "-"
    return fmt.format(value)


def table_rows(sheet: dict[str, Any]) -> tuple[list[str], list[list[str]]]:
    """(header, rows of cells) of the compact datasheet table."""
    header = [t for t, _, _ in TABLE]
    return header, [[_cell(fmt, row.get(key)) for _, key, fmt in TABLE] for row in sheet["rows"]]


def text_table(sheet: dict[str, Any]) -> str:
    """The datasheet as aligned plain text (``scalesynth cycle --datasheet``)."""
    header, rows = table_rows(sheet)
    widths = [max(len(r[c]) for r in [header, *rows]) for c in range(len(header))]
    ratio = sheet["gear_ratio"]
    gear = f"{ratio[0]:g}" if len(set(ratio)) == 1 else "/".join(f"{v:g}" for v in ratio)
    lines = [f"datasheet: motor {sheet['motor']} (peak {sheet['peak_torque_Nm']:g} N m, rated "
             f"{sheet['rated_torque_Nm']:g} N m, {sheet['max_speed_rad_s']:g} rad/s), gear {gear}, cycle "
             f"{sheet['cycle']}, dwell {sheet['dwell_s']:g} s at pick and at place"]
    for r in [header, *rows]:
        lines.append("  " + "  ".join(c.rjust(w) if i < len(r) - 1 else c for i, (c, w) in
                                      enumerate(zip(r, widths, strict=True))))
    return "\n".join(lines)


def markdown_table(sheet: dict[str, Any]) -> str:
    """The datasheet as a Markdown table with its header line."""
    header, rows = table_rows(sheet)
    out = [text_table(sheet).splitlines()[0], "", "| " + " | ".join(header) + " |",
           "|" + "---|" * len(header)]
    out += ["| " + " | ".join(r) + " |" for r in rows]
    return "\n".join(out)


def of_featured(result, featured: list[tuple[str, int]]) -> tuple[str, dict[str, Any] | str] | None:
    """The datasheet of a run's first featured design (the knee where there is one) when its config has a cycle
    and motors: (label, sheet), or (label, why) when that design's cycle cannot be followed; None otherwise."""
    from scalesynth.cycle.analysis import analyse
    from scalesynth.errors import ScalesynthError

    if result.cfg.cycle is None or getattr(result.cfg.cycle, "_motors", None) is None or not featured:
        return None
    label, row = next((f for f in featured if f[0] == "knee"), featured[0])
    rec = result.pareto.iloc[row]
    cfg = result.config_of(rec)  # the row's own gear ratio when the search varies it (bounds.gear_ratio)
    design = result.design_of(rec)
    options = cfg.resolved_options()
    try:
        res = analyse(cfg.mech, design, options, cfg.cycle, cfg.units.length)
        return label, datasheet(cfg.mech, design, options, cfg.cycle, cfg.units.length, res)
    except ScalesynthError as err:
        return label, str(err)


def html_table(sheet: dict[str, Any]) -> str:
    """The datasheet as an HTML table with its header line (report.html)."""
    import html

    header, rows = table_rows(sheet)
    head = "".join(f"<th>{html.escape(h)}</th>" for h in header)
    body = "".join("<tr>" + "".join(f"<td>{html.escape(c)}</td>" for c in r) + "</tr>" for r in rows)
    return (f"<p>{html.escape(text_table(sheet).splitlines()[0])}</p><table><thead><tr>{head}</tr></thead>"
            f"<tbody>{body}</tbody></table>")
