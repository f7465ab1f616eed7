"""Mobility of a parallel mechanism: the Grübler-Kutzbach count from its joint list and a screw-theory check.

Two independent answers to "how many degrees of freedom, and which motions?":

* **Counting** (:func:`grubler`, :func:`modified_grubler`) from a :class:`Topology`: n links (base and
  platform included), g joints with freedoms f_i.
  - classical G-K: ``M = d (n - g - 1) + sum f`` with d = 6 in space, 3 for a planar mechanism;
  - modified G-K (Huang's form): ``M = (d - lambda)(n - g - 1) + sum f + nu - zeta`` with lambda the common
    constraints (shared by every chain), nu the redundant (over-) constraints among the chains and zeta the
    passive (idle) freedoms. The topology carries the values the papers (or the spec) use, and says so.
* **Screw theory** (:func:`screw_analysis`, :func:`screw_mobility`) from the joint screws at one
  configuration: each chain's constraint wrenches span the reciprocal of its joint twists; the platform's
  twists span the reciprocal of all the chains' wrenches together; dof = its dimension, the number of
  rotations = the rank of the angular parts, the rest are translations. The numeric lambda and nu come out as
  by-products: lambda = dim of the wrenches common to all chains (= 6 - rank of all joint screws together) and
  nu = sum_i c_i - rank(W) - (k - 1) lambda for k chains with c_i constraints each (Huang's nu for a
  mechanism whose only loops are the ones between its chains; a chain with an inner loop enters through its
  resultant twists, see :func:`body_twists`).

:func:`mobility_report` ties both to a registered mechanism: it samples K random reachable configurations
(points of the bounding box accepted by the point kernel, joint values from the inverse kinematics in the
kernel's branch) and reports the range of the constraint rank, its generic (most frequent) value and the
motion type. A mechanism takes part by defining ``topology(design, options) -> Topology`` and
``joint_screws(design, options, pose, q) -> [[6-vector, ...] per chain]`` (fixed frame).

Screws are 6-vectors (direction; moment). A twist (omega; v): a revolute joint on the line through r with
direction omega is (omega; r x omega), a prismatic joint (or a parallelogram, a circular translation) along v
is (0; v). A wrench (f; m) is reciprocal to a twist (omega; v) when omega . m + v . f = 0. Numerical ranks
are taken in a working frame centred on the joint axes with moments divided by the mechanism's size
(:class:`_Frame`), so one relative tolerance fits millimetres and metres, near the origin or far from it.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from scalesynth.errors import InvalidParameter, InvalidPose, ScalesynthError

# freedoms of each joint type; "Pa" is a parallelogram counted as one joint (a 1-DOF circular translation)
FREEDOM = {"R": 1, "P": 1, "U": 2, "S": 3, "Pa": 1}
_AXES = {"R": 1, "P": 1, "Pa": 1, "U": 2, "S": 3}
# relative tolerance of numerical ranks (singular values of unit, length-normalised screws)
RTOL = 1e-8


class NoTopology(ScalesynthError):
    """The mechanism declares no joint topology or joint screws, so its mobility cannot be analysed."""


# ----- joints and topologies ----------------------------------------------------------------------------
@dataclass(frozen=True)
class Joint:
    """A joint and, for the numeric check, its geometry at one configuration (fixed frame).

    kind: 'R', 'P', 'U', 'S' or 'Pa'. point: a point on the axes (R, U; the centre of S), unused for P and Pa.
    axes: R one direction, U two (in the order of the chain), S three (default x, y, z: any three independent
    directions give the same twists), P the sliding direction, Pa the velocity direction of the
    parallelogram's moving link.
    """

    kind: str
    point: tuple[float, ...] | None = None
    axes: tuple[tuple[float, ...], ...] = ()

    def __post_init__(self):
        if self.kind not in FREEDOM:
            raise InvalidParameter(f"joint.kind: expected one of {', '.join(FREEDOM)}, got {self.kind!r}")
        axes = tuple(_vector3("joint.axes", a) for a in self.axes)
        if self.kind == "S" and not axes:
            axes = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))
        if len(axes) != _AXES[self.kind]:
            wanted = _AXES[self.kind]
            raise InvalidParameter(f"joint.axes: a {self.kind} joint needs {wanted} axes, got {len(axes)}")
        point = None
        if self.kind in ("R", "U", "S"):
            if self.point is None:
                raise InvalidParameter(f"joint.point: a {self.kind} joint needs a point on its axes")
            point = _vector3("joint.point", self.point)
        object.__setattr__(self, "axes", axes)
        object.__setattr__(self, "point", point)

    @property
    def freedom(self) -> int:
        return FREEDOM[self.kind]

    def screws(self) -> list[np.ndarray]:
        """Unit joint screws (omega; v): R = (w; r x w), P and Pa = (0; v), U = two R, S = three R."""
        out = []
        for axis in self.axes:
            a = np.asarray(axis)
            norm = float(np.linalg.norm(a))
            if not norm > 0.0:
                raise InvalidPose(f"joint.axes: a {self.kind} joint has a zero axis")
            a = a / norm
            if self.kind in ("P", "Pa"):
                out.append(np.concatenate([np.zeros(3), a]))
            else:
                out.append(np.concatenate([a, np.cross(np.asarray(self.point), a)]))
        return out


def _vector3(name: str, value) -> tuple[float, float, float]:
    arr = np.asarray(value, dtype=float)
    if arr.shape != (3,) or not np.all(np.isfinite(arr)):
        raise InvalidPose(f"{name}: expected 3 finite numbers, got {value!r}")
    return float(arr[0]), float(arr[1]), float(arr[2])


def chain_screws(joints: Sequence[Joint]) -> list[np.ndarray]:
    """All unit screws of a serial chain's joints, in order."""
    return [s for j in joints for s in j.screws()]


