"""Per-voxel stiffness (issue 12): the Numba per-leg condensation of scalesynth.stiffness.legs against a slow NumPy
twin and the NumPy reference solver (textbook frames: a cantilever chain on a revolute actuator, a Stewart platform of
two-force legs; then seed 003's ups-sspr frame at many poses), then ups-sspr's per-voxel fields (slots 3, 4: the
closed-form chain condensation) against the reference solver, the generic Numba routine and evaluate's statistics."""

import math

import numpy as np
import pytest
from numba import njit
from scipy.linalg import null_space

from scalesynth.config import load_config
from scalesynth.evaluate import evaluate_config, make_grid
from scalesynth.kernels import grid as kgrid
from scalesynth.mechanisms import get
from scalesynth.mechanisms import ups_sspr as U
from scalesynth.stiffness import legs
from scalesynth.stiffness.model import Body, FrameModel, Joint, Link
from scalesynth.stiffness.solve import solve

from conftest import ROOT

E, G = 70e3, 70e3 / 2.66  # N/mm^2
EA, EIY, EIZ, GJ = E * 348.7, E * 60066.0, E * 30000.0, G * 120132.0  # unequal bending axes on purpose


def rel(a, b):
    return float(np.max(np.abs(np.asarray(a) - np.asarray(b))) / np.max(np.abs(b)))


# ----- the slow NumPy twin of the per-leg condensation -------------------------------------------------------------
def skew(d):
    return np.array([[0.0, -d[2], d[1]], [d[2], 0.0, -d[0]], [-d[1], d[0], 0.0]])


def twin_beam_compliance(a, b, up, ea, eiy, eiz, gj, ref):
    """Ad C_b Ad^T: the cantilever tip compliance in local axes (x along the beam, y = up made orthogonal), rotated
    to global axes and carried from b to ref (t_ref = t_b + r_b x (ref - b))."""
    a, b, up, ref = (np.asarray(v, float) for v in (a, b, up, ref))
    L = np.linalg.norm(b - a)
    ex = (b - a) / L
    ey = up - ex * (up @ ex)
    ey /= np.linalg.norm(ey)
    R = np.array([ex, ey, np.cross(ex, ey)])
    c = np.zeros((6, 6))
    c[0, 0] = L / ea
    c[1, 1], c[1, 5], c[5, 5] = L**3 / (3 * eiz), L**2 / (2 * eiz), L / eiz
    c[2, 2], c[2, 4], c[4, 4] = L**3 / (3 * eiy), -(L**2) / (2 * eiy), L / eiy
    c[3, 3] = L / gj
    c[5, 1], c[4, 2] = c[1, 5], c[2, 4]
    T = np.zeros((6, 6))
    T[:3, :3] = T[3:, 3:] = R
    cb = T.T @ c @ T
    ad = np.eye(6)
    ad[:3, 3:] = -skew(ref - b)
    return ad @ cb @ ad.T


def twin_leg_stiffness(C, twists):
    """N (N^T C N)^-1 N^T, N an orthonormal basis of the wrenches f with f . xi = 0 for every joint twist xi."""
    N = null_space(np.array(twists)) if len(twists) else np.eye(6)
    return N @ np.linalg.solve(N.T @ C @ N, N.T)


def rot_twist(q, a, ref):
    a = np.asarray(a, float) / np.linalg.norm(a)
    return np.concatenate([np.cross(a, np.asarray(ref, float) - np.asarray(q, float)), a])


# ----- Numba assembly helpers (the routines under test, driven from plain arrays) --------------------------------
@njit(cache=True)
def nb_leg(beams, springs, twists, ref, length, K):
    """K += the leg stiffness at ref: beams rows (ax, ay, az, bx, by, bz, upx, upy, upz, EA, EIy, EIz, GJ), springs
    rows (kind 0 prismatic / 1 revolute, qx, qy, qz, ax, ay, az, k), twists columns (6, m)."""
    C = np.zeros((6, 6))
    for b in beams:
        legs.add_beam_compliance(C, b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7], b[8], b[9], b[10], b[11], b[12],
                                 ref[0], ref[1], ref[2])
    for s in springs:
        if s[0] == 0.0:
            legs.add_prismatic_spring(C, s[4], s[5], s[6], s[7])
        else:
            legs.add_revolute_spring(C, s[1], s[2], s[3], s[4], s[5], s[6], s[7], ref[0], ref[1], ref[2])
    N = np.empty((6, 6))
    n = legs.constraint_wrenches(twists, twists.shape[1], length, N)
    ok = legs.add_leg_stiffness(C, N, n, K, np.empty((6, 6)))
    return C, n, ok


