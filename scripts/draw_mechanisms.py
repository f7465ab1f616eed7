"""Draw every registered mechanism at a nominal pose from scalesynth's own NumPy kinematics (docs/figures/*.png).

Usage: python scripts/draw_mechanisms.py [OUT_DIR]   (default docs/figures; the PNGs there are committed)

The joint positions come from each mechanism's inverse kinematics; the per-mechanism geometry (which points a link
joins) lives only in LINKAGES below, in one place, so that it can be replaced by the mechanisms' own link geometry
once the Mechanism interface provides it.
"""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass, field
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from scalesynth.mechanisms import available, get  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]


@dataclass
class Linkage:
    """What to draw: closed polygons for the base and the platform, links as (start, end, label), joint markers."""

    base: list[np.ndarray]
    platform: np.ndarray
    links: list[tuple[np.ndarray, np.ndarray, str]]
    point: tuple[np.ndarray, str]  # the task point and its name
    notes: list[str] = field(default_factory=list)


def _solution(mech, design, options, pose, label=None):
    sols = mech.inverse_kinematics(design, options, pose)
    want = label or mech.kernel_branch(options)
    for s in sols:
        if s.label == want:
            return s.values
    raise SystemExit(f"{mech.name}: nominal pose {pose} has no IK solution in branch {want!r}")


def _pauu(mech, design, options):
    pose = (0.25, 0.35, 1.6)
    th1, th2, d = _solution(mech, design, options, pose)
    m, n, l1, e = design["m"], design["n"], design["l1"], options["e"]
    e = 2 * design["c"] if e is None else e
    x, y, z = pose
    pts = {}
    for i, (s, th) in enumerate(((1.0, th1), (-1.0, th2)), 1):
        pts[f"A{i}"] = np.array([s * m, 0.0, 0.0])
        pts[f"B{i}"] = np.array([s * m, 0.0, e])
        pts[f"C{i}"] = np.array([s * (m + l1 * math.cos(th)), 0.0, e - l1 * math.sin(th)])
        pts[f"D{i}"] = np.array([x + s * n, y, z])
    p = np.array(pose)
    base = [np.array([[m, m, 0], [-m, m, 0], [-m, -m, 0], [m, -m, 0]], dtype=float)]
    links = []
    for i in (1, 2):
        links += [(pts[f"A{i}"], pts[f"B{i}"], f"e (A{i}B{i})" if i == 1 else ""),
                  (pts[f"B{i}"], pts[f"C{i}"], f"l1, theta{i}"), (pts[f"C{i}"], pts[f"D{i}"], "l2")]
    # chain 3 (PPaP): input d = y moves the platform along y; drawn from the base centre
    foot = np.array([0.0, d, 0.0])
    links += [(np.zeros(3), foot, "d (chain 3, along y)"), (foot, np.array([x, y, 0.0]), ""),
              (np.array([x, y, 0.0]), p, "")]
    platform = np.array([pts["D1"], pts["D2"]])
    return Linkage(base, platform, links, (p, "P"), [f"mode {options['mode']}, e = {e:g} m, pose P = {pose} m"])


def _fivebar(mech, design, options):
    pose = (0.0, -725.0)
    q = _solution(mech, design, options, pose)
    q1, q2 = mech.elbows(design, q)
    r = design["r"]
    b1, b2 = np.array([r, 0.0, 0.0]), np.array([-r, 0.0, 0.0])
    e1, e2 = np.array([q1[0], q1[1], 0.0]), np.array([q2[0], q2[1], 0.0])
    p = np.array([pose[0], pose[1], 0.0])
    links = [(b1, e1, "l1, alpha1"), (b2, e2, "l1, alpha2"), (e1, p, "l2"), (e2, p, "l2")]
    return Linkage([np.array([b1, b2])], np.array([p]), links, (p, "P"),
                   [f"mode {options['mode']} (elbows out), pose P = {pose} mm"])


def _pprs(mech, design, options):
    from scalesynth.mechanisms import pprs_rprs as pr

    pose = (0.0, 0.0, 200.0)
    geo = pr.Geometry.of(design, options)
    X = mech.full_pose(options, pose)
    st = pr.chain_state(geo, X, pr.sigma_vector(mech.kernel_branch(options)))
    w1, w2, beta, s1, s2, s3 = st.q
    c = st.centres
    zhat = np.array([0.0, 0.0, 1.0])
    d1 = w1 * geo.u[0] + s1 * zhat
    d2 = w2 * geo.u[1] + s2 * zhat
    b3 = geo.rail * geo.u[2]
    d3 = b3 + s3 * (-math.cos(beta) * geo.u[2] + math.sin(beta) * zhat)
    links = [(np.zeros(3), geo.rail * geo.u[0], "rail u1 (w1)"), (np.zeros(3), geo.rail * geo.u[1], "rail u2 (w2)"),
             (w1 * geo.u[0], d1, "s1"), (w2 * geo.u[1], d2, "s2"), (b3, d3, "s3, beta"),
             (d1, c[0], "L1"), (d2, c[1], "L2"), (d3, c[2], "L3")]
    base = [np.array([np.zeros(3), b3])]
    return Linkage(base, c, links, (np.array(pose), "O1"),
                   [f"branch {mech.kernel_branch(options)}, pose O1 = {pose} mm, orientation 0"])