@dataclass(frozen=True)
class Topology:
    """Links and joints of a parallel mechanism for the G-K counts.

    n_links counts every rigid body, base and platform included (a parallelogram counted as one joint adds
    only its moving link). chains: (label, joint kinds) per chain between base and platform; a chain with an
    inner loop lists all its joints (their links go into n_links). order: 6 for a spatial mechanism, 3 for a
    planar one. common (lambda, beyond the plane's 3 for a planar mechanism), redundant (nu) and passive
    (zeta): the terms of the modified count; note: where they come from and how the paper counts.
    """

    n_links: int
    chains: tuple[tuple[str, tuple[str, ...]], ...]
    order: int = 6
    common: int = 0
    redundant: int = 0
    passive: int = 0
    note: str = ""

    def __post_init__(self):
        if self.order not in (3, 6):
            raise InvalidParameter(f"topology.order: 6 (spatial) or 3 (planar), got {self.order!r}")
        if self.n_links < 2:
            raise InvalidParameter(f"topology.n_links: base and platform at least, got {self.n_links}")
        if not self.chains:
            raise InvalidParameter("topology.chains: at least one chain")
        for label, kinds in self.chains:
            for kind in kinds:
                if kind not in FREEDOM:
                    raise InvalidParameter(f"topology.chains: {label} has an unknown joint type {kind!r}")

    @property
    def joints(self) -> tuple[str, ...]:
        return tuple(k for _, kinds in self.chains for k in kinds)

    @property
    def n_joints(self) -> int:
        return len(self.joints)

    @property
    def sum_freedom(self) -> int:
        return sum(FREEDOM[k] for k in self.joints)

    @property
    def parallelograms(self) -> int:
        return sum(1 for k in self.joints if k == "Pa")

    def expanded(self) -> Topology:
        """The same mechanism with every parallelogram drawn as its four revolutes (two more links each).

        In space each planar 4R loop is overconstrained by 3, so the classical count drops by 3 per
        parallelogram and nu grows by 3 (the modified count is unchanged); in the plane nothing changes."""
        chains = tuple(
            (label, tuple(j for k in kinds for j in (("R",) * 4 if k == "Pa" else (k,))))
            for label, kinds in self.chains
        )
        extra = 3 * self.parallelograms if self.order == 6 else 0
        return Topology(
            self.n_links + 2 * self.parallelograms, chains, self.order, self.common, self.redundant + extra,
            self.passive, self.note,
        )


