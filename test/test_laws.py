"""Rear-steer laws: registry, defining properties from the paper, low speed, actuator, belief.

Sources: Samsundar (1996) ch. 4 (Solution 1 decouples V, eq. 4.49, time constant 0.58 s;
Sano's zero steady sideslip, eq. 4.13), ch. 6 (RWC 1/2 zero steady sideslip with roll,
Figure 6.3 sign change at low speed, RWC 4 decouples V), and the model matrices of
fourws_sim.models (independent of the laws' closed forms).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from fourws_analysis.linear import closed_loop, steady_state_gains
from fourws_control import LAWS, LawInput, RearSteerActuator, make_law
from fourws_control.rwc_3dof import sign_change_speed_mps, zero_sideslip_gains_3dof
from fourws_sim.errors import (IncompatibleError, NonFiniteError, ParameterError,
                               UnknownNameError)
from fourws_sim.params import load_vehicle

SPEEDS_MPS = (5.0, 12.0, 25.0, 40.0)


@pytest.fixture(scope="module")
def set1():
    return load_vehicle("table_4_1_set_1")


@pytest.fixture(scope="module")
def set2():
    return load_vehicle("table_4_1_set_2")


def test_registry_lists_all_paper_laws_and_rejects_unknown(set1):
    expected = {"fws", "ff_zero_sideslip", "sol1", "sol2", "rwc1_3dof", "rwc2_3dof",
                "rwc4_3dof", "lqr"}
    assert set(LAWS) == expected
    for name in expected:
        assert make_law(name, set1).name == name
    with pytest.raises(UnknownNameError) as err:
        make_law("sol3", set1)
    assert all(n in str(err.value) for n in expected)
    with pytest.raises(ParameterError, match="bogus"):
        make_law("sol1", set1, bogus=1.0)


def test_sol1_decouples_lateral_velocity(set1, set2):
    """Eq. 4.49: with Solution 1 dV/dt = -(Cf+Cr)/(mU) V, no r and no delta_f terms."""
    for v in (set1, set2):
        c, t = v.chassis, v.axle_tires
        for u in SPEEDS_MPS:
            cl = closed_loop("2dof", v, "sol1", u)
            iv, ir = cl.state_index("V"), cl.state_index("R")
            scale = np.abs(cl.A).max()
            assert abs(cl.A[iv, ir]) < 1e-12 * scale
            assert abs(cl.B[iv, 0]) < 1e-12 * np.abs(cl.B).max()
            expected = -(t.cornering_stiffness_front_n_per_rad
                         + t.cornering_stiffness_rear_n_per_rad) / (c.mass_kg * u)
            assert cl.A[iv, iv] == pytest.approx(expected, rel=1e-12)


def test_sol1_lateral_velocity_time_constant_paper_value(set1):
    """Section 4.3: m U/(Cf+Cr) = 0.58 s for data set 1 at 25 m/s."""
    cl = closed_loop("2dof", set1, "sol1", 25.0)
    tau = -1.0 / cl.A[cl.state_index("V"), cl.state_index("V")]
    assert tau == pytest.approx(0.58, rel=0.01)


@pytest.mark.parametrize("law", ["ff_zero_sideslip", "sol1"])
def test_zero_steady_sideslip_on_2dof(set1, set2, law):
    """Eq. 4.13 (Sano) and Solution 1 give zero steady-state sideslip (eq. 4.91)."""
    for v in (set1, set2):
        for u in SPEEDS_MPS:
            g = steady_state_gains(closed_loop("2dof", v, law, u))
            assert abs(g["sideslip/DELTA_F"]) < 1e-12 * abs(g["yaw_rate/DELTA_F"])
            assert g["yaw_rate/DELTA_F"] > 0.0  # the car still turns left for left steer


def test_ff_zero_sideslip_counter_steers_at_low_speed(set1):
    """Eq. 4.13 with Kr = 0: Ksf -> -b/a as U -> 0 and -> a Cf/(b Cr) as U -> inf."""
    c, t = set1.chassis, set1.axle_tires
    law = make_law("ff_zero_sideslip", set1, min_speed_mps=1e-3)
    ksf_low = law.gains(0.01)[0]
    assert ksf_low == pytest.approx(-c.cg_to_rear_axle_m / c.cg_to_front_axle_m, rel=1e-4)
    ksf_high = law.gains(1e4)[0]
    assert ksf_high == pytest.approx(
        c.cg_to_front_axle_m * t.cornering_stiffness_front_n_per_rad
        / (c.cg_to_rear_axle_m * t.cornering_stiffness_rear_n_per_rad), rel=1e-4)


@pytest.mark.parametrize("law", ["rwc1_3dof", "rwc2_3dof"])
def test_rwc1_rwc2_zero_steady_sideslip_on_3dof(set1, set2, law):
    """Eqs. 6.32/6.33: zero steady sideslip of the 3-DOF model with roll and roll steer
    (checked on the model matrices, independent of the closed forms)."""
    for v in (set1, set2):
        for u in SPEEDS_MPS:
            g = steady_state_gains(closed_loop("3dof", v, law, u))
            assert abs(g["sideslip/DELTA_F"]) < 1e-10 * abs(g["yaw_rate/DELTA_F"])


def test_rwc1_reduces_to_ff_zero_sideslip_without_roll_steer(set1):
    """Model levels agree: with eps_f = eps_r = 0 roll does not change the steady slip
    equations, so RWC 1 = Sano's ratio and RWC 2 = eq. 4.14 with Ksf = 0."""
    flat = dataclasses.replace(set1, roll=dataclasses.replace(set1.roll, roll_steer_front=0.0,
                                                               roll_steer_rear=0.0))
    sano = make_law("ff_zero_sideslip", flat)
    kr_family = make_law("ff_zero_sideslip", flat, ksf=0.0)
    for u in SPEEDS_MPS:
        ksf1, kr1 = zero_sideslip_gains_3dof(flat, u)
        assert ksf1 == pytest.approx(sano.gains(u)[0], rel=1e-12)
        assert kr1 * u == pytest.approx(kr_family.gains(u)[1], rel=1e-12)


