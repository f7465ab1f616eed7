"""The bodies of a described mechanism, derived from its description alone: link capsules (clearance, the robot
drawing, cycles) and the names the dynamics and the stiffness frame share (docs/describing.md, "Bodies").

Per leg i (1-based, in the order of the expanded legs), with E the elbow (R-Pa) or carriage point (P-Pa) at the
joint value, Q = P + r_p the platform joint, n the normal of the leg's plane (R-Pa: the actuated axis u x w; P-Pa:
the carriage's cross direction) and h half the leg's parallelogram ``width``:

* ``upper_arm<i>`` (R-Pa): the arm B -> E, and with a width the elbow's short side E - h n -> E + h n;
* ``rail<i>`` (P-Pa): the rail B + lo e -> B + hi e over the stroke; ``carriage<i>``: its short side
  E - h n -> E + h n (a ball at E without a width);
* ``forearm<i>``: the parallelogram's two long bars E +- h n -> Q +- h n (one bar E -> Q on the centre line
  when the width is 0), one body: the bars of one parallelogram are never checked against each other;
* ``base``: the closed polygon through the legs' base points B_i; ``platform``: the closed polygon through the
  platform joints Q_i +- h n_i, in angular order about P.

6-DOF legs (sixdof.py), with Q = P + R r the platform joint at the options' orientation R:

* RUS / R-SS: ``upper_arm<i>`` the arm B -> E, ``rod<i>`` the rod E -> Q (one bar);
* UPS / SPS: ``leg<i>`` the whole leg B -> Q as one body (a telescoping actuator modelled as one rod stretching
  uniformly between its joints: the dynamics gives it a constant mass; the stiffness frame splits it into a
  cylinder and a piston, frame6.py);
* ``base`` and ``platform`` the closed polygons through the B_i and the Q_i, as above.

A body's *group* is its name without the leg number (``Segment.group``): upper_arm, forearm, carriage, rail,
rod, leg, base, platform. Adjacent (sharing a joint): base-upper_arm, upper_arm-forearm, base-rail, rail-carriage,
carriage-forearm, forearm-platform, upper_arm-rod, rod-platform, base-leg, leg-platform, and rail-forearm of one
leg: the model puts the carriage's joint on the rail's line, so that pair would always touch.

Capsule radii: option ``link_radius`` (a number, or a mapping of groups or bodies to radii, a body's entry
winning over its group's), defaults DEFAULT_RADII_M in metres, converted to the description's length unit.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from scalesynth.errors import InvalidParameter
from scalesynth.kernels import clearance as _kc
from scalesynth.mechanisms import links
from scalesynth.mechanisms.describe import kernel as _k
from scalesynth.mechanisms.describe import kernel2 as _k2
from scalesynth.mechanisms.describe import kernel6 as _k6

# capsule radii (m) when link_radius does not give them: illustrative, a mid-size Delta's
DEFAULT_RADII_M = {"base": 0.04, "upper_arm": 0.025, "forearm": 0.01, "platform": 0.02, "rail": 0.02,
                   "carriage": 0.03, "rod": 0.01, "leg": 0.025}
UNITS_PER_M = {"m": 1.0, "dm": 10.0, "cm": 100.0, "mm": 1000.0}
LINK_RADIUS_DOC = ("capsule radius of every body, or {group or body: radius} (groups upper_arm, forearm, carriage, "
                   "rail, rod, leg, base, platform); null = defaults (docs/describing.md)")
# options every described mechanism has, whatever its description declares (schema refuses them as names)
RESERVED_OPTIONS = ("link_radius", "youngs_modulus", "poisson_ratio", "tube", "sections", "actuator_stiffness", "load",
                    "stiffness_metrics", "clearance_metrics", "interference_free")


def leg_bodies(code: float, i: int) -> tuple[str, ...]:
    """The moving bodies of leg i (1-based) of leg type ``code`` (kernel codes), base side first."""
    if code == _k.R_PA:
        return (f"upper_arm{i}", f"forearm{i}")
    if code == _k6.RUS:
        return (f"upper_arm{i}", f"rod{i}")
    if code == _k6.UPS:
        return (f"leg{i}",)
    if code == _k2.RR:
        return (f"arm{i}", f"forearm{i}")
    return (f"rail{i}", f"carriage{i}", f"forearm{i}")


def body_names(codes: Sequence[float]) -> tuple[str, ...]:
    """Every body of a mechanism whose legs have these type codes, in link_geometry's order."""
    out = ["base"]
    for i, code in enumerate(codes, 1):
        out += leg_bodies(code, i)
    return tuple(out) + ("platform",)


