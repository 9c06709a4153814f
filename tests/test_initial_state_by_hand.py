"""navcore.filters.initial_state piece by piece against numbers worked out by hand: the rest
test at its tolerances, the disagreement of a given state with a fix, the bookkeeping of the
intervals before the state is known, the velocity from two fixes with the WGS-84 radii written
out, the state carried from a fix to the IMU epoch, and the initial sigmas of each mode."""
from __future__ import annotations

import math

import numpy as np
import pytest

from navcore.filters.initial_state import (DEFAULT_ALIGN_TIME, DEFAULT_INIT_SPEED,
                                           MAX_DIFFERENCED_FIX_GAP, Initializer, at_rest,
                                           disagreement, level)

#: WGS-84 (NIMA TR8350.2): semi-major axis [m], flattening, equatorial normal gravity [m/s^2]
A, F, GAMMA_E = 6378137.0, 1.0 / 298.257223563, 9.7803253359
E2 = F * (2.0 - F)


def _radii(lat):
    """Meridian and transverse radii (Groves eqs. 2.105-2.106)."""
    w = 1.0 - E2 * math.sin(lat) ** 2
    return A * (1.0 - E2) / w ** 1.5, A / math.sqrt(w)


def _interval(f, w, dt=0.01):
    """(dtheta, dvel) of an interval with specific force f and rate w (body vectors)."""
    return np.asarray(w, dtype=float) * dt, np.asarray(f, dtype=float) * dt


# -- the rest test ---------------------------------------------------------------------------
@pytest.mark.parametrize("f_minus_g, w, rest", [(0.29, 0.0, True), (-0.29, 0.0, True),
                                                (0.31, 0.0, False), (-0.31, 0.0, False),
                                                (0.0, 0.019, True), (0.0, 0.021, False)])
def test_rest_is_gravity_within_0_3_and_a_rate_below_0_02(f_minus_g, w, rest):
    g, dt = 9.8, 0.02
    # the specific force and the rate split over the three axes: only the norms count
    f = (g + f_minus_g) * np.array([0.6, 0.0, -0.8])
    omega = w * np.array([0.0, 0.8, 0.6])
    dtheta, dvel = _interval(f, omega, dt)
    assert at_rest(dtheta, dvel, dt, g) is rest


def test_rest_ends_exactly_at_the_tolerances():
    # 0.6 is exactly twice 0.3 in binary, so |f - g| = 0.3 exactly; |w| = 0.02 exactly
    assert not at_rest([0.0, 0.0, 0.0], [0.3, 0.0, 0.0], 1.0, 0.6)
    assert not at_rest([0.02, 0.0, 0.0], [0.0, 0.0, 0.6], 1.0, 0.6)
    assert at_rest([0.0199, 0.0, 0.0], [0.0, 0.0, 0.6], 1.0, 0.6)


def test_level_of_a_tilted_vehicle_at_rest():
    # pitched up by 0.1 rad, no roll: f = -C_nb g = g (sin 0.1, 0, -cos 0.1)
    assert level([9.8 * math.sin(0.1), 0.0, -9.8 * math.cos(0.1)]) == pytest.approx((0.0, 0.1))
    # rolled right by 0.2 rad: f = g (0, -sin 0.2, -cos 0.2)
    assert level([0.0, -9.8 * math.sin(0.2), -9.8 * math.cos(0.2)]) == pytest.approx((0.2, 0.0))


# -- a given state against the first fix -----------------------------------------------------
def test_disagreement_is_the_largest_normalized_axis_with_its_signed_distance():
    # sigmas sqrt(1 + 2^2) = sqrt(5) on every axis: 3, -4 and 1 m are 1.34, 1.79, 0.45 sigmas
    d, axis, metres = disagreement([3.0, -4.0, 1.0, 99.0, 99.0, 99.0], [1.0, 1.0, 1.0],
                                   [2.0, 2.0, 2.0])
    assert (axis, metres) == (1, -4.0) and d == pytest.approx(4.0 / math.sqrt(5.0))
    # another axis wins where its sigma is smaller: 1 m over sqrt(0.01 + 0.09) = 3.16 sigmas
    d, axis, metres = disagreement([3.0, -4.0, 1.0], [1.0, 1.0, 0.01], [2.0, 2.0, 0.3])
    assert (axis, metres) == (2, 1.0) and d == pytest.approx(1.0 / math.sqrt(0.1))


