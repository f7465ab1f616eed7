"""Mirror and rotational symmetry of a described 3T mechanism, read from its packed legs (kernel.py's layout):
which coordinate planes x = 0, y = 0 and which turns about z map the legs onto themselves, so that every field of
the kernel template is symmetric there."""

from __future__ import annotations

import numpy as np

from scalesynth.mechanisms.describe import kernel as _k

# slots that must be equal between a leg and its mirror partner, and 3-vectors that must be reflected
_SCALARS = (_k.TYPE, _k.ARM, _k.FOREARM, _k.BRANCH, _k.HAS_LIMITS, _k.LO, _k.HI, _k.HAS_CONE, _k.SIN_CONE)
_VECTORS = (_k.BASE, _k.PLAT, _k.U, _k.W)
# agreement to rounding: the legs of a pattern come from cos and sin of their angles
_RTOL = 1e-12


def mirrored_legs(p: np.ndarray, axis: int) -> bool:
    """Whether the legs packed in ``p`` (shape (N_PACKED,)) are their own mirror image in the plane
    x_axis = 0 (axis 0 or 1): :func:`mapped_legs` with that reflection (with the stiffness fields on, partners also
    need equal sections, springs and widths, and a load with no component across the plane; with the clearance
    field on, _clearance_keeps_symmetry)."""
    flip = np.ones(3)
    flip[axis] = -1.0
    return bool(mapped_legs(p, np.diag(flip))[0])


def mapped_legs(params: np.ndarray, m: np.ndarray) -> np.ndarray:
    """Per design (params: (n, N_PACKED)), whether its legs map onto themselves under the linear map ``m`` (3 x 3,
    a rotation about z or a mirror): each leg has a partner (possibly itself) with equal scalar slots whose base,
    platform offset, arm (rail) and turn directions are the leg's mapped, and whose leg-plane normal is the mapped
    one up to sign; with the stiffness fields on, also equal stiffness blocks and a load that ``m`` leaves as it is;
    with the clearance field on, _clearance_keeps_symmetry. (n,) bool; one array pass for a whole population."""
    params = np.atleast_2d(params)
    n_legs = int(params[0, 0])
    blocks = params[:, _k.HEAD : _k.HEAD + n_legs * _k.STRIDE].reshape(len(params), n_legs, _k.STRIDE)
    # rounding of cos, sin of 2 pi / n (the kinematic slots only: the stiffness block's EA is ~1e7)
    tol = _RTOL * 1e3 * np.maximum(1.0, np.abs(params[:, : _k.N_KINEMATIC]).max(axis=1))[:, None, None]
    sc = blocks[:, :, list(_SCALARS)]
    ok = np.all(np.abs(sc[:, :, None, :] - sc[:, None, :, :]) <= tol[..., None], axis=3)  # (n, i, j)
    for s in _VECTORS:
        v = blocks[:, :, s : s + 3]
        mv = v @ m.T
        ok &= np.all(np.abs(mv[:, :, None, :] - v[:, None, :, :]) <= tol[..., None], axis=3)
    a = blocks[:, :, _k.AXIS : _k.AXIS + 3]
    ma = a @ m.T
    plus = np.all(np.abs(ma[:, :, None, :] - a[:, None, :, :]) <= tol[..., None], axis=3)
    minus = np.all(np.abs(ma[:, :, None, :] + a[:, None, :, :]) <= tol[..., None], axis=3)
    ok &= plus | minus
    # the stiffness fields, where a design turns them on: partners with equal sections, springs and widths, and a
    # load the map leaves alone (a load across the map's plane or turned by it gives other deflections)
    stiff = params[:, _k.STIFF] > 0.0
    if np.any(stiff):
        sb = params[:, _k.SLEGS : _k.SLEGS + n_legs * _k.SSTRIDE].reshape(len(params), n_legs, _k.SSTRIDE)
        stol = _RTOL * 1e3 * np.maximum(1.0, np.abs(sb).max(axis=(1, 2)))[:, None, None, None]
        same = np.all(np.abs(sb[:, :, None, :] - sb[:, None, :, :]) <= stol, axis=3)
        load = params[:, _k.LOAD : _k.LOAD + 3]
        kept = np.all(np.abs(load @ m.T - load) <= _RTOL * 1e3 * np.maximum(1.0, np.abs(load).max(axis=1))[:, None],
                      axis=1)
        ok &= np.where(stiff[:, None, None], same & kept[:, None, None], True)
    return np.all(np.any(ok, axis=2), axis=1) & _clearance_keeps_symmetry(params)


def _clearance_keeps_symmetry(p: np.ndarray) -> np.ndarray:
    """Whether the clearance block of each packed design (p: (N_PACKED,) or (n, N_PACKED)) keeps every symmetry of
    its legs: off, or on with the legs' capsules alike (bodies.uniform_legs: the capsules are built from the legs'
    points, so a map of the legs onto themselves maps them onto themselves, with their radii) and without
    interference_free (the column intervals and the sector evaluator do not see the capsules' overlap: the
    evaluator falls back to nodes and bisection)."""
    p = np.asarray(p)
    return ~((p[..., _k.CLEAR] > 0.0) & ((p[..., _k.UNIFORM] <= 0.0) | (p[..., _k.FREE] > 0.0)))


def fundamental_sectors(params: np.ndarray) -> np.ndarray:
    """Per design (params: (n, N_PACKED)), the angle (rad) of the fundamental sector phi in [0, angle] of its legs'
    symmetry about z: 2 pi / n_legs for n_legs-fold rotation (n_legs >= 2), halved when the legs are also mirrored
    in y = 0 (the sector's first edge, phi = 0, is then a mirror line); NaN without rotational symmetry."""
    params = np.atleast_2d(params)
    n_legs = int(params[0, 0])
    out = np.full(len(params), np.nan)
    if n_legs < 2:
        return out
    a = 2.0 * np.pi / n_legs
    rot = np.array([[np.cos(a), -np.sin(a), 0.0], [np.sin(a), np.cos(a), 0.0], [0.0, 0.0, 1.0]])
    rotated = mapped_legs(params, rot)
    mirrored = mapped_legs(params, np.diag([1.0, -1.0, 1.0]))
    out[rotated] = np.where(mirrored, a / 2.0, a)[rotated]
    return out
