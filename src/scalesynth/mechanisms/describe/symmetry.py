"""Mirror symmetry of a described 3T mechanism, read from its packed legs (kernel.py's layout): which coordinate
planes x = 0, y = 0 map the legs onto themselves, so that every field of the kernel template is symmetric there."""

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
    x_axis = 0 (axis 0 or 1): each leg has a partner (possibly itself) with equal type, lengths, branch, limits and
    cone, whose base, platform offset, arm (rail) direction and turn direction are the leg's reflected, and whose
    leg-plane normal is the reflected one up to sign (the kernel reads only |f . normal|). With the per-voxel
    stiffness fields on (the packed flag), partners also need equal sections, actuator springs and widths, and the
    load must have no component across the plane (a reflected load would give other deflections)."""
    n = int(p[0])
    blocks = [p[_k.HEAD + i * _k.STRIDE : _k.HEAD + (i + 1) * _k.STRIDE] for i in range(n)]
    stiff = [p[_k.SLEGS + i * _k.SSTRIDE : _k.SLEGS + (i + 1) * _k.SSTRIDE] for i in range(n)]
    scale = max(1.0, float(np.abs(p[: _k.N_KINEMATIC]).max()))
    flip = np.ones(3)
    flip[axis] = -1.0
    with_stiffness = p[_k.STIFF] > 0.0
    if with_stiffness and p[_k.LOAD + axis] != 0.0:
        return False

    def partner(i: int, j: int) -> bool:
        a, b = blocks[i], blocks[j]
        if not np.allclose(a[list(_SCALARS)], b[list(_SCALARS)], rtol=0.0, atol=_RTOL * scale):
            return False
        if with_stiffness and not np.allclose(stiff[i], stiff[j], rtol=_RTOL, atol=0.0):
            return False
        for s in _VECTORS:
            if not np.allclose(flip * a[s : s + 3], b[s : s + 3], rtol=0.0, atol=_RTOL * scale):
                return False
        na, nb = flip * a[_k.AXIS : _k.AXIS + 3], b[_k.AXIS : _k.AXIS + 3]
        return bool(np.allclose(na, nb, rtol=0.0, atol=_RTOL * scale)
                    or np.allclose(na, -nb, rtol=0.0, atol=_RTOL * scale))

    return all(any(partner(i, j) for j in range(n)) for i in range(n))