# -- the intervals before the state is known -------------------------------------------------
def test_only_given_starts_done():
    assert Initializer("given").done
    assert not Initializer("given").checked      # the first fix is still to be compared
    assert not Initializer("gnss").done and not Initializer("align").done
    init = Initializer("gnss")
    assert (init.speed_min, init.align_time) == (DEFAULT_INIT_SPEED, DEFAULT_ALIGN_TIME)


@pytest.mark.parametrize("mode, rest_after_moving", [("gnss", 0.0), ("align", 0.03)])
def test_the_intervals_sum_and_gnss_levels_on_the_latest_stretch_at_rest(mode,
                                                                          rest_after_moving):
    # at the equator at sea level gravity is GAMMA_E: three intervals at rest, one moving
    init = Initializer(mode)
    still = _interval([0.0, 0.0, -GAMMA_E], [0.0, 0.0, 1e-4])
    moving = _interval([3.0, 0.0, -GAMMA_E], [0.0, 0.0, 0.5])
    for dtheta, dvel in (still, still, still):
        init.add_interval(dtheta, dvel, 0.01, 0.0, 0.0)
    assert init.rest_time == pytest.approx(0.03)
    assert init.rest_dvel == pytest.approx([0.0, 0.0, -3 * 0.01 * GAMMA_E])
    assert init.rest_dtheta == pytest.approx([0.0, 0.0, 3e-6])
    init.add_interval(*moving, 0.01, 0.0, 0.0)
    assert init.elapsed == pytest.approx(0.04)
    assert init.all_dvel == pytest.approx([0.03, 0.0, -4 * 0.01 * GAMMA_E])
    assert init.all_dtheta == pytest.approx([0.0, 0.0, 3e-6 + 0.005])
    assert init.rest_time == pytest.approx(rest_after_moving)
    assert init.rest_dvel[2] == pytest.approx(-100.0 * rest_after_moving * 0.01 * GAMMA_E)
    init.add_interval(*still, 0.01, 0.0, 0.0)           # at rest again after moving
    assert init.rest_time == pytest.approx(rest_after_moving + 0.01)
    assert init.rest_dvel.shape == init.rest_dtheta.shape == (3,)


def test_an_alignment_is_ready_at_its_time_to_a_nanosecond():
    init = Initializer("align", align_time=1.0)
    init.elapsed = 1.0 - 1e-10
    assert init.alignment_ready()
    init.elapsed = 1.0 - 1e-9                                       # the edge itself
    assert init.alignment_ready()
    init.elapsed = 1.0 - 1e-8
    assert not init.alignment_ready()
    other = Initializer("gnss", align_time=1.0)
    other.elapsed = 5.0
    assert not other.alignment_ready()


# -- fixes -----------------------------------------------------------------------------------
def _fix(t, lat, lon, h, v=(0.0, 0.0, 0.0)):
    """A fix as the filters pass it: time, position, velocity, then its sigmas and validity."""
    return (t, lat, lon, h, v, (1.0, 1.0, 2.0), True)


def test_the_velocity_between_two_fixes_uses_the_radii_at_the_second():
    init = Initializer("gnss", use_fix_velocity=False)
    lat0, lon0, h0 = 0.6, 1.0, 200.0
    assert init._velocity(_fix(10.0, lat0, lon0, h0)) is None       # no previous fix yet
    lat1, lon1, h1 = lat0 + 2e-6, lon0 - 3e-6, h0 + 1.5
    v = init._velocity(_fix(11.5, lat1, lon1, h1))
    rn, re = _radii(lat1)
    assert v == pytest.approx([(lat1 - lat0) * (rn + h1) / 1.5,
                               (lon1 - lon0) * (re + h1) * math.cos(lat1) / 1.5, -1.0], rel=1e-12)
    assert init.previous_fix == (11.5, lat1, lon1, h1)