def beam_row(a, b, up=(0.0, 0.0, 1.0), ea=EA, eiy=EIY, eiz=EIZ, gj=GJ):
    return [*a, *b, *up, ea, eiy, eiz, gj]


def test_beam_compliance_and_leg_equal_the_numpy_twin():
    """Random chains of 1-3 beams with a spring and 0-5 joint twists: C and K equal the twin's to 1e-10."""
    rng = np.random.default_rng(3)
    for trial in range(40):
        pts = np.cumsum(rng.uniform(-200, 200, (4, 3)), axis=0)
        nb = 1 + trial % 3
        ref = rng.uniform(-300, 300, 3)
        beams = np.array([beam_row(pts[i], pts[i + 1], rng.normal(size=3)) for i in range(nb)])
        axis = rng.normal(size=3)
        axis /= np.linalg.norm(axis)
        kind = float(trial % 2)
        springs = np.array([[kind, *pts[0], *axis, 3e4 if kind == 0 else 5e8]])
        m = trial % 6
        twists = [rot_twist(pts[rng.integers(0, nb + 1)], rng.normal(size=3), ref) for _ in range(m)]
        K = np.zeros((6, 6))
        J = np.array(twists).T.copy() if m else np.zeros((6, 0))
        C, n, ok = nb_leg(beams, springs, np.ascontiguousarray(J), ref, 200.0, K)
        Ct = sum(twin_beam_compliance(b[0:3], b[3:6], b[6:9], *b[9:13], ref) for b in beams)
        g = np.concatenate([axis, np.zeros(3)]) if kind == 0 else rot_twist(pts[0], axis, ref)
        Ct = Ct + np.outer(g, g) / springs[0, 7]
        rank = np.linalg.matrix_rank(J * np.r_[np.ones(3) / 200.0, np.ones(3)][:, None]) if m else 0
        assert ok and n == 6 - rank  # joints at one point free at most three rotations
        assert rel(C, Ct) < 1e-10
        Kt = twin_leg_stiffness(Ct, twists)
        assert rel(K, Kt) < 1e-8, trial
        # the constraint wrenches annihilate the joint twists: the joints pass no work
        for xi in twists:
            assert np.max(np.abs(K @ xi)) < 1e-9 * np.max(np.abs(K)) * np.max(np.abs(xi))


def test_dependent_joint_twists_free_nothing_twice():
    """A spherical joint given twice frees three rotations, not six (DEPENDENT_RTOL)."""
    J = np.zeros((6, 6))
    for c in range(6):
        legs.set_rotation_twist(J, c, 10.0, 0.0, 0.0, *np.eye(3)[c % 3], 0.0, 0.0, 0.0)
    N = np.empty((6, 6))
    assert legs.constraint_wrenches(J, 6, 100.0, N) == 3
    assert np.max(np.abs(N[:, :3].T @ J)) < 1e-12


def test_cantilever_chain_on_a_revolute_actuator_equals_the_reference_solver():
    """An L-shaped two-beam chain on a torsional actuator about an oblique axis, welded to a rigid platform at its tip:
    no passive joint, so K = C^-1 (6x6), equal to the reference solver's."""
    a, b, c = np.zeros(3), np.array([400.0, 0.0, 0.0]), np.array([400.0, 300.0, 100.0])
    axis = np.array([0.2, -0.4, 0.9]) / np.linalg.norm([0.2, -0.4, 0.9])
    k = 5e8
    links = (Link("l1", "g", a, b, EA, EIY, EIZ, GJ, np.array([0.0, 0.0, 1.0])),
             Link("l2", "g", b, c, EA, EIY, EIZ, GJ, np.array([0.0, 0.0, 1.0])))
    joints = (Joint("act", "revolute", a, ("l1.a", "base"), (axis,), k),
              Joint("knee", "fixed", b, ("l1.b", "l2.a")),
              Joint("tip", "fixed", c, ("l2.b", "platform")))
    ref = c + np.array([50.0, -20.0, 10.0])  # the platform's reference point off the tip
    m = FrameModel(3, "mm", links, joints, (Body("base", np.zeros(3)), Body("platform", ref)), "platform",
                   np.array([10.0, -20.0, -150.0]))
    res = solve(m)
    K = np.zeros((6, 6))
    beams = np.array([beam_row(a, b), beam_row(b, c)])
    nb_leg(beams, np.array([[1.0, *a, *axis, k]]), np.zeros((6, 0)), ref, 400.0, K)
    assert rel(K, res.K) < 1e-9
    kmin, defl = legs.platform_response(K, *m.load, 500.0)
    assert kmin == pytest.approx(res.stiffness_min, rel=1e-9)
    assert defl == pytest.approx(res.deflection_norm, rel=1e-9)


