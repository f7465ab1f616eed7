"""The Mechanism interface: what every registered mechanism provides.

A mechanism is a small object describing one parallel-mechanism type: its design parameters, its options
(working mode, joint limits, ...), the local fields its Numba *field kernel* computes per voxel, its design-level
metrics, and plain NumPy kinematics (IK with all branches, FK with all assembly modes, Jacobian, singularity
type) for the CLI and tests.

Field-kernel contract (Numba ``@njit``, details in ``scalesynth.kernels.grid``): ``kernel(p, x, y, z, out)``,
where ``p`` is the float64 array returned by :meth:`Mechanism.pack` and ``out`` has one slot per entry of
``Mechanism.fields`` (in that order): ``out[0]`` the LCI in [0, 1] of the pose if it is reachable under every
limit, else ``-1.0``; ``out[1]``, ``out[2]`` sigma_min and sigma_max of the homogenised Jacobian dx/dq; then the
mechanism's own fields. Planar mechanisms ignore ``z``. The kernel must never write NaN. ``point_kernel`` is the
derived scalar LCI kernel ``f(p, x, y, z) -> LCI or -1``.
"""

from __future__ import annotations

import functools
import math
import sys
from abc import ABC, abstractmethod
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

from scalesynth.declarations import MAX_MAGNITUDE, Option, Parameter  # noqa: F401 - the mechanisms' vocabulary
from scalesynth.errors import InvalidParameter, InvalidPose
from scalesynth.names import hint

if TYPE_CHECKING:
    from scalesynth.evaluation.plans import ColumnPlan, UniformPlan


@dataclass(frozen=True)
class Field:
    """A local field the field kernel writes per voxel (its slot = its index in ``Mechanism.fields``).

    ``unit`` may contain ``{length}`` (the config's length unit); '1' = dimensionless. ``better`` is the sense an
    engineer prefers ('max' or 'min'); ``range`` the values it can take. ``needs_options``: options that must be
    set (not null, not false) for the field to mean something (e.g. a material constant the kernel reads from
    ``pack``, or a flag that switches the field on); without them the kernel writes no meaningful value.
    """

    name: str
    unit: str
    description: str
    better: str = "max"
    range: tuple[float, float] = (0.0, math.inf)
    needs_options: tuple[str, ...] = ()

    def enabled(self, options: Mapping[str, Any]) -> bool:
        """Whether ``options`` (resolved) set every option the field needs."""
        return all(option_set(options, o) for o in self.needs_options)


def option_set(options: Mapping[str, Any], name: str) -> bool:
    """Whether option ``name`` is set for a field's ``needs_options``: not null and not false (a flag that is off)."""
    value = options.get(name)
    return value is not None and value is not False


def base_fields(sigma_unit: str, jacobian: str) -> tuple[Field, Field, Field]:
    """The three fields every mechanism provides, in slots 0, 1, 2. ``jacobian`` says which homogenised dx/dq
    the singular values belong to (its units), for the catalogue's descriptions."""
    return (
        Field("lci", "1", "local conditioning index 1/kappa_2 of the Jacobian", "max", (0.0, 1.0)),
        Field("sigma_min", sigma_unit, f"smallest singular value of {jacobian}: worst-direction velocity "
              "amplification (force amplification is its inverse)", "max"),
        Field("sigma_max", sigma_unit, f"largest singular value of {jacobian}: largest output motion per unit "
              "input (kinematic resolution = sigma_max x actuator resolution)", "min"),
    )


@dataclass(frozen=True)
class DesignMetric:
    """A design-level metric computed from the resolved design and options alone (no grid): ``value(design,
    options) -> float``. ``unit`` as in Field. The hypervolume reference (worst value) of a minimised design metric
    is its value at the upper corner of the optimisation bounds, so ``value`` must not decrease in any parameter.
    """

    name: str
    unit: str
    description: str
    value: Any  # Callable[[Mapping[str, float], Mapping[str, Any]], float]
    better: str = "min"
    range: tuple[float, float] = (0.0, math.inf)


