# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""Regression pin of the 8-DOF model and its tires (pre-optimization outputs).

Source of every number in this file: the model's own earlier output. The trajectories and tire
forces below were computed with the code of commit ecad847 (before the speed work on the
compiled kernels and the tires) and are pinned here so that a change meant to be a pure
speed-up (algebraic restructuring, compiler options) is proved to leave the results unchanged
to round-off. The physics behind these numbers is tested elsewhere (``test_eightdof.py``,
``test_tires.py``: the paper's tables, model levels, symmetry, conservation); a deliberate
model change must regenerate these pins and say so in its commit.

Tolerances: 1e-12 relative, on a floor of 1e-3 in the state's SI unit (the slip-angle and
roll components are 1e-2 rad and the largest trajectory's sensitivity to a 1e-15 relative
change of its initial speed is 4e-13 relative on that scale), and 1e-12 relative or 1e-9 N
(N m) for single tire evaluations (1e-12 of a 1-kN force).
"""

from __future__ import annotations

import numpy as np
import pytest

from fourws_sim.models import eightdof
from fourws_sim.models.eightdof import INPUT, STATE
from fourws_sim.params import load_vehicle
from fourws_sim.simulator import Simulator

SPEED_85_MPS = 85.0 / 3.6  # the paper's chapter-8 speed
#: Relative tolerance of a pinned value (round-off of a reordered computation).
PIN_RTOL = 1e-12
#: Floor of the scale of a state component (SI units) in the relative comparison.
STATE_SCALE_FLOOR = 1e-3
#: Absolute tolerance of a pinned tire force or moment, N or N m.
TIRE_ATOL = 1e-9

#: Maneuvers from straight running at 85 km/h on table_8_1, inputs held, RK4 1 ms in 10-step
#: ticks: front angle, rear angle (rad), drive and brake torques FL, FR, RL, RR (N m), seconds.
#: No wheel locks (the stick-slip branches are tested in test_eightdof.py).
MANEUVERS = {
    "step_steer": (0.01, 0.0, (0.0,) * 4, (0.0,) * 4, 2.0),
    "brake_in_turn": (0.015, -0.002, (0.0,) * 4, (250.0, 250.0, 150.0, 150.0), 1.0),
    "drive_in_turn": (0.02, 0.0, (0.0, 0.0, 150.0, 180.0), (0.0,) * 4, 1.5),
}

#: Final 8-DOF state (``eightdof.STATE`` order) of each maneuver, per tire model.
TRAJ = {
    ('sti', 'step_steer'): [
        23.454082601078042, -0.5700514547448852, 0.1710215998079132,
        0.03391075809846357, 0.0012884918590366653, 80.43961631103548,
        81.27086404032903, 80.5078316940622, 81.31966213193553,
        46.71606363270468, 4.862693610851673, 0.2794099864883999,
        -0.020540749579683663, 3.980892868807166, -0.033855639980190304,
        -0.03367888263542987, -0.028236903885164828, -0.027879442961839508,
    ],
    ('sti', 'brake_in_turn'): [
        21.58067416395165, -1.189401640199769, 0.3202262441241334,
        0.04639743436508507, 0.023302688734857097, 66.39107674259685,
        73.16220678704063, 61.142154847953016, 73.29098257711948,
        22.6004698579145, 1.2161790041192793, 0.2049002290190956,
        -1.8800423561040829, 5.544466511344312, -0.06373538531458996,
        -0.06294026862622183, -0.06451746415335781, -0.06300340264285899,
    ],
    ('sti', 'drive_in_turn'): [
        24.377277448087753, -1.3838177878940954, 0.25918023794634776,
        0.051409879992407696, 0.0032623064585446185, 83.1028969479354,
        84.51581754838595, 95.5850061643269, 87.16084977726966,
        35.699468997137394, 4.221835284877416, 0.34099382417361557,
        0.7401268247687153, 6.043294136059071, -0.07652830331785634,
        -0.07583369370643817, -0.06216657369352134, -0.06109348584703114,
    ],
    ('magic_formula', 'step_steer'): [
        23.442877484446168, -0.6844180549145001, 0.17004469528449828,
        0.03347659771201426, 0.0021641583666462782, 80.38452079585252,
        81.21822564058856, 80.45511002845839, 81.27409433172849,
        46.78460832996727, 4.369645120993071, 0.2667121934590129,
        -0.01954966624882523, 3.9333825537320495, -0.03870140589578414,
        -0.0384749605722016, -0.0331577880399468, -0.03275348850089145,
    ],
    ('magic_formula', 'brake_in_turn'): [
        21.506034281910487, -1.1483302842986713, 0.3136084970684659,
        0.04773937410038445, 0.02886021000121276, 71.1074164378332,
        74.32698255121525, 68.57060277075642, 74.43827340153115,
        22.558069525767387, 1.124319760473968, 0.19806328731419592,
        -1.9561620617701707, 5.717662028843386, -0.06275821231514513,
        -0.061996202944032644, -0.06247777214225534, -0.06101704724471254,
    ],
    ('magic_formula', 'drive_in_turn'): [
        24.488608248479352, -1.1747437484102894, 0.24179210093582723,
        0.04928588305897841, 0.0027541302859795955, 83.66251906721895,
        84.89637721344903, 86.93036663286061, 85.72700519191041,
        35.84102703530909, 3.805956383802625, 0.31015353523030526,
        0.7568484675606282, 5.789690680467553, -0.06810967758150323,
        -0.0675747112992667, -0.05272956916673412, -0.05186670734872194,
    ],
    ('linear', 'step_steer'): [
        23.48330064351254, -0.654794672559965, 0.13670885790979265,
        0.02685040625707228, 0.0021398519945726624, 80.60721798525537,
        81.28094596265133, 80.6643505224871, 81.328659803744,
        46.941869337473705, 3.395154721249308, 0.21428181906338922,
        -0.014441167204504125, 3.1562058848581787, -0.0374747966115675,
        -0.03729208192149975, -0.03104568099609307, -0.030748920670960366,
    ],
    ('linear', 'brake_in_turn'): [
        21.572809221987693, -0.7086787146909223, 0.1831245134339133,
        0.03169189314297668, 0.012501998449409355, 72.65528093233321,
        73.5414950575176, 73.11825431023554, 73.99825115989663,
        22.599067721509407, 0.7899500462354683, 0.13249062516757076,
        -2.004337065885853, 3.7438573708600216, -0.045582266577725294,
        -0.04529403249443551, -0.036795633660779266, -0.03626590287873533,
    ],
    ('linear', 'drive_in_turn'): [
        24.42801434444901, -1.8066837309067147, 0.27649021811343416,
        0.04814173705233814, 0.01075390928527745, 83.34101909213267,
        84.71228565839556, 86.05857658352798, 86.26065805449124,
        35.91529011400159, 3.3302076861977605, 0.31224120042676146,
        0.7637161180178038, 5.70222482909861, -0.09194434715573484,
        -0.09095880571043873, -0.08051743659375749, -0.07911077268780511,
    ],
}


#: Tire inputs (Fz N, alpha rad, kappa, mu) covering the branches of the tires: zero slip,
#: pure and combined slip, loads beyond the STI stiffness vertex, locked and spinning wheels,
#: alpha of 90 deg, reduced friction, zero friction and no load. Front coefficients of
#: table_8_1 (sti: Table C.1); vx = 20 m/s (unused by both tires).
POINTS = [
    (4000.0, 0.0, 0.0, 1.0),
    (4000.0, -0.02, 0.0, 1.0),
    (4000.0, 0.05, 0.01, 1.0),
    (3000.0, -0.1, -0.05, 1.0),
    (5500.0, 0.2, 0.1, 1.0),
    (8000.0, -0.05, -0.2, 1.0),
    (2000.0, 0.3, -1.0, 1.0),
    (4000.0, 0.0, -1.0, 1.0),
    (4000.0, 0.0, 2.5, 1.0),
    (6000.0, 1.3, 0.0, 1.0),
    (4000.0, -0.08, 0.02, 0.4),
    (200.0, 0.01, 0.001, 1.0),
    (4000.0, -1.5707963267948966, 0.0, 1.0),
    (4000.0, 0.03, 0.0, 0.0),
    (-10.0, 0.1, 0.1, 1.0),
]

#: (Fx N, Fy N, Mz N m) of the compiled tire at POINTS.
TIRE = {
    'sti': [
        (0.0, 0.0, 0.0,),
        (0.0, 1091.4736928326588, -18.056351432049848,),
        (201.006310008862, -2235.0653388453366, 24.417660856759294,),
        (-499.6812578594189, 2260.198156002093, 11.712439033671947,),
        (1285.0725621207043, -4214.653526071322, 77.90304859623741,),
        (-5349.993707027763, 1711.468682583718, 116.78960165974675,),
        (-1407.777819067787, -435.47671083404407, -8.325568107494108,),
        (-2945.0948005225855, -0.0, 0.0,),
        (2952.9278662291827, -0.0, 0.0,),
        (0.0, -4471.611905679882, 0.5662396072478207,),
        (152.85894389573895, 1308.6249706309275, -3.4179885721572494,),
        (1.177123550736087, -66.37012661129938, 0.22148834490153654,),
        (0.0, 2978.399999999999, -0.0,),
        (0.0, 0.0, 0.0,),
        (0.0, 0.0, 0.0,),
    ],
    'magic_formula': [
        (0.0, 0.0, 0.0,),
        (0.0, 911.54654069121, -27.926849754074745,),
        (702.3206720478058, -2141.4544002526754, 56.13613195466493,),
        (-1554.9149517174549, 2544.6036140718334, -21.15971966440375,),
        (2752.93025803385, -4486.350512959499, -11.013199325926957,),
        (-8531.226331455951, 1643.1932469971196, 18.030495669864138,),
        (-1541.9709960382384, -288.65387682494685, -1.0176444626433585,),
        (-3192.400030808188, 0.0, 0.0,),
        (2689.6038084291517, 0.0, 0.0,),
        (0.0, -5330.741521892125, -15.807654162843646,),
        (927.166708416767, 1561.4806014601734, -29.463241426260836,),
        (3.402176539827955, -27.93526776049593, 0.04392721218753531,),
        (0.0, 3824.6272337360137, 1.804840430097567e-15,),
        (0.0, 0.0, 0.0,),
        (0.0, 0.0, 0.0,),
    ],
}


def _run(tire: str, maneuver: str) -> np.ndarray:
    front, rear, drive, brake, seconds = MANEUVERS[maneuver]
    sim = Simulator(load_vehicle("table_8_1"), tire=tire)
    sim.reset(speed_mps=SPEED_85_MPS)
    u = np.zeros(len(INPUT))
    u[INPUT.DELTA_F] = front
    u[INPUT.DELTA_R] = rear
    u[INPUT.DRIVE_FL:INPUT.DRIVE_RR + 1] = drive
    u[INPUT.BRAKE_FL:INPUT.BRAKE_RR + 1] = brake
    for _ in range(int(round(seconds / (10 * sim.dt_s)))):
        sim.step(u, 10)
    return sim.state


@pytest.mark.parametrize(("tire", "maneuver"), sorted(TRAJ))
def test_trajectory_matches_the_pre_optimization_model(tire: str, maneuver: str) -> None:
    """Regression pin: the compiled RK4 path reproduces the earlier model's final state. The
    pins hold the 18 states of that model; the free steering system's two states, added since,
    stay exactly 0 with fixed steering control (the model ``8dof``)."""
    state = _run(tire, maneuver)
    pin = np.array(TRAJ[(tire, maneuver)])
    got = state[:pin.size]
    assert pin.size == STATE.DELTA_S
    assert state[STATE.DELTA_S] == 0.0 and state[STATE.DELTA_S_RATE] == 0.0
    scale = np.maximum(np.abs(pin), STATE_SCALE_FLOOR)
    worst = float(np.max(np.abs(got - pin) / scale))
    assert worst <= PIN_RTOL, f"worst relative deviation {worst:.3g}"


@pytest.mark.parametrize("tire", sorted(TIRE))
def test_compiled_tire_matches_the_pre_optimization_model(tire: str) -> None:
    """Regression pin: the tire function compiled into the kernels gives the earlier forces."""
    compiled = eightdof.kernel_module(tire)._tire  # the variant module holds it
    p = eightdof.params_for(load_vehicle("table_8_1"), tire)
    got = np.array([compiled(fz, alpha, kappa, 20.0, mu, p.coeffs_front)
                    for fz, alpha, kappa, mu in POINTS])
    np.testing.assert_allclose(got, np.array(TIRE[tire]), rtol=PIN_RTOL, atol=TIRE_ATOL)


def test_interleaved_sti_tires_equal_four_scalar_calls_exactly() -> None:
    """The 8-DOF kernels evaluate the STI tires of the four wheels interleaved (``forces4``):
    bit for bit the numbers of four ``forces`` calls (compiled and plain Python), so the
    speed-up cannot change a result."""
    kernels = eightdof.kernel_module("sti")
    module = eightdof.params_for(load_vehicle("table_8_1"), "sti").tire
    cf = module.pack_mapping({})
    cr = module.pack_mapping({"fzt_lb": 900.0, "ka": 0.2})  # rear differs from the front
    rng = np.random.default_rng(4)
    rows = [np.array(point[:3]) for point in POINTS]
    rows += [np.array([rng.uniform(-500.0, 9000.0), rng.uniform(-1.6, 1.6),
                       rng.choice([0.0, rng.uniform(-1.0, 1.0), rng.uniform(-3.0, 3.0)])])
             for _ in range(200)]
    for start in range(0, len(rows) - 3, 4):
        block = np.array(rows[start:start + 4])
        fz, alpha, kappa = block[:, 0].copy(), block[:, 1].copy(), block[:, 2].copy()
        vx = np.full(4, 20.0)
        for mu, forces4 in ((0.8, kernels._forces4), (1.0, module.forces4)):
            out = np.full((3, 4), np.nan)
            forces4(fz, alpha, kappa, vx, mu, cf, cr, out[0], out[1], out[2])
            scalar = kernels._tire if forces4 is kernels._forces4 else module.forces
            ref = np.array([scalar(fz[i], alpha[i], kappa[i], 20.0, mu, cf if i < 2 else cr)
                            for i in range(4)]).T
            assert np.array_equal(out, ref), (block, out - ref)


def test_vector_fast_path_checks_like_the_general_path() -> None:
    """``Simulator.step`` with a float64 vector (its fast path) rejects what ``input_vector``
    rejects, names the component, and steps exactly like a list input (general path)."""
    from fourws_sim.errors import NonFiniteError, ParameterError

    sim = Simulator(load_vehicle("table_8_1"))
    sim.reset(speed_mps=SPEED_85_MPS)
    u = np.zeros(len(INPUT))
    u[INPUT.BRAKE_RL] = -1.0
    with pytest.raises(ParameterError, match=r"brake_torque_nm\[RL\]"):
        sim.step(u, 10)
    u[INPUT.BRAKE_RL] = 0.0
    u[INPUT.DRIVE_FR] = np.nan
    with pytest.raises(NonFiniteError, match=r"drive_torque_nm\[FR\]"):
        sim.step(u, 10)
    assert sim.step_count == 0
    u[INPUT.DRIVE_FR] = 50.0
    u[INPUT.DELTA_F] = 0.02
    other = Simulator(load_vehicle("table_8_1"))
    other.reset(speed_mps=SPEED_85_MPS)
    for _ in range(20):
        sim.step(u, 10)
        other.step(u.tolist(), 10)
    assert np.array_equal(sim.state, other.state)
    assert sim.step_count == other.step_count == 200
    u[INPUT.DELTA_F] = 0.5  # the caller reusing its vector does not change the held input
    mine, ref = sim.outputs(), other.outputs()
    for name in ("front_wheel_angle_rad", "lateral_accel_mps2", "yaw_rate_radps"):
        assert mine[name] == ref[name], name
    eps_f = eightdof.params_for(sim.vehicle).arr[eightdof.PARAM.EPS_F]  # roll steer
    assert mine["front_wheel_angle_rad"] == pytest.approx(0.02 + eps_f * sim.state[STATE.PHI],
                                                          rel=1e-12)


def _lane_module():  # type: ignore[no-untyped-def]
    module = eightdof.lane_kernels_for("sti")
    assert module is not None and module.HAS_LANES
    return module


def test_sti_lane_function_equals_forces_bit_for_bit() -> None:
    """``forces_lane`` (branch-free, for the batch kernel) gives ``forces``'s numbers bit for
    bit (compiled: it divides by zero where ``forces`` takes another branch, which plain
    Python refuses), over loads, slip angles and slip ratios that take
    every branch of ``forces``: no load, negative load, no friction, no slip (g = 0), pure
    side slip (one pass), combined slip (two passes), sliding beyond the saturation's vertex
    (sigma > 1), a locked and a spinning wheel; front and rear coefficients differ."""
    import numba

    from fourws_sim.lanes import LANES
    from fourws_sim.tires import sti

    cf = sti.pack_mapping({})
    cr = sti.pack_mapping({"fzt_lb": 900.0, "ka": 0.2, "kmu": 0.3})
    rng = np.random.default_rng(11)
    rows = [(0.0, 0.1, 0.0, 1.0), (-50.0, 0.1, 0.0, 1.0), (3000.0, 0.1, 0.0, 0.0),
            (3000.0, 0.0, 0.0, 1.0), (3000.0, 0.05, 0.0, 1.0), (3000.0, 0.05, -0.1, 1.0),
            (3000.0, 1.2, 0.0, 0.6), (3000.0, 0.02, -1.0, 1.0), (3000.0, 0.02, 4.0, 1.0)]
    rows += [(rng.uniform(-500.0, 9000.0), rng.uniform(-1.6, 1.6),
              rng.choice([0.0, rng.uniform(-1.0, 1.0), rng.uniform(-3.0, 3.0)]),
              rng.choice([0.0, 0.5, 1.0])) for _ in range(400)]
    flat = np.zeros(2 * sti.N_COEFFS * LANES)
    for k in range(sti.N_COEFFS):
        flat[k * LANES:(k + 1) * LANES] = cf[k]
        flat[(sti.N_COEFFS + k) * LANES:(sti.N_COEFFS + k + 1) * LANES] = cr[k]
    lane = numba.njit(error_model="numpy")(
        lambda fz, al, ka, mu, c, base, ln: sti.forces_lane(fz, al, ka, mu, c, base, ln))
    for i, (fz, alpha, kappa, mu) in enumerate(rows):
        for base, coeffs in ((0, cf), (sti.N_COEFFS, cr)):
            want = np.array(sti.forces(fz, alpha, kappa, 20.0, mu, coeffs))
            got = np.array(lane(fz, alpha, kappa, mu, flat, base, i % LANES))
            assert got.tobytes() == want.tobytes(), (fz, alpha, kappa, mu, got - want)


def _lanes_case(module, rng):  # type: ignore[no-untyped-def]
    """A lane array of states of the kinds a study meets: straight running at several speeds,
    perturbed states with drive and brake torques, a held wheel, an unloaded wheel, a slowly
    rolling scale car (its light wheels need sub-steps), and one non-finite state. Returns
    each lane's parameters, the lane array, states and inputs."""
    from fourws_sim.lanes import LANES

    car = eightdof.params_for(load_vehicle("table_8_1"), "sti")
    scale_car = eightdof.params_for(load_vehicle("f1tenth"), "sti")
    IN = np.zeros(module.N_IN * LANES)
    params, states, inputs = [], [], []
    for ln in range(LANES):
        p = scale_car if ln == 3 else car
        x = eightdof.initial_state(p, 8.0 + 3.0 * ln)
        x = x + rng.normal(0.0, 0.02, x.size) * np.maximum(np.abs(x), 0.1)
        u = np.zeros(eightdof.N_INPUT)
        u[INPUT.DELTA_F] = rng.normal(0.0, 0.05)
        u[INPUT.DELTA_R] = rng.normal(0.0, 0.01)
        u[INPUT.DRIVE_FL] = rng.uniform(0.0, 300.0)
        u[INPUT.BRAKE_RL] = rng.uniform(0.0, 300.0)
        if ln == 1:
            x[STATE.OMEGA_FL] = 0.0  # a held wheel
        if ln == 2:
            x[STATE.AY_LT] = 60.0  # the inner wheels lift off
        if ln == 3:
            x = eightdof.initial_state(p, 0.3)  # light wheels rolling slowly: sub-steps
        if ln == 4:
            x[STATE.V] = np.nan
        module.pack_lane(IN, ln, x, u, p.arr, p.coeffs_front, p.coeffs_rear)
        params.append(p)
        states.append(x)
        inputs.append(u)
    return params, IN, states, inputs


