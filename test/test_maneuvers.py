# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""Maneuver inputs against their analytic definitions, the drivers' laws, the ISO 3888-2 track,
and the validation of maneuver files."""

from __future__ import annotations

import functools
import math
from pathlib import Path

import numpy as np
import pytest
from scipy import signal

from fourws_control import available_laws
from fourws_run.closed_loop import run_closed_loop
from fourws_sim.corridor import MARGIN_BACKOFF_M, clearance, plan_corridor_path
from fourws_sim.drivers import (CirclePath, PathDriverSpec, PathTrackingDriver,
                                PreviewPathDriver, SpeedHoldDriver, SpeedHoldSpec, SplinePath,
                                TrackingDriverSpec)
from fourws_sim.errors import ParameterError, UnknownNameError
from fourws_sim.maneuvers import (MANEUVER_TYPES, available_maneuvers, load_maneuver_spec,
                                  make_maneuver, maneuver_spec_from_mapping)
from fourws_sim.params import GRAVITY_MPS2, load_vehicle

VEHICLE = "table_4_4"  # has a steering ratio (Table 4.4) for the hand-wheel conversion
STILL = {"speed_mps": 20.0, "x_m": 0.0, "y_m": 0.0, "heading_rad": 0.0,
         "lateral_accel_mps2": 0.0}


def _vehicle():
    return load_vehicle(VEHICLE)


def _front(man, times):
    return np.array([man.command(float(t), STILL).front_wheel_angle_rad for t in times])


def test_every_type_has_a_shipped_file_that_loads_and_round_trips() -> None:
    specs = [load_maneuver_spec(name) for name in available_maneuvers()]
    assert {s.type for s in specs} == set(MANEUVER_TYPES)
    for spec in specs:
        again = load_maneuver_spec(spec.to_dict())
        assert again.to_dict() == spec.to_dict()
    assert load_maneuver_spec("step_steer_85kmh").initial_speed_mps == pytest.approx(85 / 3.6)


def test_step_steer_amplitude_and_ramp() -> None:
    """ISO 7401 step: 0 before, linear ramp, held amplitude; 10-90 % rise within 0.15 s."""
    spec = load_maneuver_spec("step_steer_85kmh")
    p = spec.params
    man = make_maneuver(spec, _vehicle())
    t = np.array([0.0, p.start_s - 1e-3, p.start_s + 0.5 * p.ramp_time_s,
                  p.start_s + p.ramp_time_s, spec.duration_s - 0.01])
    np.testing.assert_allclose(_front(man, t), [0.0, 0.0, 0.5 * p.amplitude_rad,
                                                p.amplitude_rad, p.amplitude_rad], rtol=1e-12)
    fine = np.arange(0.0, 2.0, 1e-4)
    y = np.array([p.steer(x) for x in fine]) / p.amplitude_rad
    rise = fine[np.argmax(y >= 0.9)] - fine[np.argmax(y >= 0.1)]
    assert rise == pytest.approx(0.8 * p.ramp_time_s, abs=2e-4)
    assert rise <= 0.15


def test_hand_wheel_input_is_divided_by_the_steering_ratio() -> None:
    vehicle = _vehicle()
    data = load_maneuver_spec("step_steer_85kmh").to_dict()
    data.update(steer_input="steering_wheel", amplitude_rad=0.5)
    man = make_maneuver(data, vehicle)
    cmd = man.command(3.0, STILL)
    assert cmd.steering_wheel_angle_rad == pytest.approx(0.5, rel=1e-12)
    assert cmd.front_wheel_angle_rad == pytest.approx(0.5 / vehicle.steering.ratio, rel=1e-12)
    road = make_maneuver("step_steer_85kmh", vehicle).command(3.0, STILL)
    assert road.steering_wheel_angle_rad == pytest.approx(
        road.front_wheel_angle_rad * vehicle.steering.ratio, rel=1e-12)


def test_ramp_steer_rate() -> None:
    spec = load_maneuver_spec("ramp_steer")
    p = spec.params
    man = make_maneuver(spec, _vehicle())
    t0 = p.start_s + 0.1
    y = _front(man, [t0, t0 + 0.2])
    assert (y[1] - y[0]) / 0.2 == pytest.approx(p.rate_radps, rel=1e-9)
    assert _front(man, [p.start_s + p.ramp_time_s + 1.0])[0] == pytest.approx(p.amplitude_rad)


def test_single_sine_is_one_period() -> None:
    spec = load_maneuver_spec("sine")
    p = spec.params
    t = np.arange(0.0, spec.duration_s, 1e-4)
    y = np.array([p.steer(x) for x in t])
    period = 1.0 / p.frequency_hz
    assert y.max() == pytest.approx(p.amplitude_rad, rel=1e-6)
    assert t[np.argmax(y)] == pytest.approx(p.start_s + 0.25 * period, abs=2e-4)
    assert np.trapezoid(y, t) == pytest.approx(0.0, abs=1e-6 * p.amplitude_rad)
    assert np.all(y[t > p.start_s + period + 1e-3] == 0.0)


@pytest.mark.parametrize("spacing", ["logarithmic", "linear"])
def test_chirp_instantaneous_frequency(spacing: str) -> None:
    """Half-periods between zero crossings equal 1 / (2 f(t)) of the analytic sweep law."""
    data = load_maneuver_spec("swept_sine").to_dict()
    data["spacing"] = spacing
    p = load_maneuver_spec(data).params
    t = np.arange(p.start_s, p.start_s + p.sweep_time_s, 1e-4)
    y = np.array([p.steer(x) for x in t])
    idx = np.nonzero(np.diff(np.signbit(y)))[0][1:]
    # linear interpolation of each crossing
    tc = t[idx] - y[idx] * (t[idx + 1] - t[idx]) / (y[idx + 1] - y[idx])
    f_measured = 0.5 / np.diff(tc)
    tau = 0.5 * (tc[1:] + tc[:-1]) - p.start_s
    if spacing == "linear":
        f_law = p.f_start_hz + (p.f_end_hz - p.f_start_hz) * tau / p.sweep_time_s
    else:
        f_law = p.f_start_hz * (p.f_end_hz / p.f_start_hz) ** (tau / p.sweep_time_s)
    np.testing.assert_allclose(f_measured, f_law, rtol=5e-3)
    # zero crossings over the sweep: 2 per period, 2 * integral of f(tau) over [0, T]
    if spacing == "linear":
        periods = 0.5 * (p.f_start_hz + p.f_end_hz) * p.sweep_time_s
    else:
        periods = ((p.f_end_hz - p.f_start_hz) * p.sweep_time_s
                   / math.log(p.f_end_hz / p.f_start_hz))
    assert abs(len(idx) + 2 - 2.0 * periods) <= 1.0
    assert f_measured[-1] == pytest.approx(p.f_end_hz, rel=0.02)
    assert np.abs(y).max() == pytest.approx(p.amplitude_rad, rel=1e-3)


def test_random_steer_power_is_inside_its_band() -> None:
    spec = load_maneuver_spec("random_steer")
    p = spec.params
    man = make_maneuver(spec, _vehicle())
    fs = 100.0  # the control rate the maneuver is sampled at
    t = np.arange(p.start_s + p.fade_s, p.start_s + p.length_s, 1.0 / fs)
    y = _front(man, t)
    freqs, psd = signal.welch(y, fs=fs, nperseg=2048)
    df = freqs[1] - freqs[0]
    # the Hann window's main lobe spreads a line over +-2 bins: the band edges get that margin
    inside = (freqs >= p.f_low_hz - 2 * df) & (freqs <= p.f_high_hz + 2 * df)
    frac_in = psd[inside].sum() / psd.sum()
    assert frac_in > 0.999
    # the band power is the variance: rms as specified (brick-wall filtered, exact scaling)
    assert math.sqrt(psd[inside].sum() * df) == pytest.approx(p.rms_rad, rel=0.1)
    assert np.sqrt(np.mean(y * y)) == pytest.approx(p.rms_rad, rel=0.05)
    # seeded: same seed, same input; another seed, another input
    again = _front(make_maneuver(spec, _vehicle()), t[:200])
    np.testing.assert_array_equal(again, y[:200])
    other = dict(spec.to_dict(), seed=p.seed + 1)
    assert not np.allclose(_front(make_maneuver(other, _vehicle()), t[:200]), y[:200])


@pytest.mark.parametrize("shape,area_factor", [("triangle", 0.5), ("half_sine", 2 / math.pi)])
def test_pulse_area(shape: str, area_factor: float) -> None:
    data = dict(load_maneuver_spec("pulse").to_dict(), shape=shape)
    p = load_maneuver_spec(data).params
    t = np.linspace(0.0, 2.0, 200001)
    y = np.array([p.steer(x) for x in t])
    assert np.trapezoid(y, t) == pytest.approx(area_factor * p.amplitude_rad * p.width_s,
                                               rel=1e-6)
    assert y.max() == pytest.approx(p.amplitude_rad, rel=1e-4)


def test_speed_hold_torque_law() -> None:
    """First call (empty integrator): T = m R (kp e + f_r g), on the driven axle only;
    a speed above target brakes with the front/rear split."""
    vehicle = load_vehicle("table_8_1")
    spec = SpeedHoldSpec(kp_per_s=2.0, ki_per_s2=1.0, driven_axle="rear")
    driver = SpeedHoldDriver(spec, vehicle)
    m, r = vehicle.chassis.mass_kg, vehicle.body.wheel_radius_m
    fr = vehicle.tire.rolling_resistance if vehicle.tire is not None else 0.0
    drive, brake = driver.command(0.0, 20.0, 20.5)
    total = m * r * (2.0 * 0.5 + fr * GRAVITY_MPS2)
    assert drive[0] == drive[1] == 0.0
    assert drive[2] + drive[3] == pytest.approx(total, rel=1e-12)
    assert sum(brake) == 0.0
    # integrator after 0.1 s of 0.5 m/s error: ki * 0.05 m added
    drive, _ = driver.command(0.1, 20.0, 20.5)
    assert sum(drive) == pytest.approx(m * r * (1.0 + 0.05 + fr * GRAVITY_MPS2), rel=1e-12)
    fresh = SpeedHoldDriver(spec, vehicle)
    drive, brake = fresh.command(0.0, 21.0, 20.0)
    assert sum(drive) == 0.0
    assert sum(brake) == pytest.approx(m * r * (2.0 - fr * GRAVITY_MPS2), rel=1e-12)
    assert (brake[0] + brake[1]) / sum(brake) == pytest.approx(spec.brake_front_fraction)


def test_preview_driver_on_the_circle_steers_its_curvature() -> None:
    """On the circle, tangent to it, the pure-pursuit arc is the circle itself (chord
    geometry): delta = (L + K U^2) / R for any preview distance."""
    vehicle = load_vehicle("table_5_1")
    radius, speed = 40.0, 12.0
    for direction in (1, -1):
        path = CirclePath(radius, direction)
        # yaw-rate feedback on: on the circle at r = U / R there is no shortfall to correct
        driver = PreviewPathDriver(PathDriverSpec(yaw_rate_gain_s=0.3), vehicle, path)
        angle = 0.7  # any point of the circle, heading tangent
        cx, cy = path.centre
        x = cx + radius * math.cos(direction * (angle - math.pi / 2))
        y = cy + radius * math.sin(direction * (angle - math.pi / 2))
        delta = driver.steer(0.0, {"x_m": x, "y_m": y, "heading_rad": direction * angle,
                                   "speed_mps": speed, "yaw_rate_radps": direction * speed
                                   / radius})
        expected = (vehicle.chassis.wheelbase_m
                    + vehicle.understeer_gradient_rad_per_mps2 * speed ** 2) / radius
        assert delta == pytest.approx(direction * expected, rel=1e-9)


def test_iso_3888_2_track() -> None:
    """Section lengths 12/11/12 m, gaps 13.5/12.5 m (61 m in all), widths 1.1W+0.25, W+1,
    max(1.3W+0.25, 3), side lane 1 m left of section 1, exit lane's right edge in line with
    the entry lane's (ISO 3888-2:2011, Table 1)."""
    for width in (1.7, 2.3):
        data = dict(load_maneuver_spec("double_lane_change").to_dict(), vehicle_width_m=width)
        p = load_maneuver_spec(data).params
        (a0, a1, ar, al), (b0, b1, br, bl), (c0, c1, cr, cl) = p.sections
        assert (a1 - a0, b0 - a1, b1 - b0, c0 - b1, c1 - c0) == pytest.approx(
            (12.0, 13.5, 11.0, 12.5, 12.0))
        assert c1 - a0 == pytest.approx(61.0)
        assert a0 == pytest.approx(p.approach_m)
        assert (al - ar, bl - br, cl - cr) == pytest.approx(
            (1.1 * width + 0.25, width + 1.0, max(1.3 * width + 0.25, 3.0)))
        assert br - al == pytest.approx(1.0)
        assert cr == pytest.approx(ar)
        # the driver's line runs through the middle of each gated section
        path = p.path(60 / 3.6)
        assert path.y_ref(0.0) == 0.0  # starts at the start pose
        assert ar < path.y_ref(0.5 * (a0 + a1)) < al
        assert br < path.y_ref(0.5 * (b0 + b1)) < bl
        assert cr < path.y_ref(0.5 * (c0 + c1)) < cl