def test_stewart_platform_of_two_force_legs():
    """Six UPS legs (U with both axes normal to the leg at the base, cylinder, prismatic actuator spring, rod, S at
    the platform): each leg is a two-force member, K = sum G G^T / (L / EA + 1 / k), G = (u, (B - P) x u); the
    routine, the closed form and the reference solver agree."""
    k = 2e4
    ang_b = np.radians([0, 100, 120, 220, 240, 340])
    ang_p = np.radians([40, 80, 160, 200, 280, 320])
    base = [np.array([300 * np.cos(t), 300 * np.sin(t), 0.0]) for t in ang_b]
    P = np.array([15.0, -10.0, 400.0])
    top = [P + np.array([150 * np.cos(t), 150 * np.sin(t), 20.0]) for t in ang_p]
    links, joints, K_closed, K_nb = [], [], np.zeros((6, 6)), np.zeros((6, 6))
    for i, (a, b) in enumerate(zip(base, top, strict=True)):
        mid = 0.5 * (a + b)
        u = (b - a) / np.linalg.norm(b - a)
        n1 = np.cross(u, [0.0, 0.0, 1.0])
        n1 /= np.linalg.norm(n1)
        n2 = np.cross(u, n1)
        up = np.array([1.0, 0.0, 0.0])
        links += [Link(f"c{i}", "leg", a, mid, EA, EIY, EIY, GJ, up),
                  Link(f"r{i}", "leg", mid, b, EA, EIY, EIY, GJ, up)]
        joints += [Joint(f"U{i}", "universal", a, (f"c{i}.a", "base"), (n1, n2)),
                   Joint(f"P{i}", "prismatic", mid, (f"c{i}.b", f"r{i}.a"), (u,), k),
                   Joint(f"S{i}", "spherical", b, (f"r{i}.b", "platform"))]
        g = np.concatenate([u, np.cross(b - P, u)])
        K_closed += np.outer(g, g) / (np.linalg.norm(b - a) / EA + 1 / k)
        J = np.array([rot_twist(a, n1, P), rot_twist(a, n2, P), *(rot_twist(b, e, P) for e in np.eye(3))]).T
        nb_leg(np.array([beam_row(a, mid, up, eiz=EIY), beam_row(mid, b, up, eiz=EIY)]),
               np.array([[0.0, *mid, *u, k]]), np.ascontiguousarray(J), P, 300.0, K_nb)
    m = FrameModel(3, "mm", tuple(links), tuple(joints), (Body("base", np.zeros(3)), Body("platform", P)),
                   "platform", np.array([5.0, 30.0, -150.0]))
    res = solve(m)
    assert rel(K_nb, K_closed) < 1e-9 and rel(res.K, K_closed) < 1e-8
    kmin, defl = legs.platform_response(K_nb, *m.load, max(link.length for link in links))
    assert kmin == pytest.approx(res.stiffness_min, rel=1e-8)
    assert defl == pytest.approx(res.deflection_norm, rel=1e-8)