def test_chapter6_gains_change_sign_at_low_speed(set1):
    """Figure 6.3 (data set 1): Ksf1 and Kr1 are negative at low speed (rear wheels steer
    against the front), positive at high speed, both crossing at the same speed; Kr1 changes
    little compared with Ksf1."""
    u0 = sign_change_speed_mps(set1)
    assert 5.0 < u0 < 85.0
    lo, hi = zero_sideslip_gains_3dof(set1, 5.0), zero_sideslip_gains_3dof(set1, 85.0)
    assert lo[0] < 0.0 and lo[1] < 0.0
    assert hi[0] > 0.0 and hi[1] > 0.0
    at = zero_sideslip_gains_3dof(set1, u0)
    assert abs(at[0]) < 1e-12 and abs(at[1]) < 1e-12
    speeds = np.linspace(5.0, 85.0, 81)
    ksf = np.array([zero_sideslip_gains_3dof(set1, u)[0] for u in speeds])
    kr = np.array([zero_sideslip_gains_3dof(set1, u)[1] for u in speeds])
    assert np.ptp(kr) < 0.1 * np.ptp(ksf)


def test_rwc4_decouples_lateral_velocity_on_3dof(set1, set2):
    """Section 6.2: RWC 4 leaves only the V term in the V equation of the 3-DOF model."""
    for v in (set1, set2):
        for u in SPEEDS_MPS:
            cl = closed_loop("3dof", v, "rwc4_3dof", u)
            iv = cl.state_index("V")
            scale = np.abs(cl.A).max()
            for s in ("R", "PHI", "PHI_DOT"):
                assert abs(cl.A[iv, cl.state_index(s)]) < 1e-9 * scale
            assert abs(cl.B[iv, 0]) < 1e-9 * np.abs(cl.B).max()