def test_dlc_line_keeps_its_limits_and_its_clearance() -> None:
    """The planned line honours the program's constraints: |U^2 y''| <= a_max and
    |U^3 d3y/dx3| <= j_max (finite differences on its grid), y = 0 with zero slope and
    curvature at the start and straight at the end; its clearance is the smallest
    body-to-cone distance of its grid points and lies within the back-off of the widest
    line's."""
    p = load_maneuver_spec("double_lane_change").params
    speed = 60 / 3.6
    plan = p.plan(speed)
    h = p.path_step_m
    y = plan.y_m
    assert np.max(np.abs(np.diff(y, 2))) / h ** 2 * speed ** 2 <= \
        p.path_lateral_accel_mps2 * (1 + 1e-6)
    assert np.max(np.abs(np.diff(y, 3))) / h ** 3 * speed ** 3 <= \
        p.path_lateral_jerk_mps3 * (1 + 1e-6)
    assert np.all(y[:3] == 0.0)
    assert np.ptp(y[-4:]) < 1e-9
    assert plan.margin_m == pytest.approx(clearance(plan.x_m, y, p.sections,
                                                    p.vehicle_width_m), abs=1e-12)
    assert plan.widest_margin_m - MARGIN_BACKOFF_M - 1e-9 <= plan.margin_m \
        <= plan.widest_margin_m + 1e-9
    # the number the YAML quotes: 6.1 cm at 6.25 m/s^2, 60 km/h, W = 1.7 m
    assert plan.margin_m == pytest.approx(0.061, abs=5e-4)


