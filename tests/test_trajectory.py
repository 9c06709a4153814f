"""Trajectory generator: built-in profiles, documented values, smoothness, errors, state."""
import copy
import json
import math
import pickle

import numpy as np
import pytest

from navcore.core.component import ParameterError
from navcore.ins.motion_profiles import BUILTIN_PROFILES, builtin_profile, load_profile
from navcore.ins.trajectory import TrajectoryGenerator


def speed(s):
    return math.sqrt(s["vn"] ** 2 + s["ve"] ** 2 + s["vd"] ** 2)


def run(profile, dt, until=None):
    gen = TrajectoryGenerator(profile, dt)
    until = gen.duration if until is None else until
    rows = [gen.state()]
    rates, accels = [0.0], [0.0]
    while gen.time < until - 1e-9:
        s, dtheta, dvel = gen.step()
        assert np.all(np.isfinite(dtheta)) and np.all(np.isfinite(dvel))
        rows.append(s)
        rates.append(gen.last_rate_norm)
        accels.append(gen.last_accel_norm)
    table = {k: np.array([r[k] for r in rows]) for k in rows[0]}
    table["speed"] = np.sqrt(table["vn"] ** 2 + table["ve"] ** 2 + table["vd"] ** 2)
    table["rate"], table["accel"] = np.array(rates), np.array(accels)
    return gen, table


@pytest.mark.parametrize("name", BUILTIN_PROFILES)
def test_builtin_profiles_run_to_completion(name):
    gen, tab = run(name, 0.1)
    assert gen.time == pytest.approx(gen.duration)
    for key, col in tab.items():
        assert np.all(np.isfinite(col)), key
    assert tab["h"].min() > 0.0
    assert np.all(np.abs(tab["pitch"]) < math.radians(85.0))
    if name == "static":
        assert tab["speed"].max() == 0.0 and np.ptp(tab["h"]) == 0.0
    if name == "uav_maneuver":
        assert gen.duration == 3600.0
        assert 29.9 < tab["speed"].min() and tab["speed"].max() < 60.1
        t = tab["time"]
        strong = ((t < 600) | ((t >= 1200) & (t < 3000)))
        low = ~strong
        # strong manoeuvres vs low dynamics, as in paper 000 Fig. 3
        assert tab["rate"][strong].mean() > 5 * tab["rate"][low].mean()
        assert tab["accel"][strong].mean() > 5 * tab["accel"][low].mean()
        assert tab["rate"][low].max() < math.radians(1.0)
    if name == "manoeuvre_1h":
        # paired climbs and descents: back to the start height after each block
        assert abs(tab["h"][-1] - 1000.0) < 1e-6
        assert 99.9 < tab["speed"].min() and tab["speed"].max() < 150.1


def test_aircraft_500s_documented_values():
    gen, tab = run("aircraft_500s", 0.01)
    t = tab["time"]

    def at(key, time):
        return tab[key][int(round(time / 0.01))]

    assert math.degrees(tab["lat"][0]) == pytest.approx(40.1)
    assert math.degrees(tab["lon"][0]) == pytest.approx(118.6)
    assert gen.duration == 500.0
    assert at("speed", 40) == pytest.approx(80.0, abs=1e-9)
    assert at("h", 40) == pytest.approx(100.0, abs=1e-9)          # takeoff run on the runway
    assert at("h", 80) == pytest.approx(586.3, abs=0.5)            # first climb
    assert at("speed", 130) == pytest.approx(150.0, abs=1e-9)
    assert at("h", 190) == pytest.approx(2019.2, abs=0.5)          # second climb
    assert at("speed", 240) == pytest.approx(200.0, abs=1e-9)
    cruise = (t >= 240) & (t <= 440)
    assert np.ptp(tab["speed"][cruise]) < 1e-9 and np.ptp(tab["h"][cruise]) < 1e-6
    assert math.degrees(at("pitch", 60)) == pytest.approx(10.0, abs=1e-9)
    assert math.degrees(at("pitch", 160)) == pytest.approx(10.0, abs=1e-9)
    # turn: 180 deg, peak rate 180/56 deg/s, bank ~48.8 deg, ends level on heading south
    assert abs(math.degrees(tab["yaw"][-1])) == pytest.approx(180.0, abs=1e-9)
    assert math.degrees(at("roll", 470)) == pytest.approx(
        math.degrees(math.atan(200.0 * math.radians(180.0 / 56.0) / 9.80665)), abs=1e-9)
    assert tab["roll"][-1] == pytest.approx(0.0, abs=1e-12)
    assert tab["h"][-1] == pytest.approx(2019.2, abs=0.5)


