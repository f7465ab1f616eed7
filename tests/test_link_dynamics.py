"""The links' inverse dynamics along a cycle (scalesynth.dynamics.inverse) against its reference twin
(tests/link_dynamics_twin.py: IK re-solved at every displaced pose, link_geometry per pose), on every mechanism
with link geometry: each mechanism's vectorised link_endpoints equals link_geometry pose by pose, and the actuator
forces of the links agree with the twin's."""

import numpy as np
import pytest

from link_dynamics_twin import link_forces_by_ik
from scalesynth.config import load_config
from scalesynth.cycle import analysis, trajectory
from scalesynth.cycle import config as ccfg
from scalesynth.dynamics import inverse

from conftest import ROOT

CONFIGS = {"planar-fivebar": "fivebar_pnp_cycle", "2pauu-ppap": "paper_2pauu_ppap", "pprs-rprs": "pprs_rprs",
           "rps-upu": "rps_upu", "rps-upu-tool": "rps_upu_tool", "ups-sspr": "ups_sspr", "delta": "delta",
           "linear-delta": "linear_delta"}
SAMPLES = 24


def _cycle(name):
    """(cfg, design, options, traj, label, size, q, A, a_dot) of the config's own design along its cycle."""
    cfg = load_config(ROOT / "configs" / f"{CONFIGS[name]}.yaml")
    mech, d, o = cfg.mech, cfg.resolved_design(), cfg.resolved_options()
    cyc = cfg.cycle.model_copy(update={"samples": SAMPLES})
    traj = trajectory.build(ccfg.vertices(cyc, mech, cfg.units.length), cyc.law, cyc.cycle_time, cyc.samples)
    label = mech.kernel_branch(o)

    def kin(poses):
        return mech.cycle_kinematics(d, o, poses, label)

    size = analysis._size(mech, d, o)
    q, A = kin(traj.p)
    assert np.all(np.isfinite(q))  # the config's design follows its cycle
    a_dot = analysis._a_dot_xdot(kin, mech, traj, size)
    return cfg, cyc, d, o, traj, label, size, q, A, a_dot


@pytest.mark.parametrize("name", CONFIGS)
def test_vectorised_endpoints_equal_link_geometry(name):
    cfg, _, d, o, traj, _, size, q, A, _ = _cycle(name)
    mech = cfg.mech
    assert hasattr(mech, "link_endpoints")  # the search's path is the vectorised one
    # the poses and joint values endpoint_motion evaluates: off the branch by a step along A (not assembled)
    rng = np.random.default_rng(0)
    poses = traj.p + 1e-3 * size * rng.standard_normal(traj.p.shape) * (np.array(mech.task_units) == "length")
    qs = q + 1e-3 * rng.standard_normal(q.shape)
    fast = mech.link_endpoints(d, o, poses, qs).segments()  # (segments, 2, 3, poses)
    for s in range(len(poses)):
        a, b, _ = mech.link_geometry(d, o, poses[s], qs[s]).as_arrays()
        np.testing.assert_allclose(fast[:, 0, :, s], a, rtol=0, atol=1e-12 * size)
        np.testing.assert_allclose(fast[:, 1, :, s], b, rtol=0, atol=1e-12 * size)


@pytest.mark.parametrize("name", CONFIGS)
def test_link_forces_equal_the_reference_twin(name):
    cfg, cyc, d, o, traj, label, size, q, A, a_dot = _cycle(name)
    mech, unit = cfg.mech, cfg.units.length
    cyc._dynamics = None  # tube links of the options' sections: every moving segment has mass
    A_si = analysis.si_velocity_map(mech, A, unit)
    tau, tau_g, F = inverse.link_forces(mech, d, o, cyc, traj, size, q, A, a_dot, A_si, unit, label)
    ref_tau, ref_g, ref_F = link_forces_by_ik(mech, d, o, cyc, traj, label, size, A_si, unit)
    # both are central differences of the same endpoints (steps 1e-5 and 1e-4 of the size); they differ by the
    # second differences' truncation, O(step^2), largest in the twin's, whose path re-solves the IK (linear-delta:
    # 1.7e-7 at step 3e-4, 1.9e-8 at 1e-4, 3e-9 at 3e-5 against this path, which moves by < 1e-9 over those steps),
    # and their rounding (~1e-16 / 1e-8 of the centripetal terms), relative to the links' largest actuator force
    scale = np.max(np.abs(ref_tau))
    assert scale > 0.0
    np.testing.assert_allclose(tau, ref_tau, rtol=0, atol=5e-8 * scale)
    np.testing.assert_allclose(F, ref_F, rtol=0, atol=5e-8 * np.max(np.abs(ref_F)))
    # the gravity part needs first derivatives only (truncation ~1e-10)
    np.testing.assert_allclose(tau_g, ref_g, rtol=0, atol=1e-8 * np.max(np.abs(ref_g)))


def test_p_model_leg_lengths_equal_the_legs_kinematics():
    """rps-upu-tool's closed-form P-model leg lengths (the branch choice of link_endpoints) against _legs."""
    from scalesynth.mechanisms.rps_upu import _legs, _p_leg_lengths

    geom = (120.0, 60.0, 80.0, 150.0)  # g, h, c, e (mm)
    rng = np.random.default_rng(1)
    x = np.column_stack([rng.uniform(100, 300, 50), rng.uniform(-3, 3, 50), rng.uniform(-3, 3, 50)])
    _, q, _ = _legs(geom, "P", "plane", x)
    np.testing.assert_allclose(_p_leg_lengths(geom, x), q, rtol=1e-13)