def grubler(top: Topology) -> int:
    """Classical Grübler-Kutzbach count d (n - g - 1) + sum f, d = top.order (6 spatial, 3 planar)."""
    return top.order * (top.n_links - top.n_joints - 1) + top.sum_freedom


def modified_grubler(top: Topology) -> int:
    """Modified count (d - lambda)(n - g - 1) + sum f + nu - zeta with the topology's lambda, nu and zeta."""
    d = top.order - top.common
    return d * (top.n_links - top.n_joints - 1) + top.sum_freedom + top.redundant - top.passive


# ----- screw algebra -------------------------------------------------------------------------------------
_SWAP = np.block([[np.zeros((3, 3)), np.eye(3)], [np.eye(3), np.zeros((3, 3))]])  # reciprocal product matrix


def _stack(screws) -> np.ndarray:
    arr = np.asarray(screws, dtype=float).reshape(-1, 6)
    if not np.all(np.isfinite(arr)):
        raise InvalidPose("joint screws: non-finite entries")
    return arr


@dataclass(frozen=True)
class _Frame:
    """A working frame for numerical ranks: origin c at the point nearest to all the screw axes (least
    squares) and moments divided by L, the largest distance of an axis from c. Screws there describe the same
    mechanism moved and scaled by 1/L, so reciprocity, ranks and angular parts are unchanged while every entry
    is O(1). Moment ratios below 1e-9 count as zero (L = 1: all axes through c)."""

    centre: np.ndarray
    length: float

    @classmethod
    def of(cls, stacks: Sequence[np.ndarray]) -> _Frame:
        every = np.vstack(stacks) if stacks else np.zeros((0, 6))
        w2 = np.einsum("ij,ij->i", every[:, :3], every[:, :3])
        rot = w2 > 0.0
        centre = np.zeros(3)
        if np.any(rot):
            # the point nearest to all the axes (least squares): sum_k (I - u_k u_k^T)(c - foot_k) = 0
            units = every[rot, :3] / np.sqrt(w2[rot, None])
            feet = np.cross(every[rot, :3], every[rot, 3:]) / w2[rot, None]  # w x m / |w|^2 for m = r x w
            proj = np.eye(3)[None] - units[:, :, None] * units[:, None, :]
            centre = np.linalg.lstsq(proj.sum(axis=0), np.einsum("kij,kj->i", proj, feet), rcond=1e-10)[0]
        moved = every[rot, 3:] - np.cross(centre, every[rot, :3])
        length = float(np.max(np.linalg.norm(moved, axis=1) / np.sqrt(w2[rot]), initial=0.0))
        return cls(centre, length if length > 1e-9 * max(1.0, float(np.linalg.norm(centre))) else 1.0)

    def into(self, rows: np.ndarray) -> np.ndarray:
        """Screws (rows) in the working frame, each scaled to unit norm."""
        moved = (rows[:, 3:] - np.cross(self.centre, rows[:, :3])) / self.length
        out = np.hstack([rows[:, :3], moved])
        norms = np.linalg.norm(out, axis=1)
        if np.any(norms == 0.0):
            raise InvalidPose("joint screws: a zero screw")
        return out / norms[:, None]

    def back(self, rows: np.ndarray) -> np.ndarray:
        """Screws (rows) from the working frame back to the original one."""
        rows = np.atleast_2d(rows)
        return np.hstack([rows[:, :3], rows[:, 3:] * self.length + np.cross(self.centre, rows[:, :3])])


def _rank_and_null(rows: np.ndarray, rtol: float) -> tuple[int, np.ndarray]:
    """Numerical rank of a (k, 6) matrix of unit rows (singular values above rtol times the largest, at
    least 1) and an orthonormal basis (rows) of its null space."""
    if rows.shape[0] == 0:
        return 0, np.eye(6)
    _, sv, vt = np.linalg.svd(rows)
    r = int(np.sum(sv > rtol * max(1.0, sv[0])))
    return r, vt[r:]


def _reciprocal_unit(rows: np.ndarray, rtol: float) -> np.ndarray:
    """Orthonormal basis (rows) of the screws reciprocal to the given (already scaled) screws."""
    return _rank_and_null(rows @ _SWAP, rtol)[1]


