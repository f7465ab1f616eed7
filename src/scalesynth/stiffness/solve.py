"""NumPy reference solver of a :class:`~scalesynth.stiffness.model.FrameModel` (slow, general, obviously correct).

Every link end is a node with ``nd`` degrees of freedom (planar: ux, uy, rz; spatial: ux, uy, uz, rx, ry, rz); every
body other than the base has ``nd`` (rigid) or ``dim`` (point) DOFs at its reference point. Beams contribute the
exact Euler-Bernoulli element stiffness; actuator springs ``k (a . relative motion)^2``; joints are exact linear
constraints (relative translation and the rotations outside the joint's free axes vanish), eliminated with an
orthonormal null-space basis N of the constraint matrix. The platform stiffness is the static condensation of the
constrained stiffness onto the platform DOFs; the compliance is its inverse, infinite when the condensed stiffness
is singular (a singular pose: the platform can move without deforming anything). No per-voxel use: the kernels
use closed-form per-leg condensations checked against this solver.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from scalesynth.stiffness.model import FrameModel, Link

# eigenvalue ratio (smallest / largest) at or below which a platform stiffness is singular
SINGULAR_RTOL = 1e-11


@dataclass(frozen=True)
class StiffnessResult:
    """Platform stiffness ``K`` (N/length, N, N*length/rad blocks; shape (n, n), n = platform DOFs), compliance ``C``
    (None at a singular pose: infinite), translational compliance ``C_t`` (dim x dim, None when singular), the
    deflection (length unit, ``dim`` entries, inf at a singular pose) under the model's load, and ``stiffness_min``
    (N/length): the smallest eigenvalue of the translational stiffness C_t^-1 felt by a pure force (0 if singular).
    ``dofs`` names the platform DOFs."""

    K: np.ndarray
    C: np.ndarray | None
    C_t: np.ndarray | None
    deflection: np.ndarray
    stiffness_min: float
    singular: bool
    dofs: tuple[str, ...]

    @property
    def deflection_norm(self) -> float:
        return float(np.linalg.norm(self.deflection)) if np.all(np.isfinite(self.deflection)) else math.inf


def _frame(link: Link, dim: int) -> np.ndarray:
    """Rows = local unit axes x (along the beam), y, z in the global frame."""
    d = link.end - link.start
    ex = d / np.linalg.norm(d)
    if dim == 2:
        return np.array([[ex[0], ex[1], 0.0], [-ex[1], ex[0], 0.0], [0.0, 0.0, 1.0]])
    up = np.asarray(link.up, dtype=float)
    ey = up - ex * (up @ ex)
    ey /= np.linalg.norm(ey)
    return np.array([ex, ey, np.cross(ex, ey)])


def beam_stiffness(link: Link, dim: int) -> np.ndarray:
    """Global element stiffness of a straight Euler-Bernoulli beam: (6, 6) planar [ux uy rz]x2, (12, 12) spatial."""
    L = link.length
    R = _frame(link, dim)
    if dim == 2:
        ea, ei = link.EA / L, link.EIz
        k = np.zeros((6, 6))
        k[np.ix_([0, 3], [0, 3])] = ea * np.array([[1, -1], [-1, 1]])
        b = ei / L**3 * np.array([[12, 6 * L, -12, 6 * L], [6 * L, 4 * L * L, -6 * L, 2 * L * L],
                                  [-12, -6 * L, 12, -6 * L], [6 * L, 2 * L * L, -6 * L, 4 * L * L]])
        k[np.ix_([1, 2, 4, 5], [1, 2, 4, 5])] = b
        T = np.zeros((6, 6))
        T[0:3, 0:3] = R
        T[3:6, 3:6] = R
        return T.T @ k @ T
    k = np.zeros((12, 12))
    ea, gj = link.EA / L, link.GJ / L
    k[np.ix_([0, 6], [0, 6])] = ea * np.array([[1, -1], [-1, 1]])
    k[np.ix_([3, 9], [3, 9])] = gj * np.array([[1, -1], [-1, 1]])
    # bending in the local xy plane (v, theta_z) with EIz, in the xz plane (w, theta_y) with EIy (sign of theta_y)
    for idx, ei, s in (([1, 5, 7, 11], link.EIz, 1.0), ([2, 4, 8, 10], link.EIy, -1.0)):
        b = ei / L**3 * np.array([[12, s * 6 * L, -12, s * 6 * L], [s * 6 * L, 4 * L * L, -s * 6 * L, 2 * L * L],
                                  [-12, -s * 6 * L, 12, -s * 6 * L], [s * 6 * L, 2 * L * L, -s * 6 * L, 4 * L * L]])
        k[np.ix_(idx, idx)] = b
    T = np.zeros((12, 12))
    for i in range(4):
        T[3 * i : 3 * i + 3, 3 * i : 3 * i + 3] = R
    return T.T @ k @ T


class _Layout:
    """DOF numbering of a model and the motion operators of its parts."""

    def __init__(self, model: FrameModel):
        self.dim = dim = model.dim
        self.nd = 3 if dim == 2 else 6
        self.nr = 1 if dim == 2 else 3  # rotation components
        self.start: dict[str, int] = {}
        n = 0
        for link in model.links:
            for end in ("a", "b"):
                self.start[f"{link.name}.{end}"] = n
                n += self.nd
        self.bodies = {b.name: b for b in model.bodies}
        for b in model.bodies:
            if b.name == "base":
                continue
            self.start[b.name] = n
            n += self.nd if b.kind == "rigid" else dim
        self.ndof = n

    def motion(self, part: str, at: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
        """(translation rows (dim, ndof), rotation rows (nr, ndof) or None) of part ``part`` at point ``at``."""
        dim, nr = self.dim, self.nr
        t = np.zeros((dim, self.ndof))
        r = np.zeros((nr, self.ndof))
        if part == "base":
            return t, r
        s = self.start[part]
        body = self.bodies.get(part)
        if body is not None and body.kind == "point":
            t[:, s : s + dim] = np.eye(dim)
            return t, None
        t[:, s : s + dim] = np.eye(dim)
        r[:, s + dim : s + dim + nr] = np.eye(nr)
        if body is not None:  # rigid body: t(at) = t + r x (at - ref)
            d = np.asarray(at, dtype=float)[:dim] - body.ref[:dim]
            if dim == 2:
                t[:, s + 2] = [-d[1], d[0]]
            else:
                t[:, s + 3 : s + 6] = -np.array([[0, -d[2], d[1]], [d[2], 0, -d[0]], [-d[1], d[0], 0]])
        return t, r


def _complement(axes, n: int) -> np.ndarray:
    """Orthonormal basis (rows) of the complement of span(axes) in R^n."""
    if not axes:
        return np.eye(n)
    a = np.array([np.asarray(v, dtype=float)[:n] for v in axes]).T
    q, _ = np.linalg.qr(a, mode="complete")
    return q[:, a.shape[1] :].T


def _assemble(model: FrameModel, lay: _Layout) -> tuple[np.ndarray, np.ndarray]:
    dim, nd = model.dim, lay.nd
    K = np.zeros((lay.ndof, lay.ndof))
    for link in model.links:
        idx = np.r_[lay.start[f"{link.name}.a"] : lay.start[f"{link.name}.a"] + nd,
                    lay.start[f"{link.name}.b"] : lay.start[f"{link.name}.b"] + nd]
        K[np.ix_(idx, idx)] += beam_stiffness(link, dim)
    rows = []
    for j in model.joints:
        (t1, r1), (t2, r2) = (lay.motion(p, j.at) for p in j.parts)
        dt = t1 - t2
        axes3 = [np.asarray(a, dtype=float) for a in j.axes]
        if j.kind == "prismatic":
            rows.append(_complement([a[:dim] for a in axes3], dim) @ dt)
        else:
            rows.append(dt)
        if r1 is not None and r2 is not None:
            dr = r1 - r2
            if dim == 2:
                free = j.kind in ("revolute", "spherical", "universal")
                if not free:
                    rows.append(dr)
            elif j.kind in ("fixed", "prismatic"):
                rows.append(dr)
            elif j.kind in ("revolute", "universal"):
                rows.append(_complement(axes3, 3) @ dr)
        if j.stiffness is not None:
            a = axes3[0]
            if j.kind == "prismatic":
                g = a[:dim] @ dt
            elif dim == 2:
                g = dr[0] * np.sign(a[2])
            else:
                g = a @ dr
            K += j.stiffness * np.outer(g, g)
    A = np.vstack(rows) if rows else np.zeros((0, lay.ndof))
    return K, A


def is_singular(K: np.ndarray, dim: int, length: float, rtol: float = SINGULAR_RTOL) -> bool:
    """True when the platform stiffness K (translations first, then rotations) is singular: its smallest
    eigenvalue is at most rtol times its largest once rotations are measured as arc lengths at the characteristic
    length ``length`` (so every entry is in N/length and the test is unit-free)."""
    if not np.all(np.isfinite(K)):
        return True
    t = np.ones(K.shape[0])
    t[dim:] = 1.0 / length
    w = np.linalg.eigvalsh(K * np.outer(t, t))
    return bool(w[0] <= rtol * w[-1])


def _held_rotations(A: np.ndarray, s: int, dim: int, n: int) -> list[int]:
    """Rotation DOFs (indices into the platform's n DOFs) that the joints alone hold rigidly: no motion satisfying
    the constraints A u = 0 turns the platform about that axis (e.g. a chain of prismatic joints to the base, seed
    000's PPaP). Their compliance is exactly 0 and their stiffness infinite, so they are not platform DOFs."""
    if A.shape[0] == 0 or n == dim:
        return []
    _, sv, vt = np.linalg.svd(A)
    rank = int(np.sum(sv > 1e-12 * sv[0]))
    rows = vt[rank:, s : s + n]  # platform components of an orthonormal basis of the admissible motions
    return [i for i in range(dim, n) if np.linalg.norm(rows[:, i]) <= 1e-9]


def platform_compliance(model: FrameModel) -> tuple[np.ndarray | None, tuple[str, ...]]:
    """Compliance of the platform DOFs (n, n), None when the structure is a mechanism (singular pose), and the DOF
    names. Solved as the saddle-point system [[K, A^T], [A, 0]] [u; lambda] = [S^T; 0] (u the displacements under
    a unit generalised force on each platform DOF): no condensation by subtraction, so a stiff part in series with a
    soft one keeps its accuracy. Platform rotations that the joints hold rigidly (_held_rotations) are left out of
    the DOFs (a purely translating platform has DOFs x, y, z)."""
    lay = _Layout(model)
    K, A = _assemble(model, lay)
    n_all, m = lay.ndof, A.shape[0]
    body = model.body(model.platform)
    s = lay.start[model.platform]
    n = lay.nd if body.kind == "rigid" else model.dim
    held = _held_rotations(A, s, model.dim, n)
    M = np.zeros((n_all + m, n_all + m))
    M[:n_all, :n_all] = K
    M[:n_all, n_all:] = A.T
    M[n_all:, :n_all] = A
    rhs = np.zeros((n_all + m, n))
    rhs[s : s + n] = np.eye(n)
    names = ("x", "y", "z")[: model.dim]
    if n > model.dim:
        names = names + (("rz",) if model.dim == 2 else ("rx", "ry", "rz"))
    keep = [i for i in range(n) if i not in held]
    names = tuple(names[i] for i in keep)
    try:
        X = np.linalg.solve(M, rhs[:, keep])
    except np.linalg.LinAlgError:
        return None, names
    C = X[s : s + n][keep]
    if not np.all(np.isfinite(C)):
        return None, names
    return 0.5 * (C + C.T), names


def solve(model: FrameModel) -> StiffnessResult:
    """Platform stiffness, compliance, deflection under ``model.load`` and stiffness_min (see StiffnessResult)."""
    C, names = platform_compliance(model)
    dim = model.dim
    load = np.asarray(model.load, dtype=float)
    K = None
    if C is not None:
        try:
            K = np.linalg.inv(C)
            K = 0.5 * (K + K.T)
        except np.linalg.LinAlgError:
            K = None
    if K is None or is_singular(K, dim, max(link.length for link in model.links)):
        defl = np.full(dim, math.inf) if np.any(load != 0) else np.zeros(dim)
        Kout = np.zeros((len(names), len(names))) if K is None else K
        return StiffnessResult(Kout, None, None, defl, 0.0, True, names)
    C_t = C[:dim, :dim]
    defl = C_t @ load
    kmin = float(1.0 / np.linalg.eigvalsh(C_t)[-1])
    return StiffnessResult(K, C, C_t, defl, kmin, False, names)