@dataclass(frozen=True)
class Solution:
    """One IK branch or FK assembly mode: a label (e.g. '+-') and its value vector."""

    label: str
    values: np.ndarray

    def as_dict(self) -> dict:
        return {"branch": self.label, "values": [float(v) for v in self.values]}


@dataclass(frozen=True)
class Mechanism(ABC):
    """Base description; concrete mechanisms subclass and fill the methods."""

    name: str
    title: str
    seed: str
    motion: str  # e.g. "3T", "2R1T"
    task_axes: tuple[str, ...]
    task_units: tuple[str, ...]  # "length" or "angle" per task axis
    joints: tuple[str, ...]
    joint_units: tuple[str, ...]
    parameters: tuple[Parameter, ...]
    options: tuple[Option, ...] = field(default_factory=tuple)
    default_length_unit: str = "m"
    fields: tuple[Field, ...] = field(default_factory=tuple)  # slots of the field kernel; starts with base_fields
    design_metrics: tuple[DesignMetric, ...] = field(default_factory=tuple)
    # (column, unit) of each derived_columns entry, unit as Parameter.unit ('length', 'angle', '1' or a text with
    # {length}); the labels of plots and report.html read them. A tuple: the mechanism stays hashable
    derived_units: tuple[tuple[str, str], ...] = ()
    # the evaluator's plans for this mechanism (scalesynth.evaluation.plans), chosen by benchmark and explained where
    # each mechanism sets them; None: the default plan per task dimension, or no calibrated uniform grid
    node_plan: ClassVar[ColumnPlan | None] = None  # the adaptive evaluator with nodes and bisections
    interval_plan: ClassVar[ColumnPlan | None] = None  # with its closed-form column intervals (interval_kernel_for)
    uniform_plan: ClassVar[UniformPlan | None] = None  # the tolerance form on a calibrated uniform grid
    # adaptive-evaluator plans calibrated per tolerance (evaluation.plans.CalibratedPlan; a description's evaluation
    # block): ahead of the per-design calibration ladder
    calibrated_plans: ClassVar[tuple] = ()

    @property
    def n_fields(self) -> int:
        return len(self.fields)

    @property
    def field_names(self) -> tuple[str, ...]:
        return tuple(f.name for f in self.fields)

    # ----- parameters ---------------------------------------------------------------------------
    @property
    def parameter_names(self) -> tuple[str, ...]:
        return tuple(p.name for p in self.parameters)

    @property
    def option_names(self) -> tuple[str, ...]:
        return tuple(o.name for o in self.options)

    @property
    def pose_axes(self) -> tuple[str, ...]:
        """Names of the values of an FK solution (default: the task axes; 6-DOF mechanisms add orientation)."""
        return self.task_axes

    @property
    def planar(self) -> bool:
        return len(self.task_axes) == 2

    def default_design(self) -> dict[str, float]:
        return {p.name: float(p.default) for p in self.parameters}

    def default_options(self) -> dict[str, Any]:
        return {o.name: o.default for o in self.options}

    def resolve_design(self, values: Mapping[str, Any] | None = None) -> dict[str, float]:
        """Defaults overlaid by ``values``; raise InvalidParameter naming the first bad entry."""
        design = self.default_design()
        for key, value in (values or {}).items():
            if key not in design:
                raise InvalidParameter(f"design.{key}: unknown parameter of {self.name} " + hint(str(key), design))
            design[key] = _finite_float(f"design.{key}", value)
        for p in self.parameters:
            if p.positive and design[p.name] <= 0:
                raise InvalidParameter(f"design.{p.name}: must be > 0, got {design[p.name]:g}")
        return design

    def resolve_options(self, values: Mapping[str, Any] | None = None) -> dict[str, Any]:
        options = self.default_options()
        for key, value in (values or {}).items():
            if key not in options:
                raise InvalidParameter(f"options.{key}: unknown option of {self.name} "
                                       + hint(str(key), options, also=self.parameter_names))
            options[key] = value
        self.check_options(options)
        for key, value in options.items():
            _check_magnitudes(f"options.{key}", value)
        return options

    def check_options(self, options: dict[str, Any]) -> None:  # noqa: B027 - optional hook, no options by default
        """Validate option values in place (override); raise InvalidParameter naming the option."""

    # ----- what subclasses provide (abstract: a registered mechanism cannot be created without them) -----------
    @abstractmethod
    def pack(self, design: Mapping[str, float], options: Mapping[str, Any]) -> np.ndarray:
        """Flatten a resolved design and options into the float64 vector the point kernel reads."""

    @property
    @abstractmethod
    def field_kernel(self):
        """The Numba field kernel ``kernel(p, x, y, z, out)`` writing ``n_fields`` slots (module docstring)."""

    @property
    def reach_kernel(self):
        """A Numba kernel with the field kernel's signature whose slot 0 is >= 0 exactly where the field kernel's
        is (reachable), the other slots unspecified: the adaptive evaluator's nodes and bisections need no more.
        Default: the field kernel itself; a mechanism overrides it with one that skips the costly fields."""
        return self.field_kernel

    @property
    def lci_kernel(self):
        """A Numba kernel with the field kernel's signature whose slot 0 is the field kernel's, bit for bit (the LCI
        or -1), the other slots unspecified: a search whose workspace metrics are the LCI's alone (measure, GCI,
        bands) runs it (``grid_stats(lci_only=True)``, evaluate_population's ``fields``). Default: the field
        kernel itself; a mechanism overrides it with one that skips the costly fields."""
        return self.field_kernel

    def stats_kernel(self, packed: np.ndarray, lci_only: bool = False):
        """The kernel the workspace evaluators run over the designs ``packed`` (n, N): ``lci_kernel`` for
        ``lci_only``, else the field kernel. A mechanism whose opt-in fields are off in every design may answer a
        kernel that writes the other fields and leaves those slots alone (the evaluators' buffers hold 0 there, what
        the field kernel writes with its flags off), so that a run without them never compiles their stages."""
        return self.lci_kernel if lci_only else self.field_kernel

    @property
    def interval_kernel(self):
        """None, or a Numba kernel ``intervals(p, x, y, zlo, zhi, out) -> k`` (3-D tasks): the reachable set of the
        column at cross position (x, y) over [zlo, zhi] of the column axis (``column_axis``: by default the last
        task axis; x, y: the other two task coordinates in task order), i.e. where the reach kernel's slot 0 is
        >= 0, in closed form: its k >= 0 sorted, disjoint, closed intervals written to out[:k] (out: float64
        (K, 2), task units; exact to rounding at the ends), or -1 when this design and these options are not
        handled in closed form or need more than K rows (the adaptive evaluator then evaluates nodes and bisects,
        kernels.adaptive). Default: None (nodes and bisection everywhere)."""
        return None

    def column_axis(self, options: Mapping[str, Any]) -> int:
        """The task axis along which ``interval_kernel`` gives a column's reachable intervals under these resolved
        options, and so the axis the adaptive evaluator runs its columns along when it uses the interval kernel
        (without it, the columns run along the last axis). Default: the last task axis. A mechanism returning
        another axis gives its kernels in column order too (``column_order_kernel``)."""
        return len(self.task_axes) - 1

    def column_order_kernel(self, kernel, options: Mapping[str, Any]):
        """``kernel`` (this mechanism's field_kernel, lci_kernel or reach_kernel) as a Numba kernel
        ``k(p, u, v, w, out)`` whose task coordinates come in column order: the two cross axes in task order, then
        ``column_axis(options)``; the same out, bit for bit. Default (the column axis is the last): ``kernel``."""
        if self.column_axis(options) != len(self.task_axes) - 1:
            raise NotImplementedError(f"{self.name}: column_axis is not the last task axis, so "
                                      "column_order_kernel must be overridden")
        return kernel

    def interval_kernel_for(self, options: Mapping[str, Any]):
        """``interval_kernel`` where it handles every column under these resolved options, else None: the adaptive
        evaluator then runs the mechanism's node plan (evaluate.adaptive_plan), whose z-levels find the thin shells
        that nodes miss. Default: the interval kernel whatever the options."""
        return self.interval_kernel

    @property
    def point_kernel(self):
        """Scalar LCI kernel ``f(p, x, y, z) -> LCI or -1`` derived from the field kernel (single points, plots)."""
        kernel = _LCI_KERNELS.get(self.name)
        if kernel is None:
            from scalesynth.kernels.grid import lci_kernel

            kernel = _LCI_KERNELS[self.name] = lci_kernel(self.field_kernel, self.n_fields)
        return kernel

    @abstractmethod
    def bounding_box(self, design: Mapping[str, float], options: Mapping[str, Any]) -> tuple[np.ndarray, np.ndarray]:
        """Box (lo, hi), 3 entries each, that contains the whole reachable set."""

    @abstractmethod
    def inverse_kinematics(self, design, options, pose) -> list[Solution]:
        """Every IK branch of a pose, labelled; [] if the pose is out of reach."""

    @abstractmethod
    def forward_kinematics(self, design, options, inputs) -> list[Solution]:
        """Every FK assembly mode found for the joint inputs, labelled."""

    @abstractmethod
    def kernel_branch(self, options: Mapping[str, Any]) -> str:
        """Label of the IK branch (working mode) whose LCI the point kernel returns."""

    @abstractmethod
    def lci(self, design, options, pose, q) -> float:
        """LCI at a pose with joint values q, computed with NumPy (SVD); the point kernel's reference."""

    @abstractmethod
    def singularity(self, design, options, pose, q, tol: float = 1e-7) -> str:
        """'none', 'inverse', 'forward' or 'both'."""

    # ----- cycle analysis and interference (scalesynth.cycle); optional: a mechanism without them says so --
    def link_geometry(self, design, options, pose, q):
        """Bodies at a pose with joint values q as named capsules, and which bodies share a joint
        (:class:`scalesynth.mechanisms.links.LinkGeometry`, mechanism frame, length unit, planar z = 0). A mechanism
        may add its vectorised twin ``link_endpoints(design, options, poses (m, k), q (m, n_joints))`` ->
        links.SegmentPoints, which the link dynamics use (tests/test_link_dynamics.py holds the two equal)."""
        raise InvalidParameter(f"mechanism: {self.name} has no link geometry yet (cycle and clearance need it)")

    def velocity_map(self, design, options, pose, q) -> np.ndarray:
        """Square matrix A (n_joints x n_joints) with q_dot = A [x_dot; 0]: its first len(task_axes) columns
        map task-axis rates (length or rad per unit time) to actuator rates, any further columns the rates of
        the degrees of freedom the task holds constant (pprs-rprs: the angular velocity). The inverse of the
        forward Jacobian; actuator forces of a task-space force F follow from A^T tau = [F; 0]."""
        raise InvalidParameter(f"mechanism: {self.name} has no velocity map yet (cycle analysis needs it)")

    def cycle_kinematics(self, design, options, poses, label: str) -> tuple[np.ndarray, np.ndarray]:
        """IK in branch ``label`` and the velocity map at many poses (n, k): q (n, n_joints), NaN rows where the
        branch does not exist, and A (n, n_joints, n_joints) (NaN there). This default loops over
        inverse_kinematics and velocity_map (the reference); a mechanism may override it with a vectorised twin
        that must agree with it (tests/test_cycle.py)."""
        n, nj = len(poses), len(self.joints)
        q = np.full((n, nj), np.nan)
        a = np.full((n, nj, nj), np.nan)
        for s, pose in enumerate(poses):
            sols = {sol.label: sol.values for sol in self.inverse_kinematics(design, options, pose)}
            if label in sols:
                q[s] = sols[label]
                a[s] = self.velocity_map(design, options, pose, q[s])
        return q, a

    def population_cycle_kinematics(self, designs, options, poses, label: str) -> tuple[np.ndarray, np.ndarray]:
        """cycle_kinematics of many resolved designs, each at its own poses (D, n, k) -> q (D, n, n_joints),
        A (D, n, n_joints, n_joints). This default calls cycle_kinematics per design; a mechanism may batch it
        (the cycle metrics of a population, ``cycle.population``), equal to these calls to rounding."""
        out = [self.cycle_kinematics(d, options, p, label) for d, p in zip(designs, poses, strict=True)]
        nj = len(self.joints)
        if not out:
            return np.empty((0, poses.shape[1], nj)), np.empty((0, poses.shape[1], nj, nj))
        return np.stack([q for q, _ in out]), np.stack([a for _, a in out])

    def payload_points(self, design, options, poses) -> np.ndarray:
        """payload_point at many poses (n, k) -> (n, 3); this default loops, a mechanism may vectorise it."""
        return np.array([self.payload_point(design, options, pose) for pose in poses], dtype=float).reshape(-1, 3)

    def payload_point(self, design, options, pose) -> np.ndarray:
        """Where a cycle's payload (a point mass) sits at a pose: a 3-D point of the mechanism frame (length unit).
        Needed only by mechanisms with an angular task axis (with Cartesian task axes the payload is at the task
        point); the cycle analysis differentiates it to get the payload's velocity and acceleration."""
        raise InvalidParameter(f"mechanism: {self.name} has no payload point yet (cycles on its task axes need it)")

    def mirror_axes(self, options: Mapping[str, Any]) -> tuple[int, ...]:
        """Task axes a on which, under these resolved options, every design's reachable set and every field are
        symmetric about 0: f(.., x_a, ..) = f(.., -x_a, ..), because the pose at -x_a is the mirror image of the
        pose at x_a (tests/test_mirror.py checks each declaration on random designs and options). The tolerance form
        then evaluates only the half box x_a >= 0 where the box is symmetric about 0 (evaluate.py). Default: none."""
        return ()

    def kernel_clearance(self, options: Mapping[str, Any]) -> bool:
        """Whether the field kernel's ``clearance`` slot holds the link capsules' clearance under these resolved
        options (the cycle then reads it from one kernel call instead of link_geometry per sample). Default:
        wherever the mechanism has that field; an opt-in field (the described mechanisms') says when it is on."""
        return "clearance" in self.field_names

    def grid_stats(self, packed: np.ndarray, lo: np.ndarray, step: np.ndarray, shape: np.ndarray, edges: np.ndarray,
                   lci_only: bool = False):
        """Statistics rows of every field for many designs (layout in kernels.grid); ``lci_only``: only the count,
        the LCI's statistics and the bands are meaningful (``lci_kernel``). A mechanism may override this with a
        faster kernel that feeds the same accumulator (kernels.grid.gather_column, accumulate_cells)."""
        from scalesynth.kernels import grid as _grid

        return _grid.population_stats(self.stats_kernel(packed, lci_only), self.n_fields, packed, lo, step, shape,
                                      edges)

    def derived_columns(self, design: Mapping[str, float]) -> dict[str, float]:
        """Extra result columns derived from a design (e.g. m_minus_n); none by default."""
        return {}

    def canonical_vectors(self, names: list[str], X: np.ndarray) -> np.ndarray:
        """Design vectors in coordinates where two rows are equal iff the models are identical (default: X)."""
        return np.asarray(X, dtype=float)

    # ----- helpers shared by the CLI ------------------------------------------------------------
    def measure_name(self) -> str:
        return "area" if self.planar else "volume"

    def measure_unit(self, length_unit: str) -> str:
        """Unit suffix of the workspace measure, e.g. 'm3', 'mm2', 'mm_rad2'."""
        n_len = sum(1 for u in self.task_units if u == "length")
        n_ang = sum(1 for u in self.task_units if u == "angle")
        parts = []
        if n_len:
            parts.append(length_unit + (str(n_len) if n_len > 1 else ""))
        if n_ang:
            parts.append("rad" + (str(n_ang) if n_ang > 1 else ""))
        return "_".join(parts)

    def measure_key(self, length_unit: str) -> str:
        return f"{self.measure_name()}_{self.measure_unit(length_unit)}"

    def length_unit(self, unit: str | None, where: str = "units.length") -> str:
        """The length unit every number of this mechanism is in: ``unit`` if it names that unit, the mechanism's
        own unit when None. Any other unit is refused (InvalidParameter naming ``where``): the kernels, defaults
        and options are in the mechanism's own unit and nothing converts them, so another name would only relabel
        the numbers (issue 27)."""
        if unit is None or unit == self.default_length_unit:
            return self.default_length_unit
        raise InvalidParameter(f"{where}: {self.name} computes in {self.default_length_unit}, not {unit!r}; "
                               f"lengths are not converted, so give every length in {self.default_length_unit} "
                               f"(units.length: {self.default_length_unit})")

    def check_vector(self, what: str, values, expected: int) -> np.ndarray:
        arr = np.asarray(values, dtype=float)
        if arr.shape != (expected,) or not np.all(np.isfinite(arr)):
            raise InvalidPose(f"{what}: expected {expected} finite numbers, got {values!r}")
        if np.any(np.abs(arr) > MAX_MAGNITUDE):
            raise InvalidPose(f"{what}: values beyond +-{MAX_MAGNITUDE:g} (the largest magnitude scalesynth "
                              "computes with)")
        return arr