def group_of(body: str) -> str:
    """The group of a body name: the name without its trailing leg number ('forearm2' -> 'forearm')."""
    return body.rstrip("0123456789")


def check_link_radius(options: dict[str, Any], codes: Sequence[float]) -> None:
    """Validate options['link_radius'] against the bodies and their groups; InvalidParameter naming the entry."""
    bodies = body_names(codes)
    links.check_radius_option(options, tuple(dict.fromkeys(tuple(map(group_of, bodies)) + bodies)))


def radii(options: Mapping[str, Any], codes: Sequence[float], length_unit: str,
          defaults_m: Mapping[str, float] = DEFAULT_RADII_M) -> dict[str, float]:
    """Capsule radius per body (length unit): the defaults (m, by group), then link_radius's groups, then its
    bodies."""
    scale = UNITS_PER_M[length_unit]
    bodies = body_names(codes)
    value = options.get("link_radius")
    out = {b: defaults_m[group_of(b)] * scale for b in bodies}
    if value is None:
        return out
    if not isinstance(value, Mapping):
        return {b: float(value) for b in bodies}
    for b in bodies:
        if group_of(b) in value:
            out[b] = float(value[group_of(b)])
    for b in bodies:
        if b in value:
            out[b] = float(value[b])
    return out


def link_geometry(legs, widths: Sequence[float], rad: Mapping[str, float], pose, q) -> links.LinkGeometry:
    """Capsules and adjacency at platform centre ``pose`` with joint values ``q`` (module docstring). ``legs``:
    the resolved legs (legs.Leg), ``widths``: each leg's parallelogram width, ``rad``: radius per body."""
    p = np.asarray(pose, dtype=float)
    segs: list[links.Segment] = []
    pairs: list[tuple[str, str]] = []
    base_pts, plat_pts = [], []

    def seg(name, body, a, b, carries_mass=True):
        segs.append(links.Segment(name, body, np.asarray(a, dtype=float), np.asarray(b, dtype=float), rad[body],
                                  carries_mass))

    for i, (leg, w, qi) in enumerate(zip(legs, widths, q, strict=True), 1):
        h = 0.5 * float(w)
        e = leg.actuated_point(float(qi))
        j = p + leg.platform
        side = h * leg.normal
        base_pts.append(leg.base)
        plat_pts += [j - side, j + side] if h > 0.0 else [j]
        if leg.type.code == _k.R_PA:
            seg(f"upper_arm{i}", f"upper_arm{i}", leg.base, e)
            if h > 0.0:
                # the parallelogram's short end link at the elbow: massless (its mass model, docs/cycles.md)
                seg(f"elbow{i}", f"upper_arm{i}", e - side, e + side, carries_mass=False)
            pairs += [("base", f"upper_arm{i}"), (f"upper_arm{i}", f"forearm{i}")]
        else:
            lo, hi = leg.limits
            seg(f"rail{i}", f"rail{i}", leg.base + lo * leg.u, leg.base + hi * leg.u)
            seg(f"carriage{i}", f"carriage{i}", e - side, e + side)
            pairs += [("base", f"rail{i}"), (f"rail{i}", f"carriage{i}"), (f"carriage{i}", f"forearm{i}"),
                      (f"rail{i}", f"forearm{i}")]
        if h > 0.0:
            seg(f"forearm{i}a", f"forearm{i}", e + side, j + side)
            seg(f"forearm{i}b", f"forearm{i}", e - side, j - side)
        else:
            seg(f"forearm{i}", f"forearm{i}", e, j)
        pairs.append((f"forearm{i}", "platform"))
    for k, (a, b) in enumerate(_ring(base_pts, np.mean(base_pts, axis=0)), 1):
        seg(f"base{k}", "base", a, b)
    for k, (a, b) in enumerate(_ring(plat_pts, p), 1):
        seg(f"platform{k}", "platform", a, b)
    order = {b: n for n, b in enumerate(body_names([leg.type.code for leg in legs]))}
    segs.sort(key=lambda s: order[s.body])  # stable: a body's segments stay in the order written
    return links.LinkGeometry(tuple(segs), links.adjacency(pairs))