def test_corridor_line_through_one_centred_lane_is_straight() -> None:
    """Analytic case: one lane of width w centred on y = 0 needs no turning; the widest line is
    y = 0 with clearance (w - W) / 2."""
    width, lane = 1.7, 2.6
    plan = plan_corridor_path([(30.0, 60.0, -0.5 * lane, 0.5 * lane)], width, 20.0, 5.0, 30.0,
                              x_start_m=0.0, x_end_m=80.0)
    assert plan.widest_margin_m == pytest.approx(0.5 * (lane - width), abs=1e-9)
    assert plan.margin_m == pytest.approx(0.5 * (lane - width), abs=1e-9)
    assert np.max(np.abs(plan.y_m)) < 1e-9


def test_tracking_driver_on_an_arc_steers_the_steady_state_angle() -> None:
    """On an arc of radius R, on the line and tangent to it, turning at r = U/R with
    a_y = U^2/R and no sideslip, every error term is zero: the driver steers its internal
    model's steady-state angle delta = (L + K_us U^2) / R (steady-state bicycle model), and
    the mirrored arc gives the mirrored angle."""
    vehicle = load_vehicle("table_8_1")
    radius, speed = 60.0, 15.0
    x = np.arange(-20.0, 20.01, 0.25)
    spec = TrackingDriverSpec(neuromuscular_lag_s=0.0, lateral_accel_lag_s=0.0)
    expected = (vehicle.chassis.wheelbase_m
                + vehicle.understeer_gradient_rad_per_mps2 * speed ** 2) / radius
    for direction in (1, -1):
        arc = direction * (radius - np.sqrt(radius ** 2 - x ** 2))
        driver = PathTrackingDriver(spec, vehicle, SplinePath(x, arc))
        state = {"x_m": 0.0, "y_m": 0.0, "heading_rad": 0.0, "sideslip_rad": 0.0,
                 "speed_mps": speed, "yaw_rate_radps": direction * speed / radius,
                 "lateral_accel_mps2": direction * speed ** 2 / radius}
        first = driver.steer(0.0, state)
        later = driver.steer(0.5, state)  # (almost) no error: the integrator stays ~empty
        # 1e-4: the spline's curvature of the sampled arc, not the driver
        assert first == pytest.approx(direction * expected, rel=1e-4)
        assert later == pytest.approx(direction * expected, rel=1e-4)


