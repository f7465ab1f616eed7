"""Finite-difference scaffolding shared by the kinematics tests: random poses the kernel finds reachable, the FK
assembly nearest a pose, and dx/dq by central differences of a mechanism's forward kinematics (the check of every
analytic Jacobian against something nobody here wrote)."""

import math

import numpy as np

# central-difference stencils: (offset in steps, weight); the sum over them divided by (denominator * h)
_STENCILS = {2: (((1, 1.0), (-1, -1.0)), 2.0),  # error O(h^2)
             4: (((-2, 1.0), (-1, -8.0), (1, 8.0), (2, -1.0)), 12.0)}  # error O(h^4)


def reachable_points(point_fields, packed, lo, hi, rng, k, min_lci=1e-3, tries=200_000, n_fields=3):
    """k random points of the box [lo, hi] (each drawn as rng.uniform(lo, hi)) where the kernel's
    point_fields(packed, *p, out) writes an LCI above min_lci into out[0]; list of arrays of lo's shape.
    ``n_fields``: the kernel's output size (its mechanism's n_fields: a kernel writes every field, unchecked)."""
    pts, out = [], np.zeros(n_fields)
    for _ in range(tries):
        p = rng.uniform(lo, hi)
        point_fields(packed, *p, out)
        if out[0] > min_lci:
            pts.append(p)
            if len(pts) == k:
                return pts
    raise AssertionError(f"only {len(pts)} of {k} reachable points in {tries} draws")


def nearest_assembly(solutions, p):
    """The values of the FK solution (objects with .values) nearest to pose p in the max norm: the assembly a
    small joint step from p's inputs lands on."""
    return min((s.values for s in solutions), key=lambda v: np.abs(v - p).max())


def assembly_error(solutions, p):
    """Max-norm distance from pose p to the nearest FK solution (inf when there is none)."""
    return min((float(np.abs(s.values - p).max()) for s in solutions), default=math.inf)


def fk_jacobian(mech, design, options, p, q, h, order=2):
    """dx/dq at joint values q by central differences (order 2 or 4) of mech.forward_kinematics, each step's
    assembly the one nearest pose p; shape (len(p), len(q)), units of the pose per unit of the joints."""
    q = np.asarray(q, dtype=float)
    stencil, denominator = _STENCILS[order]
    fd = np.zeros((len(p), len(q)))
    for i in range(len(q)):
        dq = np.zeros(len(q))
        dq[i] = h
        vals = {s: nearest_assembly(mech.forward_kinematics(design, options, q + s * dq), p) for s, _ in stencil}
        fd[:, i] = sum(w * vals[s] for s, w in stencil) / (denominator * h)
    return fd


def central_differences(f, x, steps):
    """df/dx at x by central differences: column k is (f(x + h_k e_k) - f(x - h_k e_k)) / (2 h_k), ``steps`` the
    h_k (one number for every axis, or one per axis); f maps an array like x to an array (m,). Shape (m, len(x))."""
    x = np.asarray(x, dtype=float)
    steps = np.broadcast_to(np.asarray(steps, dtype=float), x.shape)
    cols = []
    for k in range(len(x)):
        h = float(steps[k])
        e = np.zeros(len(x))
        e[k] = h
        cols.append((np.asarray(f(x + e)) - np.asarray(f(x - e))) / (2 * h))
    return np.stack(cols, axis=1)