def test_lane_right_hand_side_equals_the_scalar_one_bit_for_bit() -> None:
    """``rhs_lanes`` (the vectorized right-hand side of the study's batch kernel) gives each
    lane exactly ``rhs``'s derivatives, slip rate, accelerations and applied road-wheel
    angles (a tick's outputs)."""
    from fourws_sim.lanes import LANES

    module = _lane_module()
    kernels = eightdof.kernels_for("sti")
    params, IN, states, inputs = _lanes_case(module, np.random.default_rng(5))
    OUT = np.zeros(module.N_OUT * LANES)
    module.rhs_lanes(IN, OUT)
    for ln in range(LANES):
        dx = np.zeros(eightdof.N_STATE)
        aux = np.zeros(eightdof.N_AUX)
        p = params[ln]
        kernels.rhs(states[ln], inputs[ln], p.arr, p.coeffs_front, p.coeffs_rear, dx, aux)
        got = OUT[ln:eightdof.N_STATE * LANES:LANES]
        assert got.tobytes() == dx.tobytes(), ln
        rate = OUT[module.R_RATE * LANES + ln]
        assert rate == aux[eightdof._AUX_RATE] or (np.isnan(rate) and ln == 4)
        for row, slot in ((module.R_AX, eightdof._AUX_AX), (module.R_AY, eightdof._AUX_AY),
                          (module.R_DF, eightdof._AUX_DELTA_F),
                          (module.R_DR, eightdof._AUX_DELTA_R)):
            got, want = OUT[row * LANES + ln], aux[slot]
            assert np.array([got]).tobytes() == np.array([want]).tobytes(), (ln, row)