def test_the_longitude_difference_is_wrapped_across_the_date_line():
    init = Initializer("gnss", use_fix_velocity=False)
    init._velocity(_fix(0.0, 0.0, math.pi - 1e-6, 0.0))
    v = init._velocity(_fix(1.0, 0.0, -math.pi + 1e-6, 0.0))
    assert v[1] == pytest.approx(2e-6 * A, rel=1e-6)                # east, not 2 pi west


@pytest.mark.parametrize("gap, known", [(MAX_DIFFERENCED_FIX_GAP, True),
                                        (MAX_DIFFERENCED_FIX_GAP + 1e-3, False), (0.0, False),
                                        (-1.0, False)])
def test_two_fixes_give_a_velocity_only_up_to_the_gap(gap, known):
    init = Initializer("gnss", use_fix_velocity=False)
    init._velocity(_fix(5.0, 0.5, 0.5, 0.0))
    assert (init._velocity(_fix(5.0 + gap, 0.5 + 1e-6, 0.5, 0.0)) is not None) is known


def test_the_fixs_own_velocity_is_taken_as_float():
    v = Initializer("gnss")._velocity(_fix(0.0, 0.5, 0.5, 0.0, (3, 4, -1)))
    assert v.dtype == np.float64 and v.tolist() == [3.0, 4.0, -1.0]


def test_a_state_from_a_fix_waits_for_the_speed_and_records_the_first_position():
    init = Initializer("gnss", speed_min=5.0)
    assert init.state_from_fix(_fix(1.0, 0.5, 0.6, 10.0, (3.0, 3.9, 0.0)), 1.0) is None
    assert init.first_position == (0.5, 0.6, 10.0)
    assert init.state_from_fix(_fix(2.0, 0.51, 0.6, 10.0, (3.0, 4.0, 0.0)), 2.0) is not None
    assert init.first_position == (0.5, 0.6, 10.0)                  # the first is kept


def test_a_state_from_a_fix_is_carried_to_the_imu_epoch_without_rest():
    init = Initializer("gnss")
    lat, lon, h, v = 0.7, -1.2, 300.0, (20.0, -15.0, 2.0)
    state = init.state_from_fix(_fix(100.0, lat, lon, h, v), 100.25)
    rn, re = _radii(lat)
    assert state[0] == pytest.approx(lat + 20.0 * 0.25 / (rn + h), rel=1e-14)
    assert state[1] == pytest.approx(lon - 15.0 * 0.25 / ((re + h) * math.cos(lat)), rel=1e-14)
    assert state[2] == pytest.approx(h - 2.0 * 0.25, rel=1e-14)
    assert list(state[3]) == [20.0, -15.0, 2.0]
    # no rest stretch: roll 0, pitch the flight-path angle, yaw the course
    assert state[4:] == pytest.approx((0.0, math.atan2(-2.0, 25.0), math.atan2(-15.0, 20.0)))


def test_a_state_from_a_fix_levels_on_the_rest_stretch():
    init = Initializer("gnss")
    g = 9.8
    f = [g * math.sin(0.05), -g * math.cos(0.05) * math.sin(0.1),
         -g * math.cos(0.05) * math.cos(0.1)]                       # roll 0.1, pitch 0.05
    for _ in range(5):                                              # 0.5 s at rest
        init.add_interval(*_interval(f, [0.0, 0.0, 0.0], 0.1), 0.1, 0.0, 0.0)
    state = init.state_from_fix(_fix(3.0, 0.2, 0.3, 0.0, (0.0, 10.0, 0.0)), 3.0)
    assert state[4:] == pytest.approx((0.1, 0.05, math.pi / 2))