def test_tracking_driver_lags_like_its_neuromuscular_first_order() -> None:
    """With only the steering lag acting, a constant command c is approached as
    delta_k = c (1 - (T_n / (T_n + dt))^k) (the forward-Euler first order of the docstring);
    the command is the internal model's angle for a_c = w_n^2 * 0.1 m (0.1 m right of a
    straight line)."""
    vehicle = load_vehicle("table_8_1")
    x = np.arange(0.0, 50.0, 0.5)
    spec = TrackingDriverSpec(neuromuscular_lag_s=0.05, turn_rate_gain_s=0.0,
                              turn_integral_gain=0.0, sideslip_gain=0.0,
                              path_frequency_radps=2.0, lateral_accel_lag_s=0.0)
    driver = PathTrackingDriver(spec, vehicle, SplinePath(x, np.zeros_like(x)))
    speed = 10.0
    state = {"x_m": 10.0, "y_m": -0.1, "heading_rad": 0.0, "sideslip_rad": 0.0,
             "speed_mps": speed, "yaw_rate_radps": 0.0, "lateral_accel_mps2": 0.0}
    a_c = 2.0 ** 2 * 0.1
    command = (vehicle.chassis.wheelbase_m
               + vehicle.understeer_gradient_rad_per_mps2 * speed ** 2) * a_c / speed ** 2
    dt, ratio = 0.01, 0.05 / 0.06
    angles = [driver.steer(k * dt, state) for k in range(6)]
    assert angles[0] == 0.0  # the hands start where they are
    for k in range(1, 6):
        assert angles[k] == pytest.approx(command * (1.0 - ratio ** k), rel=1e-9)


