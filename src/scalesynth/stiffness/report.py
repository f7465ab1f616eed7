"""Stiffness of one mechanism at one pose, as a plain dict (what `scalesynth stiffness` prints)."""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

import numpy as np

from scalesynth.errors import InvalidParameter
from scalesynth.stiffness.solve import solve

if TYPE_CHECKING:  # annotations only: nothing below the mechanisms imports them
    from scalesynth.mechanisms.base import Mechanism


def modelled(mech: Mechanism) -> bool:
    """True if the mechanism supplies a stiffness model (a ``stiffness_model(design, options, pose)`` method)."""
    return callable(getattr(mech, "stiffness_model", None))


def _num(v: float) -> float | str:
    """JSON-safe number: infinities as the strings 'inf' / '-inf' (JSON has no infinity)."""
    v = float(v)
    return v if math.isfinite(v) else ("inf" if v > 0 else "-inf")


def _matrix(a: np.ndarray | None, n: int) -> list:
    if a is None:
        return [["inf"] * n for _ in range(n)]
    return [[_num(v) for v in row] for row in a]


JOINT_MODELS = ("ideal", "bonded")


def pose_stiffness(mech: Mechanism, design: Mapping[str, float], options: Mapping[str, Any], pose,
                   joints: str = "ideal") -> dict:
    """Deflection under options['load'], compliance and stiffness of the platform DOFs, stiffness_min and the model
    solved, every unit stated. ``mech``: any object with the Mechanism interface and a ``stiffness_model``.
    ``joints``: 'ideal' (moment-free passive joints, the per-voxel fields' model) or 'bonded' (passive joints
    welded). Raises InvalidParameter for an unmodelled mechanism or a bad ``joints``,
    InvalidPose outside the workspace."""
    if joints not in JOINT_MODELS:
        raise InvalidParameter(f"--joints: must be one of {', '.join(JOINT_MODELS)}, got {joints!r}")
    if not modelled(mech):
        # the command line names the modelled mechanisms (commands.stiffness, above the registry)
        raise InvalidParameter(f"mechanism: no stiffness model for {mech.name} yet")
    model = mech.stiffness_model(design, options, pose, joints)
    res = solve(model)
    u = model.length_unit
    n = len(res.dofs)
    return {
        "mechanism": mech.name,
        "pose": [float(v) for v in pose],
        "branch": mech.kernel_branch(options),
        "joints": joints,
        "units": {"length": u, "force": "N", "deflection": u, "compliance": f"{u}/N (translations), rad/(N*{u}) "
                  "(rotations)", "stiffness": f"N/{u} (translations), N*{u}/rad (rotations)",
                  "stiffness_min": f"N/{u}"},
        "dofs": list(res.dofs),
        "load": [float(v) for v in model.load],
        "deflection": [_num(v) for v in res.deflection],
        "deflection_norm": _num(res.deflection_norm),
        "singular": res.singular,
        "compliance": _matrix(res.C, n),
        "stiffness": _matrix(res.K, n),
        "stiffness_min": _num(res.stiffness_min),
        "model": model.to_dict(),
    }