def test_rwc4_does_not_apply_to_2dof_models(set1):
    law = make_law("rwc4_3dof", set1)
    for model in ("2dof", "2dof-lagged", "2dof-free"):
        with pytest.raises(IncompatibleError, match="roll"):
            law.linear_gains(model, set1, 20.0)


def test_3dof_laws_need_roll_data():
    v = load_vehicle("table_4_4")
    for name in ("rwc1_3dof", "rwc2_3dof", "rwc4_3dof"):
        with pytest.raises(ParameterError, match="roll"):
            make_law(name, v)


def test_low_speed_fades_to_zero_without_nan(set1):
    """Below min_speed_mps the gains are those of min_speed_mps times U/min_speed_mps."""
    for name in LAWS:
        law = make_law(name, set1)
        umin = law.min_speed_mps
        k_min = law.gains(umin)
        assert np.allclose(law.gains(0.5 * umin), 0.5 * k_min, rtol=1e-12, atol=0.0)
        assert np.all(law.gains(0.0) == 0.0)
        assert np.all(law.gains(-3.0) == 0.0)  # reversing: no rear steer
        inp = LawInput(0.05, 0.0, 0.3, 0.01, 0.02, 0.1)
        assert law(inp) == 0.0
        with pytest.raises(NonFiniteError):
            law(LawInput(0.05, math.nan))


def test_rear_angle_is_the_gain_sum(set1):
    """rear_angle = Ksf delta_f + Kr U r for Solution 1 (Table 4.2)."""
    law = make_law("sol1", set1)
    c, t = set1.chassis, set1.axle_tires
    u, df, r = 20.0, 0.02, 0.1
    cf, cr = t.cornering_stiffness_front_n_per_rad, t.cornering_stiffness_rear_n_per_rad
    kr = (c.mass_kg * u * u + c.cg_to_front_axle_m * cf - c.cg_to_rear_axle_m * cr) / (cr * u * u)
    expected = -cf / cr * df + kr * u * r
    assert law(LawInput(df, u, r, 0.3, 0.1, 0.5)) == pytest.approx(expected, rel=1e-12)


def test_belief_vehicle_breaks_decoupling(set1):
    """A controller that believes 40 % softer tires no longer decouples V on the true car;
    the believed car itself is decoupled."""
    belief = set1.with_axle_tires(0.6)
    law = make_law("sol1", belief)
    true_cl = closed_loop("2dof", set1, law, 25.0)
    believed_cl = closed_loop("2dof", belief, law, 25.0)
    iv, ir = true_cl.state_index("V"), true_cl.state_index("R")
    assert abs(believed_cl.A[iv, ir]) < 1e-12 * np.abs(believed_cl.A).max()
    # the residual coupling equals Cr (Kr_belief - Kr_true) U / m
    c, t = set1.chassis, set1.axle_tires
    cr = t.cornering_stiffness_rear_n_per_rad
    u = 25.0
    kr_true = make_law("sol1", set1).gains(u)[1]
    kr_bel = law.gains(u)[1]
    assert true_cl.A[iv, ir] == pytest.approx(cr * (kr_bel - kr_true) / c.mass_kg, rel=1e-9)


def test_actuator_limits(set1):
    act = RearSteerActuator(set1)
    lim = set1.actuators.rear_angle_limit_rad
    rate = set1.actuators.rear_rate_limit_rad_per_s
    dt = 0.01
    assert act.apply(1.0, dt) == pytest.approx(rate * dt, rel=1e-12)  # rate limited
    for _ in range(1000):
        act.apply(1.0, dt)
    assert act.angle_rad == pytest.approx(lim, rel=1e-12)  # angle limited
    fast = RearSteerActuator(set1, angle_limit_rad=0.1, rate_limit_rad_per_s=math.inf)
    assert fast.apply(-0.5, dt) == -0.1
    with pytest.raises(ParameterError, match="dt_s"):
        act.apply(0.0, 0.0)
    with pytest.raises(ParameterError, match="angle_limit_rad"):
        RearSteerActuator(set1, angle_limit_rad=-1.0)
    with pytest.raises(NonFiniteError):
        act.apply(math.nan, dt)


