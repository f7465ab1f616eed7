"""Closed task-space paths and motion laws: positions, velocities and accelerations over one cycle.

A cycle is a closed polyline (vertices in task axes, the last joined back to the first). With a *rest-to-rest*
law every segment starts and ends at rest and its normalised displacement s(tau), tau in [0, 1], follows

* ``poly345``: s = 10 tau^3 - 15 tau^4 + 6 tau^5 (peak s' = 1.875, peak |s''| = 5.7735);
* ``modified_trapezoid``: acceleration with sine blends over the first and last eighth of each half
  (peak s' = 2.0, peak |s''| = 4.888; the classic cam law).

A segment of length L_k lasts T_k proportional to sqrt(L_k) (so every segment of one law has the same peak
acceleration), the T_k summing to the cycle period. The law ``constant`` runs the whole loop at constant
speed (samples evenly spaced in arc length, velocity jumps at the vertices, acceleration 0 between them): it
is the parametrisation of the old ``drives`` curves, not a physically realisable motion.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

LAWS = ("poly345", "modified_trapezoid", "constant")

# modified trapezoid, normalised: acceleration A * shape(tau); the constants below are the piecewise integrals
_W = 4.0 * math.pi
_V1 = 1.0 / _W  # velocity (per unit A) at tau = 1/8
_S1 = 1.0 / (8.0 * _W) - 1.0 / _W**2
_V2 = _V1 + 0.25  # at tau = 3/8
_S2 = _S1 + _V1 / 4.0 + 1.0 / 32.0
_S3 = _S2 + _V2 / 8.0 + 1.0 / _W**2  # displacement (per unit A) at tau = 1/2
MT_PEAK_ACCEL = 1.0 / (2.0 * _S3)  # A = 4.888 so that s(1) = 1


def _mt_half(tau: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Modified trapezoid on tau in [0, 1/2] per unit peak acceleration: (s, s', s'')."""
    t1 = tau
    t2 = tau - 0.125
    t3 = tau - 0.375
    p1 = tau <= 0.125
    p2 = (tau > 0.125) & (tau <= 0.375)
    s = np.where(p1, t1 / _W - np.sin(_W * t1) / _W**2,
                 np.where(p2, _S1 + _V1 * t2 + 0.5 * t2 * t2,
                          _S2 + _V2 * t3 + (1.0 - np.cos(_W * t3)) / _W**2))
    v = np.where(p1, (1.0 - np.cos(_W * t1)) / _W, np.where(p2, _V1 + t2, _V2 + np.sin(_W * t3) / _W))
    a = np.where(p1, np.sin(_W * t1), np.where(p2, 1.0, np.cos(_W * t3)))
    return s, v, a


def law_profile(law: str, tau) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Normalised rest-to-rest displacement s(tau) and its derivatives s', s'' (per unit tau), tau in [0, 1]."""
    tau = np.clip(np.asarray(tau, dtype=float), 0.0, 1.0)
    if law == "poly345":
        t2 = tau * tau
        return (t2 * tau * (10.0 - 15.0 * tau + 6.0 * t2), 30.0 * t2 * (1.0 - tau) ** 2,
                60.0 * tau * (1.0 - tau) * (1.0 - 2.0 * tau))
    if law == "modified_trapezoid":
        first = tau <= 0.5
        s_a, v_a, a_a = _mt_half(np.where(first, tau, 0.5))
        s_b, v_b, a_b = _mt_half(np.where(first, 0.5, 1.0 - tau))
        k = MT_PEAK_ACCEL
        return (k * np.where(first, s_a, 2.0 * _S3 - s_b), k * np.where(first, v_a, v_b),
                k * np.where(first, a_a, -a_b))
    raise ValueError(f"unknown rest-to-rest law {law!r}")