def test_brake_in_turn_schedule() -> None:
    vehicle = load_vehicle("table_8_1")
    spec = load_maneuver_spec("brake_in_turn")
    p = spec.params
    man = make_maneuver(spec, vehicle)
    outputs = dict(STILL, speed_mps=spec.initial_speed_mps)
    before = man.command(p.brake_start_s - 0.01, outputs)
    during = man.command(p.brake_start_s + 0.5, outputs)
    assert sum(before.brake_torque_nm) == 0.0
    assert sum(during.drive_torque_nm) == 0.0
    body = vehicle.body
    equivalent_mass = vehicle.chassis.mass_kg + 4 * body.wheel_spin_inertia_kgm2 / \
        body.wheel_radius_m ** 2  # the brakes also stop the spinning wheels
    expected = equivalent_mass * body.wheel_radius_m * 0.3 * GRAVITY_MPS2
    assert sum(during.brake_torque_nm) == pytest.approx(expected, rel=1e-6)
    assert man.phase(p.brake_start_s + 0.5) == "brake"
    assert man.phase(spec.duration_s) == "done"


def test_unknown_type_lists_the_valid_ones() -> None:
    with pytest.raises(UnknownNameError) as err:
        maneuver_spec_from_mapping({"type": "moose", "initial_speed_mps": 1.0,
                                    "duration_s": 1.0})
    assert "moose" in str(err.value)
    for name in MANEUVER_TYPES:
        assert name in str(err.value)
    with pytest.raises(UnknownNameError):
        load_maneuver_spec("no_such_maneuver")


@pytest.mark.parametrize("change,field", [
    ({"amplitude_rad": "big"}, "amplitude_rad"),
    ({"ramp_time_s": -0.1}, "ramp_time_s"),
    ({"duration_s": 0.0}, "duration_s"),
    ({"steer_input": "pedal"}, "steer_input"),
    ({"wobble": 1.0}, "wobble"),
    ({"speed_hold": {"kp_per_s": -1.0}}, "speed_hold.kp_per_s"),
    ({"speed_hold": {"driven_axle": "middle"}}, "speed_hold.driven_axle"),
    ({"path_driver": {}}, "path_driver"),
])
def test_malformed_file_names_field_and_file(tmp_path: Path, change: dict, field: str) -> None:
    data = load_maneuver_spec("step_steer_85kmh").to_dict()
    data.update(change)
    path = tmp_path / "bad.yaml"
    import yaml
    path.write_text(yaml.safe_dump(data))
    with pytest.raises(ParameterError) as err:
        load_maneuver_spec(path)
    assert err.value.field == field
    assert str(path) in str(err.value)


