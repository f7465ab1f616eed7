"""Draw every registered mechanism at a nominal pose from its own link geometry (docs/figures/*.png).

Usage: python scripts/draw_mechanisms.py [OUT_DIR [NAME ...]]   (default docs/figures, every mechanism; the PNGs
there are committed)

What is drawn is the mechanism's ``link_geometry`` (the one place per mechanism that says which points a link joins:
the same capsules the clearance, cycles and dynamics use) at a nominal pose solved by its inverse kinematics in the
kernel's branch. Only the pose is chosen here, per mechanism (NOMINAL_POSES): a mechanism not listed, e.g. a user's
description, is drawn at the first pose its kernel reaches along the vertical line through its box's centre.
"""

from __future__ import annotations

import sys
from dataclasses import dataclass, field
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from scalesynth.mechanisms import available, get  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
# the drawn pose per mechanism, in its task coordinates (each mechanism page's figure states it)
NOMINAL_POSES = {
    "2pauu-ppap": (0.25, 0.35, 1.6),
    "delta": (0.0, 0.0, -1.0),
    "linear-delta": (0.0, 0.0, -1.0),
    "hexa": (0.0, 0.0, -0.6),
    "hexapod": (0.0, 0.0, 0.8),
    "planar-fivebar": (0.0, -725.0),
    "planar-fivebar-described": (0.0, -725.0),
    "pprs-rprs": (0.0, 0.0, 200.0),
    "rps-upu": (79.37, 0.307, 0.113),
    "rps-upu-tool": (-15.01, 5.64, 32.01),  # the tool point of rps-upu's pose (tool offset 50 mm)
    "ups-sspr": (0.2, 0.15, 10.0),
}
# designs drawn instead of the defaults (2pauu-ppap: Table-4 group 1 of its paper)
DESIGNS = {"2pauu-ppap": {"m": 0.857, "n": 0.706, "l1": 1.499, "l2": 1.5, "c": 0.1}}


@dataclass
class Drawing:
    """What to draw: the mechanism's link geometry at ``pose`` with joint values ``q``, its task point and notes."""

    geometry: object  # scalesynth.mechanisms.links.LinkGeometry
    pose: tuple
    q: np.ndarray
    point: np.ndarray
    notes: list[str] = field(default_factory=list)


def nominal_pose(mech, design, options) -> tuple:
    """NOMINAL_POSES' entry, or the first pose the kernel reaches (in its branch) along the vertical line through
    the bounding box's centre, scanned from the middle outwards."""
    if mech.name in NOMINAL_POSES:
        return NOMINAL_POSES[mech.name]
    lo, hi = mech.bounding_box(design, options)
    n = len(mech.task_axes)
    centre = 0.5 * (lo + hi)[:n]
    packed = mech.pack(design, options)
    for t in sorted(np.linspace(0.0, 1.0, 81), key=lambda v: abs(v - 0.5)):
        pose = centre.copy()
        pose[n - 1] = lo[n - 1] + t * (hi[n - 1] - lo[n - 1])
        if mech.point_kernel(packed, *pose, *([0.0] * (3 - n))) > 0.0:
            return tuple(float(v) for v in pose)
    raise SystemExit(f"{mech.name}: no reachable pose found to draw; add one to NOMINAL_POSES")


def drawing(mech, design, options) -> Drawing:
    """The mechanism's link geometry at its nominal pose, in the kernel's branch."""
    pose = nominal_pose(mech, design, options)
    want = mech.kernel_branch(options)
    sols = {s.label: s.values for s in mech.inverse_kinematics(design, options, pose)}
    if want not in sols:
        raise SystemExit(f"{mech.name}: nominal pose {pose} has no IK solution in branch {want!r}")
    q = sols[want]
    geo = mech.link_geometry(design, options, pose, q)
    if "angle" in mech.task_units:  # task coordinates are not a point: the mechanism says where its task point is
        point = np.asarray(mech.payload_point(design, options, pose), dtype=float)
    else:
        point = np.zeros(3)
        point[: len(pose)] = pose
    units = {"length": mech.default_length_unit, "angle": "rad"}
    axes = ", ".join(mech.task_axes)
    unit_text = ", ".join(units[u] for u in mech.task_units)
    joints = ", ".join(f"{j} = {v:.4g}" for j, v in zip(mech.joints, q, strict=True))
    return Drawing(geo, pose, q, point, [f"branch {want}, pose ({axes}) = {pose} ({unit_text})", joints])


def draw(name: str, path: Path) -> Path:
    """Draw mechanism ``name`` at its nominal pose with its default design (DESIGNS overrides)."""
    mech = get(name)
    design = mech.resolve_design(DESIGNS.get(name, {}))
    options = mech.resolve_options({})
    dr = drawing(mech, design, options)
    unit = mech.default_length_unit
    planar = mech.planar
    fig = plt.figure(figsize=(7.5, 6.2))
    ax = fig.add_subplot(111) if planar else fig.add_subplot(111, projection="3d")

    def plot(pts, *args, **kw):
        pts = np.atleast_2d(pts)
        if planar:
            return ax.plot(pts[:, 0], pts[:, 1], *args, **kw)
        return ax.plot(pts[:, 0], pts[:, 1], pts[:, 2], *args, **kw)

    def text(at, label, **kw):
        if planar:
            ax.text(at[0], at[1], label, **kw)
        else:
            ax.text(at[0], at[1], at[2], label, **kw)

    styles = {"base": dict(color="0.45", lw=3), "platform": dict(color="tab:blue", lw=3)}
    legend, labelled = set(), set()
    for seg in dr.geometry.segments:
        style = styles.get(seg.body, dict(color="tab:orange", lw=1.8))
        ends = np.array([seg.a, seg.b])
        kind = seg.body if seg.body in styles else "links"
        label = kind if kind not in legend else None
        legend.add(kind)
        if np.allclose(seg.a, seg.b):  # a ball (a platform point, a carriage without width)
            plot(ends[:1], "o", color=style["color"], ms=7, label=label)
        else:
            plot(ends, "o-", ms=3, label=label, **style)
        if seg.body not in styles and seg.body not in labelled:
            labelled.add(seg.body)
            text(ends.mean(axis=0), " " + seg.body, fontsize=8)
    plot(dr.point, "*", color="tab:red", ms=12, label="task point")
    a, b, _ = dr.geometry.as_arrays()
    allpts = np.vstack([a, b, dr.point[None]])
    # frame axes at the origin, 25 % of the drawing's size
    size = float(np.ptp(allpts, axis=0).max()) * 0.25
    for k, (axis, col) in enumerate(zip("xyz", ("r", "g", "b"), strict=True)):
        if planar and k == 2:
            break
        tip = np.zeros(3)
        tip[k] = size
        plot(np.array([np.zeros(3), tip]), "-", color=col, lw=1)
        text(tip, axis, color=col)
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
    ax.set_title(f"{name} ({origin}, {mech.motion}): {dims}\n" + "; ".join(dr.notes), fontsize=9)
    ax.legend(loc="upper left", fontsize=8)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def main(argv: list[str]) -> int:
    out = Path(argv[1]) if len(argv) > 1 else ROOT / "docs" / "figures"
    names = argv[2:] or available()
    for name in names:
        print(draw(name, out / f"{name}.png"))
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv))