_LCI_KERNELS: dict[str, Any] = {}


@functools.lru_cache(maxsize=16)
def _circle_candidates(k: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Point indices of every pair (i, j) and triple (a, b, c) of ``k`` points."""
    i, j = np.triu_indices(k, 1)
    tri = np.array([(a, b, c) for a in range(k) for b in range(a + 1, k) for c in range(b + 1, k)],
                   dtype=np.int64).reshape(-1, 3)
    return i, j, tri[:, 0].copy(), tri[:, 1].copy(), tri[:, 2].copy()


def enclosing_circle_radius(points) -> float:
    """Radius of the smallest circle holding every 2-D point (a few points: the best circle through two or three
    of them that holds all; exact)."""
    pts = np.array(points, dtype=float).reshape(-1, 2)
    k = len(pts)
    if k < 2:
        return 0.0
    # candidates: the circle on each pair as diameter, the circumcircle of each non-collinear triple. Every array
    # operation is the elementwise one of the scalar formulas, |p|^2 is p @ p as before (BLAS: a fused multiply-add,
    # not x x + y y), so the values are those of the per-candidate loop this replaces (issue 15: it took 0.2 ms of
    # a 2 ms design evaluation); bit for bit on 80 000 random point sets
    i, j, a, b, c = _circle_candidates(k)
    x, y = pts[:, 0], pts[:, 1]
    sq = np.array([p @ p for p in pts])
    d = 2.0 * (x[a] * (y[b] - y[c]) + x[b] * (y[c] - y[a]) + x[c] * (y[a] - y[b]))
    ok = d != 0.0
    a, b, c, d = a[ok], b[ok], c[ok], d[ok]
    sa, sb, sc = sq[a], sq[b], sq[c]
    cx = np.concatenate((0.5 * (x[i] + x[j]), (sa * (y[b] - y[c]) + sb * (y[c] - y[a]) + sc * (y[a] - y[b])) / d))
    cy = np.concatenate((0.5 * (y[i] + y[j]), (sa * (x[c] - x[b]) + sb * (x[a] - x[c]) + sc * (x[b] - x[a])) / d))
    n2 = len(i)
    radius = np.concatenate((0.5 * np.hypot(x[i] - x[j], y[i] - y[j]), np.hypot(x[a] - cx[n2:], y[a] - cy[n2:])))
    dist = np.hypot(x[None, :] - cx[:, None], y[None, :] - cy[:, None])
    holds = np.all(dist <= radius[:, None] * (1 + 1e-12) + 1e-300, axis=1)
    return float(radius[holds].min(initial=math.inf))


def wrap_angle(a):
    """Angle(s) in (-pi, pi]: a float for a scalar, an array for an array."""
    w = np.arctan2(np.sin(a), np.cos(a))
    w = np.where(w == -np.pi, np.pi, w)
    return float(w) if np.ndim(w) == 0 else w


def singularity_label(inverse: bool, forward: bool) -> str:
    """'none', 'inverse', 'forward' or 'both' from the two singularity tests."""
    return {(False, False): "none", (True, False): "inverse", (False, True): "forward"}.get((inverse, forward), "both")


def svd_lci(matrix) -> float:
    """sigma_min / sigma_max of a matrix by NumPy's SVD (the kernels' reference); 0 for a zero matrix."""
    sv = np.linalg.svd(np.asarray(matrix, dtype=float), compute_uv=False)
    return float(sv[-1] / sv[0]) if sv[0] > 0 else 0.0


def check_magnitude(field_name: str, value: float) -> float:
    """``value``, or InvalidParameter naming the field if |value| > MAX_MAGNITUDE or if it is subnormal (the caller
    checks finiteness)."""
    if abs(value) > MAX_MAGNITUDE:
        raise InvalidParameter(f"{field_name}: {value:g} is beyond +-{MAX_MAGNITUDE:g}, the largest magnitude "
                               "scalesynth computes with (products of such values overflow)")
    if is_subnormal(value):
        raise InvalidParameter(f"{field_name}: {value:g} is {SUBNORMAL}")
    return value


# the message of a subnormal number: every product with it underflows to 0 and a division by it overflows
SUBNORMAL = (f"subnormal (non-zero below {sys.float_info.min:.4g}, products with it underflow to 0): "
             "give 0 or a larger number")


def is_subnormal(value: float) -> bool:
    """Whether ``value`` is non-zero and below the smallest normal float in magnitude."""
    return value != 0.0 and abs(value) < sys.float_info.min


def _check_magnitudes(field_name: str, value: Any) -> None:
    if isinstance(value, (list, tuple)):
        for i, v in enumerate(value):
            _check_magnitudes(f"{field_name}[{i}]", v)
    elif isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value):
        check_magnitude(field_name, float(value))


def _finite_float(field_name: str, value: Any) -> float:
    if isinstance(value, bool):
        raise InvalidParameter(f"{field_name}: expected a number, got {value!r}")
    try:
        out = float(value)
    except (TypeError, ValueError):
        raise InvalidParameter(f"{field_name}: expected a number, got {value!r}") from None
    if not math.isfinite(out):
        raise InvalidParameter(f"{field_name}: must be finite, got {value!r}")
    return check_magnitude(field_name, out)


def parse_range(name: str, value: Any) -> tuple[float, float] | None:
    """Option helper: None or a [lo, hi] pair with lo < hi (finite)."""
    if value is None:
        return None
    if not isinstance(value, (list, tuple)) or len(value) != 2:
        raise InvalidParameter(f"options.{name}: expected [lo, hi], got {value!r}")
    lo = _finite_float(f"options.{name}[0]", value[0])
    hi = _finite_float(f"options.{name}[1]", value[1])
    if not lo < hi:
        raise InvalidParameter(f"options.{name}: lower bound {lo:g} must be below upper bound {hi:g}")
    return lo, hi