def test_missing_amplitude_is_reported(tmp_path: Path) -> None:
    data = load_maneuver_spec("step_steer_85kmh").to_dict()
    del data["amplitude_rad"]
    with pytest.raises(ParameterError, match="amplitude_rad: missing"):
        maneuver_spec_from_mapping(data, "x.yaml")


# ------------------------------------------------------------------ ISO 3888-2, every law

#: Laws the one DLC driver does not take through the course at 60 km/h on table_8_1, and the
#: closed-loop reason (config/maneuvers/double_lane_change.yaml); the reason is asserted
#: below, so a law that starts to clear the course, or stops, fails a test. (lqr's
#: continuous design, which saturates like a relay at 100 Hz, is not a shipped default.)
DLC_NOT_DRIVABLE = {
    "sol2": "its closed loop is unstable: the yaw rate diverges with the steering held",
}
#: Smallest body-to-cone clearance each other law keeps at 60 km/h, m (the YAML lists them).
DLC_MIN_CLEARANCE_M = 0.03


@functools.lru_cache(maxsize=None)
def _dlc_run(law: str, **law_options: str) -> tuple:
    spec = load_maneuver_spec("double_lane_change")
    return spec, run_closed_loop(load_vehicle("table_8_1"), spec, law,
                                 law_options=law_options)


def _course_clearance(res, p) -> float:
    """Smallest distance (m) between the body (CG +- W/2) and the cone lines over the gated
    sections (:func:`fourws_sim.corridor.clearance`), after checking that the car drove
    through every section."""
    x, y = res["x_m"], res["y_m"]
    for x0, x1, _, _ in p.sections:
        assert ((x >= x0) & (x <= x1)).sum() > 10  # the car did drive through the section
    return clearance(x, y, p.sections, p.vehicle_width_m)


def _peak_slip_angle_rad(vehicle) -> float:
    """Slip angle of the largest lateral force of the vehicle's STI tire (Table C.1) at its
    static front and rear wheel loads, the smaller of the two: past it the tire slides."""
    from fourws_sim.tires import sti

    c = vehicle.chassis
    weight = c.mass_kg * GRAVITY_MPS2
    alphas = np.radians(np.arange(0.5, 25.0, 0.1))
    peaks = []
    for axle, share in (("front", c.cg_to_rear_axle_m), ("rear", c.cg_to_front_axle_m)):
        fz = 0.5 * weight * share / c.wheelbase_m
        coeffs = sti.pack(vehicle, axle)
        fy = [abs(sti.forces(fz, a, 0.0, 16.7, 1.0, coeffs)[1]) for a in alphas]
        peaks.append(alphas[int(np.argmax(fy))])
    return float(min(peaks))


@pytest.mark.parametrize("law", available_laws())
def test_dlc_at_60_kmh_with_every_law(law: str) -> None:
    """ISO 3888-2 at 60 km/h on table_8_1, one driver parameter set for every law: each stable
    law keeps >= 3 cm between the body and every cone line, with the steering of a human
    (road-wheel rate < 1.2 rad/s, i.e. no chatter) and the car gripping (sideslip < 10 deg);
    the laws of DLC_NOT_DRIVABLE hit cones because their car slides, its tires past the slip
    angle of their peak force (STI tire, Table C.1)."""
    spec, res = _dlc_run(law)
    margin = _course_clearance(res, spec.params)
    sideslip_deg = math.degrees(float(np.max(np.abs(res["sideslip_rad"]))))
    if law in DLC_NOT_DRIVABLE:
        assert margin < 0.0
        assert sideslip_deg > 15.0
        assert np.max(np.abs(res["slip_angle_rad"])) > _peak_slip_angle_rad(
            load_vehicle("table_8_1"))
        return
    assert margin > DLC_MIN_CLEARANCE_M
    assert sideslip_deg < 10.0
    steer = res.driver["front_wheel_angle_rad"]
    assert np.max(np.abs(np.diff(steer) / np.diff(res.time_s))) < 1.2
    assert res["x_m"][-1] > spec.params.sections[-1][1]  # and out of the course
    speed = res["speed_mps"]
    assert np.max(np.abs(speed / spec.initial_speed_mps - 1.0)) < 0.02