def _rps(mech, design, options, pose=(79.37, 0.307, 0.113), tool=False):
    g, h, c, e = (float(design[k]) for k in ("g", "h", "c", "e"))
    pp = mech.platform_pose(design, options, pose)
    p, rot = pp["p"], pp["R"]
    a = np.array([[0.0, -g, 0.0], [0.0, g, 0.0], [e, 0.0, 0.0]])
    b = p + np.array([[0.0, -h, 0.0], [0.0, h, 0.0], [c, 0.0, 0.0]]) @ rot.T
    links = [(a[i], b[i], f"q{i + 1}") for i in range(3)]
    point = (p, "O'")
    notes = [f"model {options.get('model', 'P')}, pose (z, theta, psi) = {pose} (mm, rad)"]
    if tool:
        t = mech.tool_point(design, options, pose)
        links.append((p, t, f"tool offset d = {options['tool_offset']:g}"))
        point = (t, "T")
    return Linkage([a], b, links, point, notes)


def _rps_tool(mech, design, options):
    return _rps(mech, design, options, tool=True)


def _ups(mech, design, options):
    alpha, beta, yy = 0.2, 0.15, 10.0
    a, bb, c = design["a"], design["b"], design["c"]
    s3 = math.sqrt(3.0) / 2.0
    base = np.array([[0.0, a, 0.0], [-s3 * a, -a / 2, 0.0], [s3 * a, -a / 2, 0.0]])
    rho = math.sqrt(c * c - yy * yy)
    b1 = np.array([math.sin(beta) * rho, yy, math.cos(beta) * rho])
    ca, sa, cb, sb = math.cos(alpha), math.sin(alpha), math.cos(beta), math.sin(beta)
    rot = np.array([[cb, 0, sb], [0, 1, 0], [-sb, 0, cb]]) @ np.array([[1, 0, 0], [0, ca, -sa], [0, sa, ca]])
    k = bb / math.sqrt(2.0)
    b2 = b1 + rot @ np.array([-k, k, 0.0])
    b3 = b1 + rot @ np.array([k, k, 0.0])
    mid = np.array([0.0, -a / 2, 0.0])
    b0 = 2.0 / 3.0 * b1
    links = [(np.zeros(3), b1, "c (SR link A0B1)"), (mid, b0, "l1 (SPR)"), (base[1], b2, "l2"), (base[2], b3, "l3")]
    return Linkage([base], np.array([b1, b2, b3]), links, (b1, "B1 = P"),
                   [f"pose (alpha, beta, Y) = ({alpha}, {beta}, {yy}) (rad, rad, mm)"])


def _described(mech, design, options):
    """A described mechanism (mechanisms/describe) at a pose below the base centre: each leg's arm from its base
    point to its elbow (or carriage) and the forearm on to its platform joint, from the description's legs."""
    pose = (0.0, 0.0, -1.0)
    q = _solution(mech, design, options, pose)  # the kernel's branch (elbows out)
    p = np.array(pose)
    legs = mech.legs(design, options)
    bases = np.array([leg.base for leg in legs])
    joints = np.array([p + leg.platform for leg in legs])
    links = []
    for i, (leg, qi) in enumerate(zip(legs, q, strict=True), 1):
        elbow = leg.actuated_point(qi)  # R-Pa: the elbow; P-Pa: the carriage, |elbow - base| = its joint value
        arm = "upper_arm" if leg.type.joint_unit == "angle" else "carriage"
        links += [(leg.base, elbow, f"{arm}, {mech.joints[i - 1]}"), (elbow, p + leg.platform, "forearm")]
    mode = "elbows out" if legs[0].type.joint_unit == "angle" else "platform below the carriages"
    return Linkage([bases], joints, links, (p, "P"), [f"pose P = {pose} m, {mode}"])


def _described_6dof(mech, design, options):
    """A described 6-DOF mechanism (describe/sixdof.py) at its nominal pose, the platform level: a hexapod's legs
    from base to platform joint (each labelled with its length q_i), a Hexa's arms to their elbows and rods on to
    the platform joints."""
    pose = (0.0, 0.0, 0.8) if mech.name == "hexapod" else (0.0, 0.0, -0.6)
    q = _solution(mech, design, options, pose)
    p = np.array(pose)
    rot = mech.rotation(options)
    legs = mech.legs(design, options)
    bases = np.array([leg.base for leg in legs])
    joints = np.array([p + rot @ leg.r for leg in legs])
    links = []
    for i, (leg, qi, joint) in enumerate(zip(legs, q, joints, strict=True)):
        if leg.rus:
            elbow = leg.actuated_point(qi)
            links += [(leg.base, elbow, f"arm, {mech.joints[i]}"), (elbow, joint, "rod")]
        else:
            links.append((leg.base, joint, mech.joints[i]))
    # the platform polygon in the order of the joints around it
    order = np.argsort(np.arctan2(joints[:, 1] - p[1], joints[:, 0] - p[0]))
    border = np.argsort(np.arctan2(bases[:, 1], bases[:, 0]))
    return Linkage([bases[border]], joints[order], links, (p, "P"), [f"pose P = {pose} m, platform level"])