def reciprocal(screws, rtol: float = RTOL) -> np.ndarray:
    """Basis (rows) of the screws reciprocal to all given screws (x with s^T Delta x = 0 for every s, where
    Delta = [[0, I], [I, 0]]), in the given units: twists in, wrenches out, and the other way round."""
    stack = _stack(screws)
    frame = _Frame.of([stack])
    return frame.back(_reciprocal_unit(frame.into(stack), rtol))


def rank(screws, rtol: float = RTOL) -> int:
    """Numerical rank of a set of screws (the dimension of their span)."""
    stack = _stack(screws)
    return _rank_and_null(_Frame.of([stack]).into(stack), rtol)[0]


def motion_name(rotations: int, translations: int) -> str:
    """The papers' names: '3T' and '2T' without rotations, '3R' without translations, rotations first when
    they outnumber the translations ('2R1T'), translations first otherwise ('3T3R', '3T1R', '2T1R'); '0' for
    a rigid structure."""
    if rotations == 0 and translations == 0:
        return "0"
    if rotations == 0:
        return f"{translations}T"
    if translations == 0:
        return f"{rotations}R"
    if rotations > translations:
        return f"{rotations}R{translations}T"
    return f"{translations}T{rotations}R"


@dataclass(frozen=True)
class ScrewResult:
    """Screw-theory mobility at one configuration.

    dof: dimension of the platform twist space; rotations: rank of its angular parts; motion: e.g. '2R1T';
    chain_ranks / chain_constraints: per chain, the rank of its joint twists and 6 minus that;
    constraint_rank: rank of all the chains' wrenches together (dof = 6 - constraint_rank); common (lambda)
    and redundant (nu) as in the module docstring; twists / wrenches: bases (rows) of the platform twists and
    of the constraint wrenches, in the units of the joint screws.
    """

    dof: int
    rotations: int
    motion: str
    chain_ranks: tuple[int, ...]
    chain_constraints: tuple[int, ...]
    constraint_rank: int
    common: int
    redundant: int
    twists: np.ndarray = field(repr=False)
    wrenches: np.ndarray = field(repr=False)

    @property
    def translations(self) -> int:
        return self.dof - self.rotations


def screw_analysis(chains: Sequence[Sequence[np.ndarray]], rtol: float = RTOL) -> ScrewResult:
    """Platform mobility from each chain's joint screws (lists of 6-vectors (omega; v) in one frame)."""
    if not chains:
        raise InvalidParameter("chains: at least one chain of joint screws is needed")
    stacks = [_stack(c) for c in chains]
    frame = _Frame.of(stacks)
    unit = [frame.into(s) for s in stacks]
    ranks, counts, wrench_rows = [], [], []
    for s in unit:
        ranks.append(_rank_and_null(s, rtol)[0])
        w = _reciprocal_unit(s, rtol)
        counts.append(w.shape[0])
        wrench_rows.append(w)
    wrenches = np.vstack(wrench_rows)
    constraint_rank, _ = _rank_and_null(wrenches, rtol)
    twists = _reciprocal_unit(wrenches, rtol) if wrenches.shape[0] else np.eye(6)
    dof = twists.shape[0]
    rotations = _rank_and_null(twists[:, :3], rtol)[0] if dof else 0
    # a wrench common to every chain is reciprocal to every joint screw of the mechanism
    common = 6 - _rank_and_null(np.vstack(unit), rtol)[0]
    redundant = sum(counts) - constraint_rank - (len(unit) - 1) * common
    wrench_basis = np.linalg.svd(wrenches)[2][:constraint_rank] if constraint_rank else np.zeros((0, 6))
    return ScrewResult(
        dof=dof,
        rotations=rotations,
        motion=motion_name(rotations, dof - rotations),
        chain_ranks=tuple(ranks),
        chain_constraints=tuple(counts),
        constraint_rank=constraint_rank,
        common=common,
        redundant=redundant,
        twists=frame.back(twists),
        wrenches=frame.back(wrench_basis),
    )