def test_series_of_two_springs():
    """Ka (Ka + Kb)^-1 Kb is the inverse of Ca + Cb for invertible springs, and a singular Ka stays allowed."""
    rng = np.random.default_rng(5)
    a, b = rng.normal(size=(6, 6)), rng.normal(size=(6, 6))
    Ka, Kb = a @ a.T + 0.1 * np.eye(6), b @ b.T + 0.1 * np.eye(6)
    out = np.empty((6, 6))
    assert legs.series_stiffness(Ka, Kb, out, np.empty((6, 6)))
    assert rel(out, np.linalg.inv(np.linalg.inv(Ka) + np.linalg.inv(Kb))) < 1e-10
    v = rng.normal(size=(6, 4))
    Ks = v @ v.T  # rank 4
    assert legs.series_stiffness(Ks, Kb, out, np.empty((6, 6)))
    # energy minimum over the middle node, by hand: Kb - Kb (Ks + Kb)^-1 Kb
    assert rel(out, Kb - Kb @ np.linalg.solve(Ks + Kb, Kb)) < 1e-9


def test_platform_response_singular_and_zero_load_never_nan():
    K = np.diag([1e3, 1e3, 0.0, 1e9, 1e9, 1e9])  # free to translate along z
    assert legs.platform_response(K, 0.0, 0.0, -150.0, 100.0) == (0.0, legs.DEFLECTION_CAP)
    assert legs.platform_response(K, 0.0, 0.0, 0.0, 100.0) == (0.0, 0.0)
    K[2, 2] = 1e3 * 1e-13  # eigenvalue ratio below SINGULAR_RTOL
    assert legs.platform_response(K, 0.0, 0.0, -150.0, 100.0) == (0.0, legs.DEFLECTION_CAP)
    K[2, 2] = math.nan
    assert legs.platform_response(K, 1.0, 0.0, 0.0, 100.0) == (0.0, legs.DEFLECTION_CAP)
    K = np.diag([2e3, 1e3, 4e3, 1e9, 1e9, 1e9])
    assert legs.platform_response(K, 0.0, 300.0, 0.0, 100.0) == pytest.approx((1e3, 0.3), rel=1e-14)


def test_sym3_max_eigenvalue():
    rng = np.random.default_rng(8)
    for _ in range(200):
        a = rng.normal(size=(3, 3))
        s = a @ a.T * 10.0 ** rng.uniform(-6, 6)
        got = legs.sym3_max_eigenvalue(s[0, 0], s[0, 1], s[0, 2], s[1, 1], s[1, 2], s[2, 2])
        assert got == pytest.approx(np.linalg.eigvalsh(s)[-1], rel=1e-12)
    assert legs.sym3_max_eigenvalue(2.0, 0.0, 0.0, 2.0, 0.0, 2.0) == 2.0


# ----- seed 003 (ups-sspr): the generic routine on its frame, and the per-voxel closed form ---------------------------
UPS = get("ups-sspr")
DESIGN = UPS.resolve_design({})