def test_transitions_are_smooth():
    """No jumps in angular rate or acceleration across segment boundaries: at 100 Hz the
    per-step changes stay within a bounded angular acceleration and jerk, whereas an abrupt
    profile (transition 0) jumps by the full turn rate / acceleration in one step."""
    dt = 0.01
    for name, until in (("aircraft_500s", 500.0), ("uav_maneuver", 300.0)):
        gen, tab = run(name, dt, until=until)
        assert (
            np.abs(np.diff(tab["rate"][1:])).max() / dt < 5.0
        )  # rad/s^2 (UAV roll oscillation: ~2.1)
        assert np.abs(np.diff(tab["accel"][1:])).max() / dt < 20.0  # m/s^3 (UAV turn entry: ~10)
    abrupt = {"start": {"lat_deg": 40.0, "lon_deg": 110.0, "h": 100.0, "speed": 50.0},
              "segments": [{"type": "level", "duration": 1.0},
                           {"type": "turn", "duration": 5.0, "turn_rate_deg": 10.0,
                            "transition": 0.0}]}
    gen, tab = run(abrupt, dt)
    assert np.abs(np.diff(tab["rate"][1:])).max() / dt > 10.0


def test_manoeuvre_intensity_attributes():
    gen = TrajectoryGenerator("static", 0.01)
    gen.step()
    assert gen.last_accel_norm == 0.0
    assert gen.last_rate_norm == pytest.approx(7.292115e-5, rel=1e-9)
    gen = TrajectoryGenerator("aircraft_500s", 0.01)
    while gen.time < 20.0:
        gen.step()
    assert gen.last_accel_norm == pytest.approx(80.0 / 38.0, rel=1e-3)


def test_profile_end_holds_final_state():
    profile = {"start": {"lat_deg": 10.0, "lon_deg": 20.0, "h": 300.0, "speed": 50.0},
               "segments": [{"type": "turn", "duration": 10.0, "heading_change_deg": 90.0}]}
    gen = TrajectoryGenerator(profile, 0.05)
    while gen.time < 30.0:
        s, _, _ = gen.step()
    assert gen.last_accel_norm == pytest.approx(0.0, abs=1e-9)
    assert math.degrees(s["yaw"]) == pytest.approx(90.0, abs=1e-9)
    assert s["roll"] == pytest.approx(0.0, abs=1e-12)
    assert speed(s) == pytest.approx(50.0, abs=1e-12)


def test_roll_pitch_manoeuvres_and_hold_attitude():
    profile = {"start": {"lat_deg": 40.1, "lon_deg": 118.6, "h": 50.0},
               "segments": [
                   {"type": "hold_attitude", "duration": 20.0, "roll_deg": 5.0,
                    "pitch_deg": 10.0, "yaw_deg": -170.0, "transition": 5.0},
                   {"type": "roll", "duration": 20.0, "amplitude_deg": 30.0, "period": 10.0},
                   {"type": "pitch", "duration": 20.0, "amplitude_deg": 20.0, "shape": "step"},
                   {"type": "static", "duration": 5.0}]}
    gen, tab = run(profile, 0.01)

    def at(key, time):
        return math.degrees(tab[key][int(round(time / 0.01))])

    assert (at("roll", 10), at("pitch", 10), at("yaw", 10)) == pytest.approx(
        (5, 10, -170), abs=1e-9
    )
    # yaw goes the short way from 0 to -170 deg
    assert np.all(np.degrees(tab["yaw"][:1000]) <= 1e-9)
    assert at("roll", 20 + 2.5) == pytest.approx(5.0 + 30.0, abs=1e-9)  # sine peak, window = 1
    assert at("pitch", 50) == pytest.approx(30.0, abs=1e-9)           # step held
    assert (at("roll", 65), at("pitch", 65)) == pytest.approx((5, 10), abs=1e-9)
    assert tab["speed"].max() == 0.0


def test_generator_state_save_restore_is_exact():
    gen = TrajectoryGenerator("uav_maneuver", 0.01)
    for _ in range(500):
        gen.step()
    saved = copy.deepcopy(gen.__dict__)
    blob = pickle.dumps(gen)
    ref = [gen.step() for _ in range(200)]
    for other in (pickle.loads(blob), TrajectoryGenerator("static", 0.01)):
        other.__dict__.clear()
        other.__dict__.update(copy.deepcopy(saved))
        for s_ref, th_ref, dv_ref in ref:
            s, th, dv = other.step()
            assert s == s_ref
            np.testing.assert_array_equal(th, th_ref)
            np.testing.assert_array_equal(dv, dv_ref)
        assert other.last_rate_norm == gen.last_rate_norm


def base_profile(*segments):
    return {"start": {"lat_deg": 40.0, "lon_deg": 110.0, "h": 100.0, "speed": 50.0},
            "segments": [{"type": "level", "duration": 5.0}, {"type": "cruise", "duration": 5.0},
                         *segments]}