def screw_mobility(chains: Sequence[Sequence[np.ndarray]], rtol: float = RTOL) -> tuple[int, str]:
    """(dof, motion type) of the platform carried by the chains, e.g. (3, '2R1T')."""
    res = screw_analysis(chains, rtol)
    return res.dof, res.motion


def body_twists(*subchains: Sequence[np.ndarray], rtol: float = RTOL) -> list[np.ndarray]:
    """Twist basis of a body carried by several serial subchains in parallel (an inner loop of a hybrid
    chain): the twists in every subchain's span, in the given units. A hybrid chain then enters
    :func:`screw_analysis` as these resultant twists followed by the joints after the loop."""
    if not subchains:
        raise InvalidParameter("subchains: at least one serial subchain is needed")
    raw = [_stack(s) for s in subchains]
    frame = _Frame.of(raw)
    stacks = [frame.into(s) for s in raw]
    first = stacks[0].T
    # t in every span: t = T_1 a_1 = T_k a_k (k >= 2), a null space of [T_1, -T_2, 0, ...; T_1, 0, -T_3, ...]
    others = stacks[1:]
    blocks = [
        np.hstack([first] + [-s.T if j == k else np.zeros_like(s.T) for j, s in enumerate(others)])
        for k in range(len(others))
    ]
    if blocks:
        system = np.vstack(blocks)
        _, sv, vt = np.linalg.svd(system)
        coeffs = vt[int(np.sum(sv > rtol * max(1.0, float(sv[0])))) :, : first.shape[1]]
        images = coeffs @ first.T
    else:
        images = stacks[0]
    if images.shape[0] == 0:
        return []
    _, sv, vt = np.linalg.svd(images, full_matrices=False)
    basis = vt[: int(np.sum(sv > rtol * max(1.0, float(sv[0]))))]
    return list(frame.back(basis))


# ----- a registered mechanism ----------------------------------------------------------------------------
def _capable(mech) -> None:
    if not callable(getattr(mech, "topology", None)) or not callable(getattr(mech, "joint_screws", None)):
        raise NoTopology(
            f"mechanism: {mech.name} declares no joint topology (methods topology and joint_screws), so its "
            "mobility cannot be analysed"
        )


def sample_configurations(mech, design, options, count: int, seed: int = 0, max_draws: int | None = None):
    """``count`` random feasible configurations [(pose, q)]: points drawn uniformly in the bounding box, kept
    where the point kernel accepts them (reachable within every limit), with the joint values of the kernel's
    IK branch. Deterministic for a given seed. Raises InvalidPose when ``max_draws`` points (default 2000 per
    configuration) give too few."""
    if isinstance(count, bool) or not isinstance(count, (int, np.integer)) or count < 1:
        raise InvalidParameter(f"samples: expected an integer >= 1, got {count!r}")
    lo, hi = (np.asarray(v, dtype=float) for v in mech.bounding_box(design, options))
    packed = mech.pack(design, options)
    kernel = mech.point_kernel
    branch = mech.kernel_branch(options)
    dims = len(mech.task_axes)
    rng = np.random.default_rng(seed)
    limit = 2000 * count if max_draws is None else max_draws
    found, draws = [], 0
    while len(found) < count and draws < limit:
        batch = rng.uniform(lo, hi, size=(min(256, limit - draws), 3))
        draws += batch.shape[0]
        for point in batch:
            if not kernel(packed, point[0], point[1], point[2]) >= 0.0:
                continue
            pose = point[:dims].copy()
            sols = {s.label: s.values for s in mech.inverse_kinematics(design, options, pose)}
            if branch in sols:
                found.append((pose, np.asarray(sols[branch], dtype=float)))
                if len(found) == count:
                    break
    if len(found) < count:
        raise InvalidPose(
            f"samples: found only {len(found)} of {count} feasible configurations of {mech.name} in {draws} "
            "random points of its bounding box (empty or tiny workspace?)"
        )
    return found