def test_lane_rk4_equals_the_scalar_rk4_bit_for_bit() -> None:
    """``rk4_lanes`` advances each lane exactly as ``rk4`` advances its state, through a step
    taken in sub-steps (the slow lane) and with a lane whose state is not finite (it stops,
    its state stays as it was, the others go on)."""
    from fourws_sim.lanes import LANES

    module = _lane_module()
    kernels = eightdof.kernels_for("sti")
    params, IN, states, inputs = _lanes_case(module, np.random.default_rng(6))
    p = params[0]
    X = np.zeros(eightdof.N_STATE * LANES)
    for ln in range(LANES):
        X[ln::LANES] = states[ln]
    active = np.ones(LANES, dtype=np.int64)
    work = np.zeros((6, eightdof.N_STATE))
    n_steps = 25
    left = module.rk4_lanes(
        X, IN, np.zeros(module.N_OUT * LANES), np.zeros((4, eightdof.N_STATE * LANES)),
        np.zeros(eightdof.N_STATE * LANES), np.zeros(LANES), active, 1e-3, n_steps,
        np.zeros(eightdof.N_STATE), np.zeros(eightdof.N_INPUT), np.zeros(p.arr.size),
        np.zeros(p.coeffs_front.size), np.zeros(p.coeffs_rear.size), work,
        np.zeros(eightdof.N_AUX))
    assert left == LANES - 1 and active[4] == 0
    for ln in range(LANES):
        x = states[ln].copy()
        p = params[ln]
        done = kernels.rk4(x, inputs[ln], p.arr, p.coeffs_front, p.coeffs_rear, 1e-3, n_steps)
        assert done == (0 if ln == 4 else n_steps)
        got = X[ln::LANES]
        assert got.tobytes() == x.tobytes() or (ln == 4 and np.isnan(got[STATE.V])), ln
    # the slow lane's steps did go through sub-steps (the scalar path the lanes hand over to)
    dx = np.zeros(eightdof.N_STATE)
    aux = np.zeros(eightdof.N_AUX)
    p = params[3]
    kernels.rhs(states[3], inputs[3], p.arr, p.coeffs_front, p.coeffs_rear, dx, aux)
    assert eightdof.substeps(aux[eightdof._AUX_RATE], 1e-3, "rk4") > 1
