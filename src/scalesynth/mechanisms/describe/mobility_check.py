"""Does a description's legs make its motion type, and only with its actuators: a 3T description of Pa legs, a
platform that only translates; a 2T description of RR/PR legs, a platform point held in the plane.

Checked numerically at the description's default design, as the rank of the platform's twists with every actuator
locked (scalesynth.mobility's reading of a mechanism: the twists reciprocal to all the legs' constraint wrenches):

* rotations: a Pa leg lets the platform turn only about its parallelogram's hinge direction n_i (the arm's axis of an
  R-Pa leg, the carriage's cross direction of a P-Pa leg); the platform cannot turn iff the n_i span more than one
  direction (a rotation about n common to all legs is left otherwise: mobility 4, not 3T);
* translations: with the actuators locked each forearm keeps its length, f_i . v = 0; the platform is held iff the
  forearm directions span space (rank J_x = 3) at a generic reachable pose: two identical legs never do.

Motion 2T (planar, the platform point P in the plane z = 0; its orientation, where it has one, held by
parallelograms the legs do not show): each RR leg (crank R at B, then the link pinned at the elbow) or PR leg (slide
along the rail, then the link pinned at the carriage) leaves P two freedoms away from the leg's own singular poses,
and with the actuator locked one: the swing of its link, P's velocity normal to the link f_i. So the platform is
held with every actuator locked iff the links span the plane (rank [f_1; f_2] = 2) at a generic reachable pose.
Two legs that put their elbows or carriages at one point (the same leg twice, or one crank turned about the same
pivot, one slide on the same rail line) never do. An extra actuator (a third leg) is the schema's leg count.

The pose: the first of a few pseudo-random points of the bounding box that every leg reaches (limits included);
a description with none at its defaults is not judged here (its workspace is empty, which evaluate reports).
"""

from __future__ import annotations

import numpy as np

from scalesynth.errors import ConfigError, ScalesynthError

RANK_RTOL = 1e-9  # relative singular-value tolerance (unit vectors)
TRIES = 64
SEED = 20261


def _rank(rows: np.ndarray) -> int:
    sv = np.linalg.svd(rows, compute_uv=False)
    return int(np.sum(sv > RANK_RTOL * sv[0])) if sv[0] > 0 else 0


def check_mobility(desc) -> None:
    """ConfigError naming the leg and the field when the description's legs do not make its motion (3T of Pa legs,
    2T; module docstring)."""
    from scalesynth.mechanisms.describe.build import from_description

    if desc.motion == "2T":
        _check_planar(desc)
        return
    if desc.motion != "3T" or any(leg.type not in ("R-Pa", "P-Pa") for leg in desc.legs):
        return
    mech = from_description(desc)
    resolved = _defaults(mech)
    if resolved is None:
        return
    design, options, legs = resolved
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
    forearms = _unit_links(mech, design, options, legs, 3, lambda leg, q, point: leg.within_limits(q, point))
    if forearms is None or _rank(forearms) == 3:
        return
    same = _twin(legs)
    i = same if same is not None else last
    what = "repeats another leg, so the platform" if same is not None else "the platform"
    raise ConfigError(f"{where(i, 'base')}: {what} can translate with every actuator locked (the forearms do "
                      "not span space): motion 3T needs 3 independent legs")


def _defaults(mech):
    """(design, options, legs) at the mechanism's defaults, or None where they do not resolve (e.g. a P-Pa or PR
    leg whose stroke the config sets): such a description is not judged here."""
    try:
        design, options = mech.default_design(), mech.resolve_options({})
        return design, options, mech.legs(design, options)
    except ScalesynthError:
        return None


def _unit_links(mech, design, options, legs, dim: int, within) -> np.ndarray | None:
    """The legs' unit links (Q_i - E_i, rows) at the first of TRIES pseudo-random points of the bounding box that
    every leg reaches in the kernel's branch within its limits (``within(leg, q, point)``); None when none does."""
    lo, hi = (v[:dim] for v in mech.bounding_box(design, options))
    if not np.all(hi > lo):
        return None
    rng = np.random.default_rng(SEED)
    label = mech.kernel_branch(options)
    for point in lo + rng.random((TRIES, dim)) * (hi - lo):
        q = {s.label: s.values for s in mech.inverse_kinematics(design, options, point)}.get(label)
        if q is None or not all(within(leg, float(qi), point) for leg, qi in zip(legs, q, strict=True)):
            continue
        links = np.array([point + leg.platform - leg.actuated_point(float(qi)) for leg, qi in zip(legs, q,
                                                                                                  strict=True)])
        return links / np.linalg.norm(links, axis=1)[:, None]
    return None


def _twin(legs) -> int | None:
    """Index of the first leg that repeats an earlier one (same base point, platform offset and frame)."""
    for j in range(len(legs)):
        for i in range(j):
            a, b = legs[i], legs[j]
            if all(np.allclose(getattr(a, k), getattr(b, k), atol=1e-12) for k in ("base", "platform", "u", "w")):
                return j
    return None


def _check_planar(desc) -> None:
    """ConfigError naming the leg and the field when a 2T description's platform moves with its actuators locked
    (module docstring)."""
    from scalesynth.mechanisms.describe.build import from_description

    mech = from_description(desc)
    resolved = _defaults(mech)
    if resolved is None:
        return
    design, options, legs = resolved
    links = _unit_links(mech, design, options, legs, 2, lambda leg, q, point: leg.within_limits(q))
    if links is None or _rank(links) == 2:
        return
    same = _twin(legs)
    k = mech.plans[same if same is not None else len(legs) - 1].leg_index
    what = "repeats another leg, so the platform" if same is not None else "the platform"
    raise ConfigError(f"legs[{k}] ({desc.legs[k].name}).base: {what} can move with every actuator locked (the "
                      "links are parallel): motion 2T needs 2 independent legs")