@pytest.mark.parametrize(
    "segment, parameter",
    [
        ({"type": "loop", "duration": 5.0}, "type"),
        ({"type": "turn", "heading_change_deg": 30.0}, "duration"),
        ({"type": "turn", "duration": -5.0, "heading_change_deg": 30.0}, "duration"),
        ({"type": "turn", "duration": 5.0}, "turn_rate_deg"),
        (
            {"type": "turn", "duration": 5.0, "turn_rate_deg": 3, "heading_change_deg": 30},
            "turn_rate_deg",
        ),
        ({"type": "turn", "duration": 5.0, "turn_rate_deg": 3.0, "transition": -1.0}, "transition"),
        ({"type": "turn", "duration": 5.0, "turn_rate_deg": "fast"}, "turn_rate_deg"),
        ({"type": "turn", "duration": 5.0, "turnrate_deg": 3.0}, "turnrate_deg"),
        ({"type": "accelerate", "duration": 5.0}, "accel"),
        ({"type": "accelerate", "duration": 5.0, "final_speed": -3.0}, "final_speed"),
        ({"type": "accelerate", "duration": 10.0, "accel": -20.0}, "accel"),
        ({"type": "climb", "duration": 5.0}, "climb_angle_deg"),
        ({"type": "climb", "duration": 5.0, "vertical_rate": 80.0}, "vertical_rate"),
        ({"type": "climb", "duration": 5.0, "climb_angle_deg": 88.0}, "climb_angle_deg"),
        ({"type": "roll", "duration": 5.0, "amplitude_deg": 10.0}, "period"),
        ({"type": "roll", "duration": 5.0, "amplitude_deg": 10.0, "period": -2.0}, "period"),
        ({"type": "pitch", "duration": 5.0, "period": 2.0}, "amplitude_deg"),
        ({"type": "pitch", "duration": 5.0, "amplitude_deg": 5, "shape": "square"}, "shape"),
        ({"type": "static", "duration": 5.0}, "type"),
        (
            {"type": "hold_attitude", "duration": 5.0, "roll_deg": 0, "pitch_deg": 0, "yaw_deg": 0},
            "type",
        ),
    ],
)
def test_segment_errors_name_index_type_and_parameter(segment, parameter):
    with pytest.raises(ParameterError) as err:
        TrajectoryGenerator(base_profile(segment), 0.01)
    msg = str(err.value)
    assert "segment 2" in msg
    assert f"'{segment['type']}'" in msg
    assert f"'{parameter}'" in msg


@pytest.mark.parametrize("profile, words", [
    ({"segments": [{"type": "static", "duration": 1.0}]}, ["start"]),
    ({"start": {"lon_deg": 0.0, "h": 0.0}, "segments": [{"type": "static", "duration": 1}]},
     ["lat_deg", "missing"]),
    ({"start": {"lat_deg": 0.0, "lon_deg": 0.0, "h": 0.0, "speed": -1.0},
      "segments": [{"type": "level", "duration": 1}]}, ["speed"]),
    ({"start": {"lat_deg": 0.0, "lon_deg": 0.0, "h": 0.0}, "segments": []}, ["segments"]),
])
def test_profile_start_errors(profile, words):
    with pytest.raises(ParameterError) as err:
        TrajectoryGenerator(profile, 0.01)
    for w in words:
        assert w in str(err.value)


def test_bad_step_size():
    with pytest.raises(ParameterError, match="dt"):
        TrajectoryGenerator("static", 0.0)


def test_load_profile_from_file_and_name(tmp_path):
    assert load_profile("aircraft_500s") == builtin_profile("aircraft_500s")
    path = tmp_path / "mine.json"
    path.write_text(json.dumps(base_profile({"type": "turn", "duration": 5.0, "turn_rate_deg": 3})))
    prof = load_profile(str(path))
    gen = TrajectoryGenerator(str(path), 0.1)
    assert gen.duration == 15.0 and prof["segments"][2]["turn_rate_deg"] == 3
    bad = tmp_path / "bad.json"
    bad.write_text("{not json")
    with pytest.raises(ParameterError, match="bad.json"):
        load_profile(str(bad))
    invalid = tmp_path / "invalid.json"
    invalid.write_text(json.dumps(base_profile({"type": "warp", "duration": 1.0})))
    with pytest.raises(ParameterError, match=r"invalid\.json.*segment 2"):
        load_profile(str(invalid))
    with pytest.raises(ParameterError, match="nowhere.json"):
        load_profile(str(tmp_path / "nowhere.json"))
    with pytest.raises(ParameterError, match="built-in"):
        builtin_profile("no_such_profile")