def test_an_alignment_is_at_the_first_fix_or_the_given_position():
    init = Initializer("align", align_time=2.0)
    f, w = [0.0, 0.0, -9.8], [7.29e-5 * math.cos(0.6), 0.0, -7.29e-5 * math.sin(0.6)]
    for _ in range(4):
        init.add_interval(*_interval(f, w, 0.5), 0.5, 0.6, 0.0)
    lat, lon, h, v, roll, pitch, yaw = init.state_from_alignment((0.6, 0.1, 5.0))
    assert (lat, lon, h) == (0.6, 0.1, 5.0) and list(v) == [0.0, 0.0, 0.0]
    assert (roll, pitch, yaw) == pytest.approx((0.0, 0.0, 0.0), abs=1e-12)
    init.note_fix(_fix(1.0, 0.61, 0.11, 7.0))
    init.note_fix(_fix(2.0, 0.62, 0.12, 8.0))                       # only the first counts
    assert init.state_from_alignment((0.6, 0.1, 5.0))[:3] == (0.61, 0.11, 7.0)


# -- the initial sigmas ----------------------------------------------------------------------
P0 = np.array([1.0, 1.0, 1.0, 0.1, 0.1, 0.1, 0.01, 0.01, 0.01] + [1e-3] * 6)


def test_given_and_align_keep_the_configured_sigmas():
    for mode in ("given", "align"):
        p0 = Initializer(mode).start_sigmas(P0, np.array([5.0] * 6), 10.0)
        assert p0.tolist() == P0.tolist() and p0 is not P0


def test_gnss_sigmas_with_the_fixs_velocity_sigma():
    init = Initializer("gnss")
    init.rest_time = 1.0                                            # levelled at rest
    r = np.array([0.5, 3.0, 4.0, 0.05, 0.3, 0.9])
    p0 = init.start_sigmas(P0, r, 2.0)
    assert p0[:3].tolist() == [1.0, 3.0, 4.0]                       # raised to the fix's
    assert p0[3:6].tolist() == [0.1, 0.3, 0.9]
    assert p0[8] == pytest.approx(math.atan(0.3 / 2.0))             # the course: horizontal
    assert p0[6:8].tolist() == [0.01, 0.01]                         # levelled: as given
    assert p0[9:].tolist() == P0[9:].tolist()


def test_gnss_sigmas_from_differenced_fixes_and_without_rest():
    init = Initializer("gnss")
    r = np.array([0.5, 3.0, 4.0])
    p0 = init.start_sigmas(P0, r, 100.0)
    v_sigma = math.sqrt(2.0) * r / 2.0                              # two fixes 2 s apart
    assert p0[3:6] == pytest.approx(np.maximum(P0[3:6], v_sigma))
    assert p0[8] == pytest.approx(math.radians(2.0))                # at least 2 deg
    assert p0[6:8] == pytest.approx([math.radians(5.0)] * 2)        # level from the path


def test_sigmas_given_as_integers_become_floats():
    p0 = Initializer("gnss").start_sigmas([0] * 15, np.array([0.5, 0.5, 0.5]), 10.0)
    assert p0.dtype == np.float64 and p0[0] == 0.5
    assert p0[6] == pytest.approx(math.radians(5.0))


def test_configured_level_sigmas_above_what_gnss_knows_are_kept_the_yaw_is_the_course():
    p0 = P0.copy()
    p0[6:9] = [0.01, 0.2, 0.5]            # roll below the 5 deg floor, pitch and yaw above it
    out = Initializer("gnss").start_sigmas(p0, np.array([0.5, 0.5, 0.5]), 10.0)
    # the yaw is the course's: velocity sigma sqrt(2) 0.5 / 2 m/s at 10 m/s (2.03 deg)
    assert out[6:9] == pytest.approx([math.radians(5.0), 0.2,
                                      math.atan(math.sqrt(2.0) * 0.5 / 2.0 / 10.0)])