@dataclass(frozen=True)
class Trajectory:
    """One cycle sampled in time. t (n,) s from 0 to the period (first and last sample both at the start);
    p, pd, pdd (n, k) in task units, per s and per s^2; ``segment`` (n,) the segment index of each sample (a
    vertex sample belongs to the segment it starts); vertices (m + 1, k) with the start repeated at the end and
    ``vertex_times`` (m + 1,) when each is reached."""

    t: np.ndarray
    p: np.ndarray
    pd: np.ndarray
    pdd: np.ndarray
    segment: np.ndarray
    vertices: np.ndarray
    vertex_times: np.ndarray
    law: tuple[str, ...]

    @property
    def period(self) -> float:
        return float(self.t[-1])


def close(points) -> np.ndarray:
    """Vertices (m + 1, k) of the closed polyline: the first point repeated at the end if it is not already."""
    pts = np.asarray(points, dtype=float)
    return pts if np.array_equal(pts[-1], pts[0]) and len(pts) > 2 else np.vstack([pts, pts[:1]])


def build(points, laws, period: float, samples: int) -> Trajectory:
    """Sample the closed polyline through ``points`` (m, k) over one ``period`` (s) with ``samples`` time
    intervals in all. ``laws`` is one law name or one per segment ('constant' only for the whole loop).
    Zero-length segments are dropped."""
    verts = close(points)
    seg = np.diff(verts, axis=0)
    keep = np.linalg.norm(seg, axis=1) > 0
    laws = (laws,) * len(seg) if isinstance(laws, str) else tuple(laws)
    if len(laws) != len(seg):
        raise ValueError(f"need one law per segment ({len(seg)}), got {len(laws)}")
    verts = np.vstack([verts[:1], verts[1:][keep]])
    laws = tuple(law for law, k in zip(laws, keep, strict=True) if k)
    seg = np.diff(verts, axis=0)
    length = np.linalg.norm(seg, axis=1)
    if "constant" in laws:
        return _constant_speed(verts, length, period, samples)
    weight = np.sqrt(length)
    dur = period * weight / weight.sum()
    starts = np.concatenate([[0.0], np.cumsum(dur)])
    starts[-1] = period
    counts = np.maximum(4, np.round(samples * dur / period).astype(int))
    ts, ps, vs, as_, idx = [], [], [], [], []
    for k, (law, d, n) in enumerate(zip(laws, dur, counts, strict=True)):
        tau = np.linspace(0.0, 1.0, n + 1)[:-1]
        s, sd, sdd = law_profile(law, tau)
        ts.append(starts[k] + tau * d)
        ps.append(verts[k] + s[:, None] * seg[k])
        vs.append(sd[:, None] * seg[k] / d)
        as_.append(sdd[:, None] * seg[k] / (d * d))
        idx.append(np.full(n, k))
    ts.append([period])
    ps.append(verts[:1])
    vs.append(np.zeros((1, seg.shape[1])))
    as_.append(np.zeros((1, seg.shape[1])))
    idx.append([len(seg) - 1])
    return Trajectory(
        t=np.concatenate(ts), p=np.vstack(ps), pd=np.vstack(vs), pdd=np.vstack(as_),
        segment=np.concatenate(idx).astype(int), vertices=verts, vertex_times=starts, law=laws,
    )


def _constant_speed(verts: np.ndarray, length: np.ndarray, period: float, samples: int) -> Trajectory:
    """Whole loop at speed total / period; ``samples + 1`` points evenly spaced in arc length (the old drives
    sampling, evaluate.sample_path)."""
    from scalesynth.evaluate import sample_path

    k = verts.shape[1]
    total = float(length.sum())
    p = sample_path(verts, samples + 1)[:, :k]
    t = np.linspace(0.0, period, samples + 1)
    cum = np.concatenate([[0.0], np.cumsum(length)])
    arc = t / period * total
    segment = np.clip(np.searchsorted(cum, arc, side="right") - 1, 0, len(length) - 1)
    direction = np.diff(verts, axis=0) / length[:, None]
    pd = direction[segment] * (total / period)
    return Trajectory(
        t=t, p=p, pd=pd, pdd=np.zeros_like(p), segment=segment, vertices=verts,
        vertex_times=cum / total * period, law=("constant",) * len(length),
    )
