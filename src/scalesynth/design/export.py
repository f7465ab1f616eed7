"""Exports of a chosen design: its mechanism description with the numbers filled in (described mechanisms; loads
back with ``mechanism: {description: FILE}``) and a mesh of the robot at one pose (trimesh: every link capsule of
``Mechanism.link_geometry`` as a cylinder with a sphere at each end; STL or glTF binary)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from scalesynth.errors import InvalidParameter, InvalidPose, ScalesynthError

# a capsule of radius 0 (a line) is drawn with this share of the robot's size as its radius, so it has a surface
DISPLAY_RADIUS_SHARE = 0.01


def description_yaml(mech, design: dict[str, float], name: str | None = None) -> tuple[str, str] | None:
    """(name, YAML text) of a described mechanism's description with every parameter default set to ``design``,
    renamed ``<name>-design`` (a built-in name may not carry other content); None for a mechanism written in
    Python (no description to fill in)."""
    import yaml

    desc = getattr(mech, "description", None)
    if desc is None:
        return None
    data = desc.model_dump(mode="json", exclude_defaults=True)
    new = name or f"{mech.name}-design"
    data["name"] = new
    data["title"] = f"{data.get('title', mech.name)}: the design chosen by scalesynth design"
    for key, value in design.items():
        if key in data.get("parameters", {}):
            entry = data["parameters"][key]
            if isinstance(entry, dict):
                entry["default"] = float(value)
            else:
                data["parameters"][key] = float(value)
    header = (f"# {new}: {mech.name} with the chosen design's numbers as parameter defaults (scalesynth design).\n"
              "# Load it in a config with `mechanism: {description: " + f"{new}.yaml" + "}`.\n")
    return new, header + yaml.safe_dump(data, sort_keys=False)


def pose_joints(mech, design, options, pose) -> np.ndarray:
    """Joint values of the kernel's branch at ``pose`` (InvalidPose if out of reach)."""
    sols = mech.inverse_kinematics(design, options, np.asarray(pose, dtype=float))
    if not sols:
        raise InvalidPose(f"pose {[float(v) for v in pose]}: out of reach of this design")
    branch = mech.kernel_branch(options)
    return next((s.values for s in sols if s.label == branch), sols[0].values)


def geometry_at(mech, design, options, pose):
    """The design's LinkGeometry at ``pose`` (None when the mechanism has no link geometry yet)."""
    try:
        q = pose_joints(mech, design, options, pose)
        return mech.link_geometry(design, options, np.asarray(pose, dtype=float), q)
    except InvalidParameter:
        return None


def display_radii(geometry) -> np.ndarray:
    """The radius each capsule is meshed with: its own, or DISPLAY_RADIUS_SHARE of the robot's size when 0."""
    a, b, r = geometry.as_arrays()
    pts = np.vstack([a, b])
    size = float(np.max(pts.max(axis=0) - pts.min(axis=0))) or 1.0
    return np.where(r > 0, r, DISPLAY_RADIUS_SHARE * size)


def capsule_mesh(geometry):
    """One trimesh.Trimesh of every capsule: a cylinder a -> b and a sphere at each end (radius display_radii)."""
    import trimesh

    a, b, _ = geometry.as_arrays()
    radii = display_radii(geometry)
    parts = []
    for p, q, r in zip(a, b, radii, strict=True):
        for c in (p, q):
            ball = trimesh.creation.icosphere(subdivisions=2, radius=r)
            ball.apply_translation(c)
            parts.append(ball)
        if np.linalg.norm(q - p) > 1e-9 * max(1.0, r):
            parts.append(trimesh.creation.cylinder(radius=r, segment=np.array([p, q]), sections=24))
    return trimesh.util.concatenate(parts)


def robot_mesh(cfg, design: dict[str, float], pose=None):
    """The mesh of a config's design at ``pose`` (default: the centre of its task box, else of its cycle's
    start); None when the mechanism has no link geometry yet or the pose is out of reach."""
    mech = cfg.mech
    options = cfg.resolved_options()
    if pose is None:
        pose = default_pose(cfg)
    try:
        geometry = geometry_at(mech, mech.resolve_design(design), options, pose)
    except ScalesynthError:
        return None
    return None if geometry is None else capsule_mesh(geometry)


def default_pose(cfg) -> list[float]:
    if cfg.task is not None:
        return [0.5 * (cfg.task.box[ax][0] + cfg.task.box[ax][1]) for ax in cfg.mech.task_axes]
    lo, hi = cfg.mech.bounding_box(cfg.resolved_design(), cfg.resolved_options())
    return list(0.5 * (np.asarray(lo) + np.asarray(hi)))[: len(cfg.mech.task_axes)]


def write_mesh(mesh, path: Path) -> None:
    """STL (.stl) or glTF binary (.glb), written atomically."""
    from scalesynth import io as rio

    kind = Path(path).suffix.lower().lstrip(".")
    if kind not in ("stl", "glb"):
        raise InvalidParameter(f"--mesh: {Path(path).name}: expected a .stl or .glb file")
    data: Any = mesh.export(file_type=kind)
    rio.write_atomic(Path(path), lambda f: f.write(data), mode="wb")