def link_geometry6(legs, rad: Mapping[str, float], pose, rot: np.ndarray, q) -> links.LinkGeometry:
    """Capsules and adjacency of a 6-DOF mechanism (module docstring) at platform centre ``pose`` and orientation
    ``rot`` (3 x 3) with joint values ``q``; ``legs``: sixdof.Leg6 of the resolved design."""
    p = np.asarray(pose, dtype=float)
    segs: list[links.Segment] = []
    pairs: list[tuple[str, str]] = []
    base_pts, plat_pts = [], []
    for i, (leg, qi) in enumerate(zip(legs, q, strict=True), 1):
        jq = p + rot @ leg.r
        base_pts.append(leg.base)
        plat_pts.append(jq)
        if leg.rus:
            e = leg.actuated_point(float(qi))
            segs += [links.Segment(f"upper_arm{i}", f"upper_arm{i}", leg.base.copy(), e, rad[f"upper_arm{i}"]),
                     links.Segment(f"rod{i}", f"rod{i}", e.copy(), jq, rad[f"rod{i}"])]
            pairs += [("base", f"upper_arm{i}"), (f"upper_arm{i}", f"rod{i}"), (f"rod{i}", "platform")]
        else:
            segs.append(links.Segment(f"leg{i}", f"leg{i}", leg.base.copy(), jq, rad[f"leg{i}"]))
            pairs += [("base", f"leg{i}"), (f"leg{i}", "platform")]
    ring = [links.Segment(f"base{k}", "base", a, b, rad["base"])
            for k, (a, b) in enumerate(_ring(base_pts, np.mean(base_pts, axis=0)), 1)]
    ring_p = [links.Segment(f"platform{k}", "platform", a, b, rad["platform"])
              for k, (a, b) in enumerate(_ring(plat_pts, p), 1)]
    return links.LinkGeometry(tuple(ring + segs + ring_p), links.adjacency(pairs))