@pytest.mark.parametrize("speed, v_sigma, yaw_sigma_deg", [
    (10.0, (0.05, 0.3, 0.9), math.degrees(math.atan(0.3 / 10.0))),   # 2 deg floor: 1.72 < 2
    (1.0, (0.05, 0.2, 0.9), math.degrees(math.atan(0.2 / 1.0))),     # a walk: 11.3 deg
    (2.0, (0.4, 0.1, 0.9), math.degrees(math.atan(0.4 / 2.0)))])     # the larger of N and E
def test_the_yaw_sigma_is_the_courses_not_the_configured_100_deg(speed, v_sigma, yaw_sigma_deg):
    """The car's case: 100 deg configured for the given state; started from a course the
    yaw's sigma is atan(sigma_v / v) of the horizontal velocity sigma, at least 2 deg."""
    p0 = P0.copy()
    p0[8] = math.radians(100.0)
    r = np.array([0.01, 0.02, 0.03, *v_sigma])
    out = Initializer("gnss").start_sigmas(p0, r, speed)
    assert out[8] == pytest.approx(math.radians(max(2.0, yaw_sigma_deg)), rel=1e-12)


def test_default_speed_is_met_by_a_walk_and_a_slower_one_warns_after_a_minute():
    """A walk at 1.8 m/s starts at the default init_speed_min; with 2 m/s (the former
    default) it never does: one warning 60 s after the first valid fix, naming the speeds."""
    assert DEFAULT_INIT_SPEED <= 1.8
    walk = Initializer("gnss", use_fix_velocity=True)
    assert walk.state_from_fix(_fix(0.0, 0.7, 0.2, 5.0, v=(1.0, 1.5, 0.0)), 0.0) is not None
    slow = Initializer("gnss", speed_min=2.0, use_fix_velocity=True)
    warnings = []
    for k in range(62):
        t = 3.0 + k
        assert slow.state_from_fix(_fix(t, 0.7, 0.2, 5.0, v=(1.0, 1.5, 0.0)), t) is None
        warning = slow.waiting_warning(t)
        if warning:
            warnings.append((t, warning))
    assert len(warnings) == 1 and warnings[0][0] == 63.0
    assert "init_speed_min = 2 m/s in the 60 s" in warnings[0][1]
    assert "the fastest: 1.8 m/s" in warnings[0][1]


def _walk_notices(name, **params):
    """(notices, aligned) of filter ``name`` with init_mode 'gnss' on a walk at 1.8 m/s
    (walk_inputs), a 10 Hz IMU at rest, 75 s."""
    from navcore.components import registry
    from walk_inputs import LAT, walk_fix
    dt = 0.1
    f = registry.REGISTRY[name](init_mode="gnss", init_lat=LAT, init_h=100.0, **params)
    f.start(0.0)
    notices = []
    for k in range(750):
        fix = walk_fix(k, dt)
        imu = {"imu_time": (k + 1) * dt, "imu_dt": dt, "imu_dtheta_x": 0.0,
               "imu_dtheta_y": 0.0, "imu_dtheta_z": 0.0, "imu_dvel_x": 0.0,
               "imu_dvel_y": 0.0, "imu_dvel_z": -9.80 * dt}
        f.advance(k * dt, dt, {**imu, **fix})
        notices += f.take_notices()
    return notices, bool(f.out["aligned"])


@pytest.mark.parametrize("name", ["Kf", "Ukf"])
def test_a_walk_starts_at_the_default_and_warns_once_below_a_higher_speed(name):
    notices, aligned = _walk_notices(name)
    assert aligned and not [n for n in notices if "init_mode 'gnss'" in n]
    notices, aligned = _walk_notices(name, init_speed_min=2.0)
    waiting = [n for n in notices if "init_mode 'gnss'" in n]
    assert not aligned and len(waiting) == 1, notices
    assert waiting[0].startswith(f"{name}: init_mode 'gnss': no fix with a horizontal speed of "
                                 "at least init_speed_min = 2 m/s in the 60 s since")
    assert "(the fastest: 1.8 m/s)" in waiting[0]