def test_linear_gains_reject_bad_speed(set1):
    law = make_law("sol1", set1)
    for bad in (0.0, -5.0, math.inf):
        with pytest.raises(ParameterError, match="speed"):
            law.linear_gains("2dof", set1, bad)


@pytest.mark.parametrize("name, options", [("rwc4_3dof", {}), ("lqr", {"model": "3dof",
                                                                       "q_yaw": 1.0}),
                                           ("sol1", {}), ("rwc1_3dof", {})])
def test_call_path_equals_linear_gains_path(set1, name, options):
    """The 100 Hz path (LawInput) and the analysis path (K_x x + K_u u on the 3-DOF model's
    states) give the same rear angle for the same physical state (signs and units agree)."""
    law = make_law(name, set1, **options)
    rng = np.random.default_rng(7)
    for u in (4.0, 23.0, 47.0):
        x = rng.normal(size=4) * np.array([0.5, 0.2, 0.02, 0.1])  # V, r, phi, phi_dot
        delta_f = 0.03
        g = law.linear_gains("3dof", set1, u)
        expected = g.K_x @ x + g.K_u @ np.array([delta_f, 0.0])
        inp = LawInput(delta_f_rad=delta_f, speed_mps=u, yaw_rate_radps=x[1], roll_rad=x[2],
                       roll_rate_radps=x[3], lateral_velocity_mps=x[0])
        assert law(inp) == pytest.approx(expected, rel=1e-12, abs=1e-15)


@pytest.mark.parametrize("name", sorted(LAWS))
def test_call_path_equals_linear_gains_path_on_the_8dof_states(name):
    """The law written in the 8-DOF's state/input order (the order of its linearization,
    fourws_analysis.compare.eightdof_linear_system) gives the 100 Hz path's rear angle for
    any 8-DOF state and input; the states and inputs a law does not measure (speed, wheel
    spin, position, heading, lagged loads and slips, drive and brake torques) get gain 0."""
    from fourws_sim.models import eightdof as m8

    car = load_vehicle("table_8_1")
    law = make_law(name, car)
    s, i = m8.STATE, m8.INPUT
    rng = np.random.default_rng(11)
    for u in (1.0, 23.0):
        g = law.linear_gains("8dof", car, u)
        assert g.state_names == tuple(s.__members__) and g.input_names == tuple(i.__members__)
        x, w = rng.normal(size=len(s)), rng.normal(size=len(i))
        w[i.DELTA_R] = 0.0
        inp = LawInput(delta_f_rad=w[i.DELTA_F], speed_mps=u, yaw_rate_radps=x[s.R],
                       roll_rad=x[s.PHI], roll_rate_radps=x[s.P], lateral_velocity_mps=x[s.V])
        assert law(inp) == pytest.approx(g.K_x @ x + g.K_u @ w, rel=1e-12, abs=1e-15)
        measured = {s.R, s.PHI, s.P, s.V}
        assert not np.any(g.K_x[[j for j in range(len(s)) if j not in measured]])
        assert not np.any(g.K_u[[j for j in range(len(i)) if j != i.DELTA_F]])


def test_laws_are_written_only_for_linear_or_linearized_models(set1):
    """A nonlinear model the analysis does not linearize for the laws (the cubic-tire 2-DOF
    of chapter 7) is refused with the models that are."""
    with pytest.raises(IncompatibleError, match="not linear.*2dof.*linearized: 8dof"):
        make_law("sol1", set1).linear_gains("2dof-cubic", set1, 20.0)