@dataclass(frozen=True)
class MobilityReport:
    """Counts and screw-theory results of one mechanism design (see :func:`mobility_report`)."""

    mechanism: str
    expected_motion: str
    topology: Topology
    classical: int
    modified: int
    results: tuple[ScrewResult, ...]

    @property
    def generic(self) -> ScrewResult:
        """A result at the most frequent constraint rank (ties: the higher rank, i.e. the lower dof)."""
        counts = Counter(r.constraint_rank for r in self.results)
        best = max(counts.items(), key=lambda kv: (kv[1], kv[0]))[0]
        return next(r for r in self.results if r.constraint_rank == best)

    @property
    def common_in_plane_terms(self) -> int:
        """The numeric lambda in the topology's terms (without a planar mechanism's 3 common constraints)."""
        return self.generic.common - (6 - self.topology.order)

    @property
    def agrees(self) -> bool:
        """Counting, screw theory and the mechanism's declared motion all give the same answer."""
        g = self.generic
        top = self.topology
        return (
            self.modified == g.dof
            and g.motion == self.expected_motion
            and self.common_in_plane_terms == top.common
            and g.redundant == top.redundant
        )

    def uses(self) -> str:
        """Which terms the modified count uses, in words."""
        top = self.topology
        words = []
        if top.order == 3:
            words.append("planar: d = 3 (in space: lambda = 3 common constraints)")
        if top.common:
            words.append(f"lambda = {top.common} common constraints")
        if top.redundant:
            words.append(f"nu = {top.redundant} redundant constraints")
        if top.passive:
            words.append(f"zeta = {top.passive} passive freedoms")
        return "; ".join(words) or "none (equal to the classical count)"

    def to_dict(self) -> dict[str, Any]:
        top = self.topology
        g = self.generic
        ranks = [r.constraint_rank for r in self.results]
        dofs = [r.dof for r in self.results]
        out: dict[str, Any] = {
            "mechanism": self.mechanism,
            "expected_motion": self.expected_motion,
            "topology": {
                "n_links": top.n_links,
                "n_joints": top.n_joints,
                "sum_freedom": top.sum_freedom,
                "order": top.order,
                "chains": {label: list(kinds) for label, kinds in top.chains},
            },
            "grubler": {
                "classical": self.classical,
                "classical_formula": f"{top.order}(n - g - 1) + sum f",
                "modified": self.modified,
                "modified_formula": f"({top.order} - lambda)(n - g - 1) + sum f + nu - zeta",
                "lambda": top.common,
                "nu": top.redundant,
                "zeta": top.passive,
                "uses": self.uses(),
                "note": top.note,
            },
            "numeric": {
                "samples": len(self.results),
                "constraint_rank": {"generic": g.constraint_rank, "min": min(ranks), "max": max(ranks)},
                "dof": {"generic": g.dof, "min": min(dofs), "max": max(dofs)},
                "motion": g.motion,
                "motions_seen": sorted({r.motion for r in self.results}),
                "chain_constraints": list(g.chain_constraints),
                "lambda": self.common_in_plane_terms,
                "lambda_in_space": g.common,
                "nu": g.redundant,
            },
            "agrees": self.agrees,
        }
        if top.parallelograms:
            ex = top.expanded()
            out["grubler"]["parallelograms_expanded"] = {
                "n_links": ex.n_links,
                "n_joints": ex.n_joints,
                "sum_freedom": ex.sum_freedom,
                "classical": grubler(ex),
                "nu": ex.redundant,
                "modified": modified_grubler(ex),
            }
        return out


def mobility_report(mech, design, options, samples: int = 20, seed: int = 0) -> MobilityReport:
    """G-K counts of ``mech.topology`` and the screw analysis at ``samples`` random feasible configurations
    (raises NoTopology for a mechanism without ``topology`` and ``joint_screws``)."""
    _capable(mech)
    top = mech.topology(design, options)
    results = []
    for pose, q in sample_configurations(mech, design, options, samples, seed):
        chains = mech.joint_screws(design, options, pose, q)
        if len(chains) != len(top.chains):
            raise InvalidParameter(
                f"joint_screws: {mech.name} gave {len(chains)} chains, its topology lists {len(top.chains)}"
            )
        results.append(screw_analysis(chains))
    return MobilityReport(
        mechanism=mech.name,
        expected_motion=mech.motion,
        topology=top,
        classical=grubler(top),
        modified=modified_grubler(top),
        results=tuple(results),
    )