@njit(cache=True)
def ups_generic(p, alpha, beta, yy):
    """Platform stiffness (6x6 at P) of the stiffness_model frame assembled with the generic routines: each UPS leg a
    leg; the (S+SPR)R chain as the link node B0 (the lower link with its S at A0, and the SPR leg) in series with the
    upper link and the revolute at P."""
    c, am = p[U._C], p[U._AM]
    rho = math.sqrt(c * c - yy * yy)
    sa, ca, sb, cb = math.sin(alpha), math.cos(alpha), math.sin(beta), math.cos(beta)
    px, py, pz = sb * rho, yy, cb * rho
    w = np.zeros((8, 6, 6))
    C, J, N, K, Ka, Kb, work, K1 = w[0], w[1], w[2], w[3], w[4], w[5], w[6], w[7]

    def beam(C, group, ax, ay, az, bx, by, bz):
        dx, dy, dz = bx - ax, by - ay, bz - az
        up = (0.0, 0.0, 1.0) if abs(dz) < 0.9 * math.sqrt(dx * dx + dy * dy + dz * dz) else (1.0, 0.0, 0.0)
        o = U._EA_LEG if group == 0 else U._EA_LINK
        legs.add_beam_compliance(C, ax, ay, az, bx, by, bz, up[0], up[1], up[2], p[o], p[o + 1], p[o + 1],
                                 p[o + 2], px, py, pz)

    def actuated(C, ax, ay, az, bx, by, bz):
        C[:, :] = 0.0
        mx, my, mz = 0.5 * (ax + bx), 0.5 * (ay + by), 0.5 * (az + bz)
        beam(C, 0, ax, ay, az, mx, my, mz)
        beam(C, 0, mx, my, mz, bx, by, bz)
        ln = math.sqrt((bx - ax) ** 2 + (by - ay) ** 2 + (bz - az) ** 2)
        legs.add_prismatic_spring(C, (bx - ax) / ln, (by - ay) / ln, (bz - az) / ln, p[U._KACT])

    for sx in (-1.0, 1.0):
        ax, ay = sx * p[U._AX], -am
        bx0, by0 = sx * p[U._BX], p[U._BY]
        bx = px + cb * bx0 + sb * sa * by0
        by = py + ca * by0
        bz = pz - sb * bx0 + cb * sa * by0
        actuated(C, ax, ay, 0.0, bx, by, bz)
        ux, uy, uz = bx - ax, by - ay, bz
        n1 = np.cross(np.cross(np.array([0.0, 0.0, 1.0]), np.array([ax, ay, 0.0])), np.array([ux, uy, uz]))
        n1 /= np.linalg.norm(n1)
        n2 = np.cross(np.array([ux, uy, uz]), n1)
        n2 /= np.linalg.norm(n2)
        legs.set_rotation_twist(J, 0, ax, ay, 0.0, n1[0], n1[1], n1[2], px, py, pz)
        legs.set_rotation_twist(J, 1, ax, ay, 0.0, n2[0], n2[1], n2[2], px, py, pz)
        legs.set_spherical_twists(J, 2, bx, by, bz, px, py, pz)
        n = legs.constraint_wrenches(J, 5, c, N)
        legs.add_leg_stiffness(C, N, n, K, work)
    k0 = U.K0
    b0x, b0y, b0z = k0 * px, k0 * py, k0 * pz
    C[:, :] = 0.0
    beam(C, 1, 0.0, 0.0, 0.0, b0x, b0y, b0z)
    legs.set_spherical_twists(J, 0, 0.0, 0.0, 0.0, px, py, pz)
    legs.add_leg_stiffness(C, N, legs.constraint_wrenches(J, 3, c, N), Ka, work)
    actuated(C, 0.0, -am, 0.0, b0x, b0y, b0z)
    legs.set_spherical_twists(J, 0, 0.0, -am, 0.0, px, py, pz)
    legs.set_rotation_twist(J, 3, b0x, b0y, b0z, cb, 0.0, -sb, px, py, pz)
    legs.add_leg_stiffness(C, N, legs.constraint_wrenches(J, 4, c, N), Ka, work)
    C[:, :] = 0.0
    beam(C, 1, b0x, b0y, b0z, px, py, pz)
    legs.set_rotation_twist(J, 0, px, py, pz, cb, 0.0, -sb, px, py, pz)
    legs.add_leg_stiffness(C, N, legs.constraint_wrenches(J, 1, c, N), Kb, work)
    legs.series_stiffness(Ka, Kb, K1, work)
    return K + K1


# poses (alpha, beta, Y): the lowest-LCI cells (alpha at its bound), the centre, generic ones, near the l1 limits
# (Y = -37.5 and 48 for the default design), box corners
POSES = [(0.5, 0.25, 47.6), (0.5, -0.25, 47.6), (0.0, 0.0, 0.0), (0.1, 0.2, 10.0), (-0.3, 0.0, 3.97),
         (0.0, 0.0, -37.4), (-0.5, -0.5, 20.0), (0.5, 0.5, -30.0), (-0.5, 0.5, 47.9)]
OPTIONS = dict(tube=[30.0, 2.0], sections={"link": [50.0, 5.0]}, actuator_stiffness=1.2e4, load=[20.0, -35.0, -150.0])


def kernel_fields(p, pose):
    out = np.full(UPS.n_fields, np.nan)
    U.point_fields(p, *map(float, pose), out)
    assert UPS.field_names[U._F_STIFFNESS_MIN] == "stiffness_min" and UPS.field_names[U._F_DEFLECTION] == "deflection"
    assert not np.any(np.isnan(out))
    return out