def link_endpoints(legs, widths: Sequence[float], poses: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Vectorised twin of link_geometry's segment endpoints at platform centres ``poses`` (m, 3) with joint values
    ``q`` (m, n_legs): links.SegmentPoints, segments in link_geometry's order. The platform
    polygon's order is the angular order of the joints' offsets Q_i +- h n_i - P (pose-independent)."""
    p = np.asarray(poses, dtype=float)
    q = np.asarray(q, dtype=float)
    segs: list[tuple[str, Any, Any]] = []  # (body, a, b)
    base_pts, plat_offsets = [], []
    for i, (leg, w) in enumerate(zip(legs, widths, strict=True), 1):
        h = 0.5 * float(w)
        qi = q[:, i - 1]
        if leg.type.code == _k.R_PA:
            e = leg.base + leg.arm * (np.cos(qi)[:, None] * leg.u + np.sin(qi)[:, None] * leg.w)
        else:
            e = leg.base + qi[:, None] * leg.u
        j = p + leg.platform
        side = h * leg.normal
        # each joint point one object (links.segment_points takes its derivatives once)
        e_lo, e_hi, j_lo, j_hi = (e - side, e + side, j - side, j + side) if h > 0.0 else (e, e, j, j)
        base_pts.append(leg.base)
        plat_offsets += [(leg.platform - side, j_lo), (leg.platform + side, j_hi)] if h > 0.0 else [(leg.platform, j)]
        if leg.type.code == _k.R_PA:
            segs.append((f"upper_arm{i}", leg.base, e))
            if h > 0.0:
                segs.append((f"upper_arm{i}", e_lo, e_hi))
        else:
            lo, hi = leg.limits
            segs.append((f"rail{i}", leg.base + lo * leg.u, leg.base + hi * leg.u))
            segs.append((f"carriage{i}", e_lo, e_hi))
        if h > 0.0:
            segs += [(f"forearm{i}", e_hi, j_hi), (f"forearm{i}", e_lo, j_lo)]
        else:
            segs.append((f"forearm{i}", e, j))
    segs += [("base", a, b) for a, b in _ring(base_pts, np.mean(base_pts, axis=0))]
    # the platform polygon in the angular order of the offsets; the ring's points are the offsets' joint points
    offsets = [off for off, _ in plat_offsets]
    joint_of = {id(off): pt for off, pt in plat_offsets}
    for a, b in _ring_unsorted_ids(offsets):
        segs.append(("platform", joint_of[id(a)], joint_of[id(b)]))
    order = {b: n for n, b in enumerate(body_names([leg.type.code for leg in legs]))}
    segs.sort(key=lambda s: order[s[0]])
    return links.segment_points([(a, b) for _, a, b in segs], len(p))


def _ring_unsorted_ids(offsets) -> list[tuple[np.ndarray, np.ndarray]]:
    """_ring's sides about the origin, keeping the given array objects (so that each can be looked up by id)."""
    pts = sorted(offsets, key=lambda v: math.atan2(v[1], v[0]))
    if len(pts) == 1:
        return [(pts[0], pts[0])]
    if len(pts) == 2:
        return [(pts[0], pts[1])]
    return [(pts[k], pts[(k + 1) % len(pts)]) for k in range(len(pts))]


def _ring(points, centre) -> list[tuple[np.ndarray, np.ndarray]]:
    """Sides of the closed polygon through ``points`` in angular order about ``centre`` (xy-plane angle); one point
    gives one ball, two points one side."""
    pts = [np.asarray(v, dtype=float) for v in points]
    if len(pts) == 1:
        return [(pts[0], pts[0])]
    pts.sort(key=lambda v: math.atan2(v[1] - centre[1], v[0] - centre[0]))
    if len(pts) == 2:
        return [(pts[0], pts[1])]
    return [(pts[k], pts[(k + 1) % len(pts)]) for k in range(len(pts))]


def widths(plans, design: Mapping[str, float]) -> list[float]:
    """Each leg's parallelogram width (length unit) from its expression; InvalidParameter if negative."""
    out = []
    for i, plan in enumerate(plans, 1):
        w = 0.0 if plan.width is None else float(plan.width.value(design))
        if not (math.isfinite(w) and w >= 0.0):
            raise InvalidParameter(f"design: leg {i} width = {w:g}, must be >= 0")
        out.append(w)
    return out


# ----- the capsules as data for the field kernels' clearance (kernels.clearance.packed_capsule_gap) ---------------
# link_geometry's and link_geometry6's capsules with each end point written as a constant plus the moving point it
# rides on (kernels.clearance: fixed, the platform centre P, or leg i's elbow or carriage E_i), and the index pairs
# LinkGeometry.checked_pairs keeps (different bodies sharing no joint). tests/test_described_clearance.py holds the
# kernel's field equal to cycle.clearance of link_geometry at random poses and designs.
_FIXED, _PLATFORM = _kc.ANCHOR_FIXED, _kc.ANCHOR_PLATFORM


def capsules(legs, widths: Sequence[float], rad: Mapping[str, float]) -> tuple[list, np.ndarray]:
    """(capsules, pairs) of a 3T mechanism (link_geometry's bodies): capsules as (body, (anchor, c), (anchor, c),
    radius), pairs (m, 2) int64 of the checked ones."""
    out: list = []
    pairs: list[tuple[str, str]] = []
    base_pts, plat_offsets = [], []
    zero = np.zeros(3)
    for i, (leg, w) in enumerate(zip(legs, widths, strict=True), 1):
        h = 0.5 * float(w)
        side = h * leg.normal
        e = float(i - 1)
        base_pts.append(leg.base)
        plat_offsets += [leg.platform - side, leg.platform + side] if h > 0.0 else [leg.platform]
        if leg.type.code == _k.R_PA:
            out.append((f"upper_arm{i}", (_FIXED, leg.base), (e, zero)))
            if h > 0.0:
                out.append((f"upper_arm{i}", (e, -side), (e, side)))
            pairs += [("base", f"upper_arm{i}"), (f"upper_arm{i}", f"forearm{i}")]
        else:
            lo, hi = leg.limits
            out.append((f"rail{i}", (_FIXED, leg.base + lo * leg.u), (_FIXED, leg.base + hi * leg.u)))
            out.append((f"carriage{i}", (e, -side), (e, side)))
            pairs += [("base", f"rail{i}"), (f"rail{i}", f"carriage{i}"), (f"carriage{i}", f"forearm{i}"),
                      (f"rail{i}", f"forearm{i}")]
        if h > 0.0:
            out += [(f"forearm{i}", (e, side), (_PLATFORM, leg.platform + side)),
                    (f"forearm{i}", (e, -side), (_PLATFORM, leg.platform - side))]
        else:
            out.append((f"forearm{i}", (e, zero), (_PLATFORM, leg.platform)))
        pairs.append((f"forearm{i}", "platform"))
    out += [("base", (_FIXED, a), (_FIXED, b)) for a, b in _ring(base_pts, np.mean(base_pts, axis=0))]
    out += [("platform", (_PLATFORM, a), (_PLATFORM, b)) for a, b in _ring(plat_offsets, np.zeros(3))]
    return _with_radii(out, pairs, rad)


def capsules6(legs, rad: Mapping[str, float], rot: np.ndarray) -> tuple[list, np.ndarray]:
    """(capsules, pairs) of a 6-DOF mechanism (link_geometry6's bodies) at the platform orientation ``rot``."""
    out: list = []
    pairs: list[tuple[str, str]] = []
    base_pts, plat_offsets = [], []
    zero = np.zeros(3)
    for i, leg in enumerate(legs, 1):
        rho = rot @ leg.r
        base_pts.append(leg.base)
        plat_offsets.append(rho)
        if leg.rus:
            e = float(i - 1)
            out += [(f"upper_arm{i}", (_FIXED, leg.base), (e, zero)), (f"rod{i}", (e, zero), (_PLATFORM, rho))]
            pairs += [("base", f"upper_arm{i}"), (f"upper_arm{i}", f"rod{i}"), (f"rod{i}", "platform")]
        else:
            out.append((f"leg{i}", (_FIXED, leg.base), (_PLATFORM, rho)))
            pairs += [("base", f"leg{i}"), (f"leg{i}", "platform")]
    out += [("base", (_FIXED, a), (_FIXED, b)) for a, b in _ring(base_pts, np.mean(base_pts, axis=0))]
    out += [("platform", (_PLATFORM, a), (_PLATFORM, b)) for a, b in _ring(plat_offsets, np.zeros(3))]
    return _with_radii(out, pairs, rad)


def joints_coincide(legs) -> bool:
    """Whether the two legs of a 2T mechanism meet at one platform joint (Q1 = Q2 at every pose: equal offsets r_p,
    to 1e-12 of the mechanism's size, frame2's test): their links are then pinned together."""
    scale = max(1.0, *(float(np.abs(leg.base).max()) + leg.arm + leg.forearm for leg in legs))
    return bool(np.abs(legs[0].platform - legs[1].platform).max() <= 1e-12 * scale)


def capsules2(legs, rad: Mapping[str, float]) -> tuple[list, np.ndarray]:
    """(capsules, pairs) of a 2T (planar) mechanism: PlanarMechanism.link_geometry's bodies, in its order, in the
    plane z = 0: ``base`` B2 -> B1, per leg i ``arm<i>`` B -> E and ``forearm<i>`` E -> Q (RR), or ``rail<i>`` over
    the stroke, ``carriage<i>`` a ball at C and ``forearm<i>`` C -> Q (PR), ``platform`` Q1 -> Q2 (a ball at P + r_p
    where the joints coincide, and then the two forearms are adjacent: pinned together). ``legs``: planar.PlanarLeg."""
    def v3(a):
        return np.array([float(a[0]), float(a[1]), 0.0])

    out: list = [("base", (_FIXED, v3(legs[1].base)), (_FIXED, v3(legs[0].base)))]
    pairs: list[tuple[str, str]] = []
    zero = np.zeros(3)
    for i, leg in enumerate(legs, 1):
        e = float(i - 1)
        if leg.rotary:
            out.append((f"arm{i}", (_FIXED, v3(leg.base)), (e, zero)))
            pairs += [("base", f"arm{i}"), (f"arm{i}", f"forearm{i}")]
        else:
            lo, hi = leg.limits
            out.append((f"rail{i}", (_FIXED, v3(leg.base + lo * leg.u)), (_FIXED, v3(leg.base + hi * leg.u))))
            out.append((f"carriage{i}", (e, zero), (e, zero)))
            pairs += [("base", f"rail{i}"), (f"rail{i}", f"carriage{i}"), (f"carriage{i}", f"forearm{i}"),
                      (f"rail{i}", f"forearm{i}")]
        out.append((f"forearm{i}", (e, zero), (_PLATFORM, v3(leg.platform))))
        pairs.append((f"forearm{i}", "platform"))
    if joints_coincide(legs):
        pairs.append(("forearm1", "forearm2"))
    out.append(("platform", (_PLATFORM, v3(legs[0].platform)), (_PLATFORM, v3(legs[1].platform))))
    return _with_radii(out, pairs, rad)


def _with_radii(caps: list, pairs: list[tuple[str, str]], rad: Mapping[str, float]) -> tuple[list, np.ndarray]:
    return ([(body, a, b, rad[body]) for body, a, b in caps],
            links.kernel_pairs([body for body, *_ in caps], links.adjacency(pairs)))


def pack_capsules(p: np.ndarray, off: int, caps: list, pairs: np.ndarray) -> None:
    """Write the block kernels.clearance.packed_capsule_gap reads at p[off:] (p must have room: capsule_slots)."""
    stride = _kc.SEG_STRIDE
    p[off], p[off + 1] = len(caps), len(pairs)
    k = off + 2
    for _, (a0, c0), (a1, c1), radius in caps:
        p[k], p[k + 1 : k + 4] = a0, c0
        p[k + 4], p[k + 5 : k + 8] = a1, c1
        p[k + 8] = radius
        k += stride
    p[k : k + 2 * len(pairs)] = np.asarray(pairs, dtype=float).ravel()


def capsule_slots(max_capsules: int) -> int:
    """Slots of a capsule block with at most ``max_capsules`` capsules and every pair of them."""
    return 2 + max_capsules * _kc.SEG_STRIDE + max_capsules * (max_capsules - 1)


def uniform_legs(caps: list, widths: Sequence[float] = ()) -> bool:
    """Whether every leg's bodies have the radii of the other legs' bodies of their group and the legs have one
    width: then a map of the legs onto themselves (a rotation, a mirror) maps the capsules onto themselves too, and
    the clearance field keeps the legs' symmetry (describe/symmetry.py)."""
    by_group: dict[str, set[float]] = {}
    for body, _, _, radius in caps:
        if body not in ("base", "platform"):
            by_group.setdefault(group_of(body), set()).add(radius)
    return all(len(v) == 1 for v in by_group.values()) and len(set(map(float, widths))) <= 1
