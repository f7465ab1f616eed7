"""Does a 3T description of Pa legs make a platform that only translates, and only with its actuators?

Checked numerically at the description's default design, as the rank of the platform's twists with every actuator
locked (scalesynth.mobility's reading of a mechanism: the twists reciprocal to all the legs' constraint wrenches):

* rotations: a Pa leg lets the platform turn only about its parallelogram's hinge direction n_i (the arm's axis of an
  R-Pa leg, the carriage's cross direction of a P-Pa leg); the platform cannot turn iff the n_i span more than one
  direction (a rotation about n common to all legs is left otherwise: mobility 4, not 3T);
* translations: with the actuators locked each forearm keeps its length, f_i . v = 0; the platform is held iff the
  forearm directions span space (rank J_x = 3) at a generic reachable pose: two identical legs never do.

The pose: the first of a few pseudo-random points of the bounding box that every leg reaches (limits included);
a description with none at its defaults is not judged here (its workspace is empty, which evaluate reports).
"""

from __future__ import annotations

import numpy as np

from scalesynth.errors import ConfigError

RANK_RTOL = 1e-9  # relative singular-value tolerance (unit vectors)
TRIES = 64


def _rank(rows: np.ndarray) -> int:
    sv = np.linalg.svd(rows, compute_uv=False)
    return int(np.sum(sv > RANK_RTOL * sv[0])) if sv[0] > 0 else 0


def check_mobility(desc) -> None:
    """ConfigError naming the leg and the field when the description's legs do not make a 3T platform."""
    from scalesynth.errors import ScalesynthError
    from scalesynth.mechanisms.describe.build import from_description

    if desc.motion != "3T" or any(leg.type not in ("R-Pa", "P-Pa") for leg in desc.legs):
        return
    mech = from_description(desc)
    try:
        design, options = mech.default_design(), mech.resolve_options({})
        legs = mech.legs(design, options)
    except ScalesynthError:
        return  # the defaults do not resolve (e.g. a P-Pa leg whose stroke the config sets): not judged here
    plans = mech.plans
    last = len(plans) - 1

    def where(i: int, field: str) -> str:
        k = plans[i].leg_index
        return f"legs[{k}] ({desc.legs[k].name}).{field}"

    normals = np.array([leg.normal for leg in legs])
    if _rank(normals) < 2:
        field = "arm_zero" if desc.legs[plans[last].leg_index].type == "R-Pa" else "rail"
        axis = ", ".join(f"{v + 0.0:.4g}" for v in normals[0])
        raise ConfigError(f"{where(last, field)}: every leg's parallelogram hinges about ({axis}), so the platform "
                          "can turn about it: motion 3T needs hinges in two directions at least")
    lo, hi = mech.bounding_box(design, options)
    if not np.all(hi > lo):
        return
    rng = np.random.default_rng(20261)
    for point in lo + rng.random((TRIES, 3)) * (hi - lo):
        sols = {s.label: s.values for s in mech.inverse_kinematics(design, options, point)}
        q = sols.get(mech.kernel_branch(options))
        if q is None or not all(leg.within_limits(qi, point) for leg, qi in zip(legs, q, strict=True)):
            continue
        forearms = np.array([point + leg.platform - leg.actuated_point(qi) for leg, qi in zip(legs, q, strict=True)])
        forearms /= np.linalg.norm(forearms, axis=1)[:, None]
        if _rank(forearms) == 3:
            return
        same = _twin(legs)
        i = same if same is not None else last
        what = "repeats another leg, so the platform" if same is not None else "the platform"
        raise ConfigError(f"{where(i, 'base')}: {what} can translate with every actuator locked (the forearms do "
                          "not span space): motion 3T needs 3 independent legs")
    return


def _twin(legs) -> int | None:
    """Index of the first leg that repeats an earlier one (same base point, platform offset and frame)."""
    for j in range(len(legs)):
        for i in range(j):
            a, b = legs[i], legs[j]
            if all(np.allclose(getattr(a, k), getattr(b, k), atol=1e-12) for k in ("base", "platform", "u", "w")):
                return j
    return None