@pytest.mark.parametrize("opts", [{}, OPTIONS])
def test_ups_sspr_generic_routine_equals_the_reference_solver(opts):
    """The whole 6x6 platform stiffness from the generic per-leg routines equals the reference solver's at every pose,
    and the field kernel's closed form gives the same stiffness_min and deflection."""
    opt = UPS.resolve_options(opts)
    p = UPS.pack(DESIGN, opt)
    for pose in POSES:
        res = solve(UPS.stiffness_model(DESIGN, opt, pose))
        K = ups_generic(p, *pose)
        assert rel(K, res.K) < 1e-8, pose
        out = kernel_fields(p, pose)
        length = max(link.length for link in UPS.stiffness_model(DESIGN, opt, pose).links)
        assert legs.platform_response(K, *opt["load"], length) == pytest.approx((out[3], out[4]), rel=1e-9)
        assert out[3] == pytest.approx(res.stiffness_min, rel=1e-9)
        assert out[4] == pytest.approx(res.deflection_norm, rel=1e-9)


def test_ups_sspr_fields_equal_the_reference_at_random_poses():
    """150 random poses of random designs in the config's bounds: stiffness_min and deflection equal the reference
    solver's to 1e-8 (measured ~1e-13); poses outside the workspace write 0 and no NaN."""
    rng = np.random.default_rng(21)
    checked = 0
    for trial in range(150):
        design = UPS.resolve_design({"a": rng.uniform(60, 160), "b": rng.uniform(40, 120), "c": rng.uniform(115, 125)})
        opt = UPS.resolve_options({**OPTIONS, "l1_limits": None, "l2_limits": None, "l3_limits": None,
                                   "load": list(rng.uniform(-100, 100, 3))} if trial % 2 else {})
        pose = (rng.uniform(-0.5, 0.5), rng.uniform(-0.5, 0.5), rng.uniform(-0.9, 0.9) * design["c"])
        out = kernel_fields(UPS.pack(design, opt), pose)
        if out[0] < 0:
            assert out[3] == 0.0 and out[4] == 0.0
            continue
        res = solve(UPS.stiffness_model(design, opt, pose))
        assert not res.singular
        assert out[3] == pytest.approx(res.stiffness_min, rel=1e-8)
        assert out[4] == pytest.approx(res.deflection_norm, rel=1e-8)
        checked += 1
    assert checked > 80


def test_ups_sspr_near_the_forward_singularity():
    """|Y| -> c (rho -> 0, spec §3.5): the platform can move without deforming anything. Approaching it the
    deflection grows without bound, in step with the reference solver; it stays finite and never NaN."""
    opt = UPS.resolve_options({"l1_limits": None, "l2_limits": None, "l3_limits": None, "Y_range": [-120.0, 120.0]})
    p = UPS.pack(DESIGN, opt)
    prev = 0.0
    for gap in (1e-1, 1e-3, 1e-5):
        pose = (0.1, 0.2, 120.0 - gap)
        out = kernel_fields(p, pose)
        res = solve(UPS.stiffness_model(DESIGN, opt, pose))
        assert out[4] > 10 * prev and out[4] == pytest.approx(res.deflection_norm, rel=1e-6)
        prev = out[4]


def test_ups_sspr_field_grid_equals_the_reference_at_cell_centres():
    """sample_fields over a 5^3 grid of the default workspace: every reachable cell equals the reference solver at the
    cell centre, and evaluate's workspace statistics are theirs."""
    cfg = load_config(ROOT / "configs" / "ups_sspr.yaml", ["grid.resolution=5"])
    design, opt = cfg.resolved_design(), cfg.resolved_options()
    g = make_grid(UPS, design, opt, 5)
    vals = kgrid.sample_fields(UPS.field_kernel, UPS.n_fields, UPS.pack(design, opt), g.lo, g.step, g.shape)
    defl, kmin = [], []
    for idx in np.ndindex(5, 5, 5):
        cell = vals[idx]
        if cell[0] < 0:
            continue
        pose = g.lo + (np.array(idx) + 0.5) * g.step
        res = solve(UPS.stiffness_model(design, opt, pose))
        assert cell[3] == pytest.approx(res.stiffness_min, rel=1e-9)
        assert cell[4] == pytest.approx(res.deflection_norm, rel=1e-9)
        defl.append(res.deflection_norm)
        kmin.append(res.stiffness_min)
    assert len(defl) > 60
    rep = evaluate_config(cfg).to_dict()
    assert rep["max_deflection_mm"] == pytest.approx(max(defl), rel=1e-9)
    assert rep["mean_deflection_mm"] == pytest.approx(np.mean(defl), rel=1e-9)
    assert rep["min_stiffness_min_N_per_mm"] == pytest.approx(min(kmin), rel=1e-9)


