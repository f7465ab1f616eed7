"""The leg library: leg types with closed-form inverse kinematics, as NumPy (the kernel's twin lives in kernel.py).

A leg type says which joint is actuated, which link lengths it needs, its working-mode branches, its frame (the
directions a description may set) and how to solve it. ``Leg`` is one leg of a resolved design: numbers in the
mechanism frame, what ``DescribedMechanism.pack`` writes into the kernel's block and what its NumPy kinematics use.

* ``R-Pa``: rotary actuated arm (length ``upper_arm``) carrying a parallelogram forearm (``forearm``) whose ball or
  universal joints keep the platform's orientation: the rotary Delta's leg (RUU / RSS). Joint: the arm angle (rad).
* ``P-Pa``: a carriage on a straight rail carrying a parallelogram forearm: the linear Delta's leg (PUU / PSS).
  Joint: the carriage position along the rail (length).
* ``RUS`` (alias ``R-SS``), motion 6DOF: a rotary actuated arm (``arm``) carrying one rod (``rod``) with a
  spherical or universal joint at each end: the Hexa's leg. Joint: the arm angle (rad). Its NumPy twin and the rest
  of the 6-DOF kinematics are in sixdof.py, its kernel in kernel6.py.
* ``UPS`` (alias ``SPS``), motion 6DOF: a prismatic leg of variable length between a base joint and a platform
  joint: the hexapod's (Gough-Stewart) leg. Joint: the leg length (length).
* ``RR``, motion 2T (planar, z = 0): a rotary crank (``arm``) then a link (``forearm``) pinned to the platform
  point: a five-bar's leg. Joint: the crank angle (rad). Branches "+" / "-": the crank turned towards
  ``arm_positive`` from the line base -> platform joint, or away from it (the five-bar's working modes).
* ``PR``, motion 2T: a carriage on a straight rail then a link (``forearm``) pinned to the platform point. Joint: the
  carriage position along the rail (length). Branches "far" / "near" as P-Pa's.
  Their NumPy twin and the rest of the planar kinematics are in planar.py, their kernel in kernel2.py.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from scalesynth.mechanisms.describe import kernel as _k
from scalesynth.mechanisms.describe import kernel2 as _k2
from scalesynth.mechanisms.describe import kernel6 as _k6


@dataclass(frozen=True)
class LegType:
    """One entry of the library."""

    name: str
    code: float  # the kernel's TYPE slot
    doc: str
    joint: str  # default joint name prefix (theta1, theta2, ...)
    joint_unit: str  # 'angle' or 'length'
    links: tuple[str, ...]  # link lengths a leg of this type needs
    branches: dict[str, float]  # working-mode name -> the kernel's BRANCH value; the first is the default
    frame: dict[str, tuple[float, float, float]]  # direction fields a description may set, with their defaults
    motion: str = "3T"  # the motion type whose kernel template handles the leg


LEG_TYPES: dict[str, LegType] = {
    "R-Pa": LegType(
        "R-Pa", _k.R_PA, "rotary arm + parallelogram forearm (rotary Delta leg)", "theta", "angle",
        ("upper_arm", "forearm"), {"out": 1.0, "in": -1.0},
        {"arm_zero": (1.0, 0.0, 0.0), "arm_positive": (0.0, 0.0, -1.0)},
    ),
    "P-Pa": LegType(
        "P-Pa", _k.P_PA, "prismatic carriage + parallelogram forearm (linear Delta leg)", "s", "length",
        ("forearm",), {"far": 1.0, "near": -1.0}, {"rail": (0.0, 0.0, 1.0)},
    ),
}
_RUS = dict(joint="theta", joint_unit="angle", links=("arm", "rod"), branches={"out": 1.0, "in": -1.0},
            frame={"arm_zero": (1.0, 0.0, 0.0), "arm_positive": (0.0, 0.0, -1.0)}, motion="6DOF")
_UPS = dict(joint="q", joint_unit="length", links=(), branches={"one": 1.0}, frame={"cone_axis": (0.0, 0.0, 1.0)},
            motion="6DOF")
for _name, _doc, _kw in (
        ("RUS", "rotary arm + one rod with a spherical/universal joint at each end (Hexa leg)", _RUS),
        ("R-SS", "RUS with a spherical joint at each end of the rod (same kinematics)", _RUS),
        ("UPS", "prismatic leg of variable length between a base and a platform joint (hexapod leg)", _UPS),
        ("SPS", "UPS with a spherical base joint (same kinematics)", _UPS)):
    LEG_TYPES[_name] = LegType(_name, _k6.RUS if _kw is _RUS else _k6.UPS, _doc, **_kw)
LEG_TYPES["RR"] = LegType(
    "RR", _k2.RR, "rotary crank + link pinned to the platform point (planar five-bar leg)", "alpha", "angle",
    ("arm", "forearm"), {"+": 1.0, "-": -1.0}, {"arm_zero": (1.0, 0.0, 0.0), "arm_positive": (0.0, 1.0, 0.0)},
    motion="2T",
)
LEG_TYPES["PR"] = LegType(
    "PR", _k2.PR, "prismatic carriage + link pinned to the platform point (planar biglide leg)", "s", "length",
    ("forearm",), {"far": 1.0, "near": -1.0}, {"rail": (1.0, 0.0, 0.0)}, motion="2T",
)


@dataclass(frozen=True)
class Leg:
    """One leg of a resolved design, in the mechanism frame: base point, platform offset (Q - P), frame directions
    u (R-Pa arm at q = 0 / P-Pa rail) and w (R-Pa positive turn), the normal of the leg's plane (for the cone),
    link lengths, branch (+1/-1), actuator limits (None or (lo, hi)) and sin of the cone half-angle (None = off)."""

    type: LegType
    base: np.ndarray
    platform: np.ndarray
    u: np.ndarray
    w: np.ndarray
    normal: np.ndarray
    arm: float
    forearm: float
    branch: float
    limits: tuple[float, float] | None
    sin_cone: float | None

    def actuated_point(self, q: float) -> np.ndarray:
        """The elbow E (R-Pa) or carriage C (P-Pa) at joint value q."""
        if self.type.code == _k.R_PA:
            return self.base + self.arm * (math.cos(q) * self.u + math.sin(q) * self.w)
        return self.base + q * self.u

    def actuated_velocity(self, q: float) -> np.ndarray:
        """d(actuated point)/dq."""
        if self.type.code == _k.R_PA:
            return self.arm * (-math.sin(q) * self.u + math.cos(q) * self.w)
        return self.u.copy()

    def roots(self, pose) -> dict[float, float]:
        """Both IK roots {branch: q} at platform centre ``pose`` (limits not applied); {} out of reach. R-Pa:
        q = atan2(B, A) -+ acos(K / sqrt(A^2 + B^2)) in (-pi, pi], branch +1 the one with the larger cos q; P-Pa:
        q = D.e +- sqrt(l^2 - |D_perp|^2)."""
        d = np.asarray(pose, dtype=float) + self.platform - self.base
        if self.type.code == _k.R_PA:
            a = 2.0 * self.arm * float(d @ self.u)
            b = 2.0 * self.arm * float(d @ self.w)
            k = float(d @ d) + self.arm ** 2 - self.forearm ** 2
            n = math.hypot(a, b)
            if n == 0.0 or abs(k) > n:
                return {}
            base, g = math.atan2(b, a), math.acos(k / n)
            one, two = _wrap(base - g), _wrap(base + g)
            out_, in_ = (one, two) if math.cos(one) >= math.cos(two) else (two, one)
            return {1.0: out_, -1.0: in_}
        de = float(d @ self.u)
        h = self.forearm ** 2 - float(d @ d - de * de)
        if h < 0.0:
            return {}
        return {1.0: de + math.sqrt(h), -1.0: de - math.sqrt(h)}

    def within_limits(self, q: float, pose) -> bool:
        """Whether q lies in the actuator range (R-Pa: modulo 2 pi) and the forearm in the cone."""
        if self.limits is not None:
            lo, hi = self.limits
            if self.type.code == _k.R_PA:
                if (q - lo) % (2.0 * math.pi) > hi - lo:
                    return False
            elif not lo <= q <= hi:
                return False
        if self.sin_cone is not None:
            f = np.asarray(pose, dtype=float) + self.platform - self.actuated_point(q)
            if abs(float(f @ self.normal)) > self.forearm * self.sin_cone:
                return False
        return True


def _wrap(a: float) -> float:
    w = math.atan2(math.sin(a), math.cos(a))
    return math.pi if w == -math.pi else w