LINKAGES = {
    "delta": _described,
    "linear-delta": _described,
    "hexa": _described_6dof,
    "hexapod": _described_6dof,
    "2pauu-ppap": _pauu,
    "planar-fivebar": _fivebar,
    "pprs-rprs": _pprs,
    "rps-upu": _rps,
    "rps-upu-tool": _rps_tool,
    "ups-sspr": _ups,
}


def draw(name: str, path: Path) -> Path:
    """Draw mechanism ``name`` at its nominal pose with its default design (2pauu-ppap: Table-4 group 1)."""
    mech = get(name)
    values = {"m": 0.857, "n": 0.706, "l1": 1.499, "l2": 1.5, "c": 0.1} if name == "2pauu-ppap" else {}
    design = mech.resolve_design(values)
    options = mech.resolve_options({})
    lk = LINKAGES[name](mech, design, options)
    unit = mech.default_length_unit
    planar = mech.planar
    fig = plt.figure(figsize=(7.5, 6.2))
    ax = fig.add_subplot(111) if planar else fig.add_subplot(111, projection="3d")

    def plot(pts, *args, **kw):
        pts = np.atleast_2d(pts)
        if planar:
            return ax.plot(pts[:, 0], pts[:, 1], *args, **kw)
        return ax.plot(pts[:, 0], pts[:, 1], pts[:, 2], *args, **kw)

    for poly in lk.base:
        closed = np.vstack([poly, poly[:1]]) if len(poly) > 2 else poly
        plot(closed, "-", color="0.45", lw=3, label="base")
    plat = np.vstack([lk.platform, lk.platform[:1]]) if len(lk.platform) > 2 else lk.platform
    plot(plat, "-", color="tab:blue", lw=3, label="platform")
    for start, end, label in lk.links:
        seg = np.array([start, end])
        plot(seg, "o-", color="tab:orange", lw=1.8, ms=4)
        if label:
            mid = seg.mean(axis=0)
            if planar:
                ax.text(mid[0], mid[1], " " + label, fontsize=8)
            else:
                ax.text(mid[0], mid[1], mid[2], " " + label, fontsize=8)
    point, pname = lk.point
    plot(point, "*", color="tab:red", ms=12, label=f"task point {pname}")
    # frame axes at the origin, 25 % of the drawing's size
    allpts = np.vstack([*lk.base, lk.platform, *[np.array([s, e]) for s, e, _ in lk.links]])
    size = float(np.ptp(allpts, axis=0).max()) * 0.25
    for k, (axis, col) in enumerate(zip("xyz", ("r", "g", "b"), strict=True)):
        if planar and k == 2:
            break
        tip = np.zeros(3)
        tip[k] = size
        plot(np.array([np.zeros(3), tip]), "-", color=col, lw=1)
        if planar:
            ax.text(tip[0], tip[1], axis, color=col)
        else:
            ax.text(tip[0], tip[1], tip[2], axis, color=col)
    ax.set_xlabel(f"x [{unit}]")
    ax.set_ylabel(f"y [{unit}]")
    if planar:
        ax.set_aspect("equal")
        ax.grid(alpha=0.3)
    else:
        ax.set_zlabel(f"z [{unit}]")
        lo, hi = allpts.min(axis=0), allpts.max(axis=0)
        half = (hi - lo).max() / 2
        centre = (hi + lo) / 2
        ax.set_xlim(centre[0] - half, centre[0] + half)
        ax.set_ylim(centre[1] - half, centre[1] + half)
        ax.set_zlim(centre[2] - half, centre[2] + half)
        ax.set_box_aspect((1, 1, 1))
        ax.view_init(elev=22, azim=-60)
    dims = ", ".join(f"{k} = {v:g}" for k, v in design.items())
    origin = f"seed {mech.seed}" if mech.seed else "described"
    ax.set_title(f"{name} ({origin}, {mech.motion}): {dims} {unit}\n" + "; ".join(lk.notes), fontsize=9)
    ax.legend(loc="upper left", fontsize=8)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def main(argv: list[str]) -> int:
    out = Path(argv[1]) if len(argv) > 1 else ROOT / "docs" / "figures"
    missing = sorted(set(available()) - set(LINKAGES))
    if missing:
        raise SystemExit(f"no drawing for {', '.join(missing)}: add it to LINKAGES in scripts/draw_mechanisms.py")
    for name in available():
        print(draw(name, out / f"{name}.png"))
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv))