def test_tip_bilinear_equals_the_twin_cantilever():
    """legs.tip_bilinear (round sections) is w1^T C w2 with C the NumPy twin's cantilever tip compliance."""
    rng = np.random.default_rng(9)
    for _ in range(20):
        a, b = rng.uniform(-200, 200, 3), rng.uniform(-200, 200, 3)
        C = twin_beam_compliance(a, b, rng.normal(size=3), EA, EIY, EIY, GJ, b)
        w1, w2 = rng.normal(size=6) * [1, 1, 1, 100, 100, 100], rng.normal(size=6) * [1, 1, 1, 100, 100, 100]
        e = (b - a) / np.linalg.norm(b - a)
        got = legs.tip_bilinear(np.linalg.norm(b - a), EA, EIY, GJ, *e, *w1, *w2)
        assert got == pytest.approx(w1 @ C @ w2, rel=1e-10, abs=1e-12 * abs(w1 @ C @ w1))


# ----- seed 001 (pprs-rprs): per-voxel fields (slots 4, 5) against the pose-level model ----------------------------
PPRS_CFG = ROOT / "configs" / "pprs_rprs.yaml"


@pytest.mark.parametrize("opts", [{}, {"sections": {"link": [30.0, 2.5]}, "actuator_stiffness": 5e3,
                                      "beta_stiffness": 3e7, "load": [40.0, -25.0, -150.0]}])
def test_pprs_rprs_fields_equal_the_reference_at_random_poses(opts):
    """Random reachable poses of O1 in the bounding box: stiffness_min and deflection equal the reference solver on
    stiffness_model's frame (rel. 1e-7: measured <= 2e-9, the worst at near-singular poses deflecting ~500 mm where
    both solvers lose digits; ~1e-13 elsewhere)."""
    cfg = load_config(PPRS_CFG)
    mech, design = cfg.mech, cfg.resolved_design()
    opt = mech.resolve_options({**cfg.options, **opts})
    p = mech.pack(design, opt)
    assert mech.field_names[4:6] == ("stiffness_min", "deflection")
    lo, hi = mech.bounding_box(design, opt)
    rng = np.random.default_rng(13)
    out = np.full(mech.n_fields, np.nan)
    checked = 0
    for _ in range(400):
        x = lo + rng.uniform(size=3) * (hi - lo)
        mech.field_kernel(p, *x, out)
        assert not np.any(np.isnan(out))
        if out[0] < 0:
            assert out[4] == 0.0 and out[5] == 0.0
            continue
        res = solve(mech.stiffness_model(design, opt, x))
        assert out[4] == pytest.approx(res.stiffness_min, rel=1e-7)
        assert out[5] == pytest.approx(res.deflection_norm, rel=1e-7)
        checked += 1
        if checked == 60:
            break
    assert checked == 60


def test_pprs_rprs_grid_and_statistics_equal_the_reference():
    cfg = load_config(PPRS_CFG, ["grid.resolution=5"])
    mech, design, opt = cfg.mech, cfg.resolved_design(), cfg.resolved_options()
    g = make_grid(mech, design, opt, 5)
    vals = kgrid.sample_fields(mech.field_kernel, mech.n_fields, mech.pack(design, opt), g.lo, g.step, g.shape)
    defl = []
    for idx in np.ndindex(5, 5, 5):
        if vals[idx][0] < 0:
            continue
        res = solve(mech.stiffness_model(design, opt, g.lo + (np.array(idx) + 0.5) * g.step))
        assert vals[idx][4] == pytest.approx(res.stiffness_min, rel=1e-7)
        assert vals[idx][5] == pytest.approx(res.deflection_norm, rel=1e-7)
        defl.append(res.deflection_norm)
    assert len(defl) > 10
    rep = evaluate_config(cfg).to_dict()
    assert rep["max_deflection_mm"] == pytest.approx(max(defl), rel=1e-7)
    assert rep["mean_deflection_mm"] == pytest.approx(np.mean(defl), rel=1e-7)