def test_lqr_lane_change_within_the_actuator() -> None:
    """lqr's default (sampled) design through the ISO 3888-2 course at 60 km/h: its rear
    command stays within the 5 deg / 30 deg/s actuator at every tick (the actuator applies
    every command unchanged), as its rear-angle weight intends (fourws_control/lqr.py)."""
    _, res = _dlc_run("lqr")
    act = load_vehicle("table_8_1").actuators
    assert np.max(np.abs(res.rear_law_rad)) < act.rear_angle_limit_rad
    np.testing.assert_allclose(res.rear_angle_rad, res.rear_law_rad, rtol=0.0, atol=1e-12)


def _held_steer_spec(duration_s: float = 4.0):
    """0.005 rad (0.29 deg) road-wheel step at 0.5 s, 60 km/h, then held: the linear range."""
    data = load_maneuver_spec("step_steer_85kmh").to_dict()
    data.update(initial_speed_mps=60 / 3.6, duration_s=duration_s, amplitude_rad=0.005)
    return load_maneuver_spec(data)


def _yaw_rate_at(res, t_s: float) -> float:
    return float(res["yaw_rate_radps"][int(np.argmin(np.abs(res.time_s - t_s)))])


def test_sol2_car_diverges_with_the_steering_held() -> None:
    """Why sol2 is in DLC_NOT_DRIVABLE: its closed loop with the 8-DOF car is unstable. With
    the steer held, the stable laws have settled half a second after the step (yaw rate at
    2 s within 15 % of that at 1 s) while sol2's keeps growing (x4.9 from 1 s to 2 s; the
    linearized closed loop has a real eigenvalue > 0, see sol2.py on oversteer cars)."""
    car = load_vehicle("table_8_1")
    spec = _held_steer_spec()
    for law in ("fws", "sol1", "rwc1_3dof"):
        res = run_closed_loop(car, spec, law)
        assert _yaw_rate_at(res, 2.0) / _yaw_rate_at(res, 1.0) == pytest.approx(1.0, abs=0.15)
    res = run_closed_loop(car, spec, "sol2")
    assert _yaw_rate_at(res, 2.0) / _yaw_rate_at(res, 1.0) > 3.0
    assert _yaw_rate_at(res, 3.5) > 5.0 * _yaw_rate_at(res, 1.0)


def test_continuous_lqr_rear_steer_is_a_relay_that_oscillates_at_the_control_rate() -> None:
    """Why lqr's default is the sampled design (fourws_control/lqr.py): the chapter-3
    continuous design's gain on V (-3 rad/(m/s) at 60 km/h) commands rear angles far beyond
    the actuator's 5 deg (the rear steer acts as a relay), and sampled at the 100 Hz control
    rate the loop is unstable: with the steer held the yaw rate keeps swinging (peak to peak
    > 0.1 rad/s over the last 2 s) where at 500 Hz it settles (< 1e-4 rad/s) - a property of
    the design and the control period, not of the driver. In the lane change it asks for ten
    times the actuator's range and the car slides out of the course (sideslip > 15 deg); the
    sampled design (default) clears it (test_dlc_at_60_kmh_with_every_law)."""
    car = load_vehicle("table_8_1")
    spec = _held_steer_spec()
    limit = car.actuators.rear_angle_limit_rad
    cont = {"design": "continuous"}
    at_100_hz = run_closed_loop(car, spec, "lqr", control_period_s=0.01, law_options=cont)
    at_500_hz = run_closed_loop(car, spec, "lqr", control_period_s=0.002, law_options=cont)
    late = at_100_hz.time_s > 2.0
    assert np.ptp(at_100_hz["yaw_rate_radps"][late]) > 0.1
    assert np.max(np.abs(at_100_hz.rear_law_rad)) > 3.0 * limit
    late = at_500_hz.time_s > 2.0
    assert np.ptp(at_500_hz["yaw_rate_radps"][late]) < 1e-4
    dlc_spec, dlc = _dlc_run("lqr", design="continuous")
    assert np.max(np.abs(dlc.rear_law_rad)) > 10.0 * limit
    assert _course_clearance(dlc, dlc_spec.params) < 0.0
    assert math.degrees(float(np.max(np.abs(dlc["sideslip_rad"])))) > 15.0
