"""FMU states are data: the byte format (against a reader and writer built from its
description in the test) and the declared state of every registered component (no FMI;
the raw FMI calls are in test_fmu_state.py)."""
from __future__ import annotations

import base64
import collections
import hashlib
import json
import math
import struct
from pathlib import Path

import numpy as np
import pytest

from conftest import assert_same, bits
from navcore.components import registry as components
from navcore.core import state, state_format
from navcore.components.registry import REGISTRY
from navcore.errors import StateError, StateFormatError
from navcore.core.state_format import MAGIC

LAT = math.radians(40.0)
H = 0.01
PARAMS = {
    "TrajectoryImu": {"profile": "aircraft_500s", "gyro_arw_dpsh": 0.05, "accel_vrw_ugpsHz": 50.0,
                      "gyro_bias_instability_dph": 1.0, "gyro_bias_tau_s": 100.0, "seed": 7},
    "GnssReceiver": {"pos_sigma_n": 3.0, "pos_sigma_e": 3.0, "vel_sigma_n": 0.2,
                     "fix_interval": 0.1, "outlier_period": 2.0, "outlier_multiple": 8.0,
                     "seed": 5},
}
FILTER_PARAMS = {"init_lat": LAT, "init_h": 100.0}
#: a second IMM model far from the first, so the model probabilities move on these inputs
PARAMS["ImmUkf"] = dict(FILTER_PARAMS, imm_q_scale_2=1e8)
#: the attitude filters: the field the magnetometer input below measures
PARAMS["UkfAhrs"] = {"mag_field_T": 4.5e-5, "mag_inclination": math.atan2(4.0, 2.0)}
PARAMS["FuzzyUkfAhrs"] = dict(PARAMS["UkfAhrs"], fuzzy_window=5)
#: the replay plays the shipped 80 s gnss-ins-sim log (100 Hz, from t = 0)
PARAMS["ImuSensor"] = {"gyro_arw_dpsh": 0.05, "gyro_bias_instability_dph": 1.0,
                       "gyro_bias_tau_s": 100.0, "mag_field_T": 5e-5, "seed": 7}
PARAMS["GuidedUav"] = {"turbulence_w20": 7.7, "wind_e": 3.0, "seed": 4}
PARAMS["ImuGnssReplay"] = {
    "log": str(Path(__file__).resolve().parent.parent / "models/replay_gnss_ins_sim/log")}


def params_of(name):
    return PARAMS.get(name, FILTER_PARAMS)


def inputs_at(cls, k):
    """Inputs of step k (from t = k H): a moving truth for the receiver; for the filters
    stationary increments and a fix every 10 steps, every 7th fix 30 m off (so the adaptive
    and robust branches run)."""
    t1 = (k + 1) * H
    if cls.model_name == "ImuSensor":   # the sample at the step's start (Jacobi): 1 m/s north
        t0 = k * H
        return dict({p.name: p.default() for p in cls.inputs}, truth_time=t0,
                    truth_lat=LAT + t0 / 6.36e6, truth_lon=2.0, truth_h=100.0, truth_vn=1.0,
                    truth_roll=1e-4 * math.sin(k), truth_yaw=0.3)
    if cls.model_name == "GuidedUav":   # a solution flying north along the first leg
        t0 = k * H
        return {"nav_time": t0, "nav_lat": 0.6998770300497261 + 25.0 * t0 / 6.36e6,
                "nav_lon": 2.069960492865275, "nav_h": 150.0, "nav_vn": 25.0, "nav_ve": 0.0,
                "nav_vd": 0.0, "nav_yaw": 0.0}
    if cls.model_name == "GnssReceiver":
        return {"truth_time": t1, "truth_lat": 0.7 + 1e-7 * t1, "truth_lon": 2.0,
                "truth_h": 100.0, "truth_vn": 1.0, "truth_ve": 0.0, "truth_vd": 0.0,
                "truth_roll": 0.0, "truth_pitch": 0.0, "truth_yaw": 0.01 * t1}
    inputs = {p.name: p.default() for p in cls.inputs}
    if not inputs:
        return inputs
    epoch = (k + 1) // 10
    jump = 30.0 / 6.4e6 if (k + 1) % 70 == 0 else 0.0
    inputs.update(imu_time=t1, imu_dt=H, imu_dvel_z=-9.8 * H, imu_dtheta_x=1e-7 * math.sin(k),
                  gnss_time=epoch * 10 * H, gnss_lat=LAT + 1e-7 * math.cos(epoch) + jump,
                  gnss_h=100.0, gnss_valid=epoch > 0, gnss_epoch=epoch)
    if "mag_time" in inputs:       # an attitude filter: a magnetometer sample with the IMU's
        inputs.update(mag_time=t1, mag_x=2e-5 + 1e-8 * math.cos(k), mag_y=0.0, mag_z=4e-5)
        inputs = {p.name: inputs[p.name] for p in cls.inputs}
    return inputs


# -- the byte format ---------------------------------------------------------------------
IDENTITY = ("Kf", "ab" * 32)


def handmade_blob(payload_node, identity=IDENTITY, version=1):
    """A blob written from the format's description (module docstring of state_format),
    without its code."""
    payload = json.dumps(payload_node).encode()
    header = {"build": identity[1], "model": identity[0], "version": version,
              "payload_sha256": hashlib.sha256(payload).hexdigest(),
              "payload_size": len(payload)}
    return (b"navfmu-fmu-state\n" + json.dumps(header, sort_keys=True, separators=(",", ":"))
            .encode() + b"\n" + payload)


def b64(data: bytes) -> str:
    return base64.b64encode(data).decode()


def test_decode_reads_a_handmade_blob_bit_exactly():
    matrix = np.array([[1.5, -0.0], [5e-324, -2.0 ** 1000]])
    node = {"dict": {
        "neg_zero": -0.0, "tiny": 5e-324, "third": 1.0 / 3.0, "n": 2 ** 127 + 1, "flag": True,
        "none": None, "text": "static",
        "nan": {"float": "7ff8000000000123"}, "minus_inf": {"float": "fff0000000000000"},
        "matrix": {"array": ["<f8", [2, 2], b64(matrix.astype("<f8").tobytes())]},
        "ints": {"array": ["<i8", [3], b64(struct.pack("<3q", -1, 0, 2 ** 62))]},
        "mask": {"array": ["|b1", [2], b64(b"\x01\x00")]},
        "pair": {"tuple": [1, 2.5]}, "items": [1, [2]],
        "recent": {"deque": [3, [0.5, 0.25]]}}}
    tree = state_format.decode(handmade_blob(node), IDENTITY)
    assert bits(tree["neg_zero"]) == bits(-0.0)
    assert bits(tree["tiny"]) == bits(5e-324) and bits(tree["third"]) == bits(1.0 / 3.0)
    assert tree["n"] == 2 ** 127 + 1 and tree["flag"] is True and tree["none"] is None
    assert bits(tree["nan"]) == bytes.fromhex("7ff8000000000123")
    assert bits(tree["minus_inf"]) == bits(-math.inf)
    assert tree["matrix"].dtype == np.float64 and tree["matrix"].tobytes() == matrix.tobytes()
    assert tree["ints"].tolist() == [-1, 0, 2 ** 62]
    assert tree["mask"].tolist() == [True, False]
    assert tree["pair"] == (1, 2.5) and tree["items"] == [1, [2]]
    assert tree["recent"] == collections.deque([0.5, 0.25], maxlen=3)


def test_encode_writes_what_the_handmade_reader_expects():
    """encode against the format description (the test's own header and tags)."""
    tree = {"x": -0.0, "v": np.array([math.nan, 1.0]), "t": (None, 2)}
    blob = state_format.encode(tree, IDENTITY)
    magic, header, payload = blob.split(b"\n", 2)
    assert magic + b"\n" == MAGIC
    head = json.loads(header)
    assert head == {"build": IDENTITY[1], "model": "Kf", "version": 1,
                    "payload_size": len(payload),
                    "payload_sha256": hashlib.sha256(payload).hexdigest()}
    node = json.loads(payload)["dict"]
    assert bits(node["x"]) == bits(-0.0) and node["t"] == {"tuple": [None, 2]}
    dtype, shape, data = node["v"]["array"]
    assert (dtype, shape) == ("<f8", [2])
    assert base64.b64decode(data) == np.array([math.nan, 1.0]).astype("<f8").tobytes()


def payload_tree(blob):
    return json.loads(blob.split(b"\n", 2)[2])


GOOD = handmade_blob({"dict": {"P": {"array": ["<f8", [2], b64(bytes(16))]}}})
REFUSED_BLOBS = {
    "empty": (b"", "empty"),
    "other magic": (b"NAVFMU" + GOOD[6:], "magic"),
    "old pickle format": (json.dumps({"values": {}, "component": b64(b"\x80\x04.")}).encode(),
                          "pickle-based"),
    "too large": (GOOD + b" " * state_format.MAX_STATE_BYTES, "more than"),
    "truncated": (GOOD[:-3], "truncated"),
    "byte changed in payload": (GOOD[:-5] + b"B" + GOOD[-4:], "SHA-256"),
    "byte changed in header": (GOOD.replace(b'"version":1', b'"version":2'), "version 2"),
    "older version": (handmade_blob({"dict": {}}, version=0), "version 0"),
    "no header": (MAGIC + b"x" * 2000, "no header"),
    "other model": (handmade_blob({"dict": {}}, ("Iakf", "ab" * 32)), "'Iakf'"),
    "other build": (handmade_blob({"dict": {}}, ("Kf", "cd" * 32)), "another build"),
    "unknown tag": (handmade_blob({"pickle": b64(b"\x80\x04.")}), "unknown node tag"),
    "object dtype": (handmade_blob({"array": ["|O", [1], b64(bytes(8))]}), "not allowed"),
    "data size": (handmade_blob({"array": ["<f8", [3], b64(bytes(16))]}), "16 bytes"),
    "bool bytes": (handmade_blob({"array": ["|b1", [1], b64(b"\x07")]}), "0 and 1"),
    "NaN literal": (handmade_blob(math.nan), "NaN is not allowed"),
    "deep nesting": (handmade_blob(json.loads("[" * 60 + "]" * 60)), "deeper"),
    "huge integer": (handmade_blob(2 ** 300), "larger"),
    "two-key object": (handmade_blob({"dict": {}, "tuple": []}), "one tag"),
}


@pytest.mark.parametrize("case", sorted(REFUSED_BLOBS))
def test_decode_refuses(case):
    blob, message = REFUSED_BLOBS[case]
    with pytest.raises(StateFormatError, match=message):
        state_format.decode(blob, IDENTITY)


# -- declared state of every component (no FMI) -------------------------------------------
def stepped(cls, n, start=0):
    component = cls(**params_of(cls.model_name))
    component.start(0.0)
    outputs = [dict(component.step(k * H, H, inputs_at(cls, k))) for k in range(start, n)]
    return component, outputs


def run(component, k0, n):
    cls = type(component)
    return [dict(component.step(k * H, H, inputs_at(cls, k))) for k in range(k0, k0 + n)]


def declared_objects(obj, where):
    """Every declared object reachable from ``obj`` through state fields."""
    yield where, obj
    fields, _ = state.declared_fields(type(obj))
    for name in fields:
        value = getattr(obj, name)
        items = value if isinstance(value, list) else [value]
        for i, item in enumerate(items):
            if state.is_declared(item):
                yield from declared_objects(item, f"{where}.{name}" + (
                    f"[{i}]" if isinstance(value, list) else ""))


@pytest.mark.parametrize("name", sorted(REGISTRY))
def test_every_attribute_is_declared_and_restored_exactly(name):
    """Walks the component after stepping: every instance attribute of it and of its
    sub-objects is a declared state or derived field, and a component rebuilt from the
    serialized state equals the original in every attribute, derived ones included."""
    component, _ = stepped(REGISTRY[name], 300)
    for where, obj in declared_objects(component, name):
        assert state.undeclared_attributes(obj) == (), where
    blob = state_format.encode(component.get_state(), (name, "b"))
    restored = REGISTRY[name].from_state(state_format.decode(blob, (name, "b")))
    assert_same(component, restored, name)


@pytest.mark.parametrize("steps", [0, 1, 1000])
@pytest.mark.parametrize("name", sorted(REGISTRY))
def test_serialized_component_continues_bit_identically(name, steps):
    component, _ = stepped(REGISTRY[name], steps)
    blob = state_format.encode(component.get_state(), (name, "b"))
    restored = REGISTRY[name].from_state(state_format.decode(blob, (name, "b")))
    assert_same(run(component, steps, 150), run(restored, steps, 150))


def test_the_adaptive_histories_are_part_of_the_state():
    """After 1000 steps (100 fixes, 14 of them 30 m off) the histories the bit-identity test
    carries are not trivial: a full Newton buffer, a Sage-Husa R away from R0, IMM
    probabilities away from uniform, a CTFA weight above 0."""
    newton = stepped(components.NewtonRobustKf, 1000)[0].get_state()["fields"]["engine"]
    assert len(newton["history"]["_values"]) == 5 and len(newton["sample_variances"]) == 5
    sage = stepped(components.SageHusaFading, 1000)[0]
    assert not np.allclose(sage.get_state()["fields"]["engine"]["R"], sage.engine.R0)
    imm = stepped(components.ImmUkf, 1000)[0].get_state()["fields"]["engine"]
    assert imm["bank"]["mu"][0] > 0.6
    ctfa = stepped(components.CtfaUkf, 1000)[0].get_state()["fields"]["engine"]
    assert ctfa["schedule"]["weight"] > 0.0


class _ForgetfulKf(components.Kf):
    def initialize(self, start_time):
        self.smoothed_heading = 0.0      # added, not declared
        return super().initialize(start_time)


def test_an_undeclared_attribute_fails_get_state():
    component = _ForgetfulKf()
    component.start(0.0)
    with pytest.raises(StateError, match="smoothed_heading"):
        component.get_state()


class _HistoryKf(components.Kf):
    """A filter with a buffer of past solutions, declared as other filters will have."""

    state_fields = ("solutions",)

    def initialize(self, start_time):
        self.solutions = collections.deque(maxlen=4)
        return super().initialize(start_time)

    def step(self, t, h, inputs):
        out = super().step(t, h, inputs)
        self.solutions.append((self.nav_time, self.engine.nav.v_ned.copy(), {"h": out["nav_h"]}))
        return out


def _described_node(value):
    """The payload node of one value as the format's description spells it (module
    docstring of state_format), built here without its code."""
    if isinstance(value, collections.deque):
        return {"deque": [value.maxlen, [_described_node(v) for v in value]]}
    if isinstance(value, tuple):
        return {"tuple": [_described_node(v) for v in value]}
    if isinstance(value, dict):
        return {"dict": {k: _described_node(v) for k, v in value.items()}}
    if isinstance(value, np.ndarray):
        return {"array": ["<f8", list(value.shape), b64(value.astype("<f8").tobytes())]}
    return value


def test_a_declared_buffer_of_tuples_is_encoded_as_described_and_round_trips():
    """The buffer's bytes against the format's description (a deque of maxlen 4 holding the
    last 4 (time, velocity array, dict) tuples, written here by hand); then the
    self-consistency of the round trip: the restored filter continues bit for bit."""
    component, _ = stepped(_HistoryKf, 30)
    blob = state_format.encode(component.get_state(), IDENTITY)
    node = payload_tree(blob)["dict"]["fields"]["dict"]["solutions"]
    assert [entry["tuple"][0] for entry in node["deque"][1]] == [0.27, 0.28, 0.29, 0.3]
    assert node == _described_node(component.solutions)
    tree = state_format.decode(blob, IDENTITY)
    restored = _HistoryKf.from_state(tree)
    assert_same(component, restored)
    assert_same(run(component, 30, 20), run(restored, 30, 20))
    tree["fields"]["solutions"][0] = (0.1, "payload", {"h": 1.0})
    with pytest.raises(StateError, match="numeric data"):
        _HistoryKf.from_state(tree)


def test_restore_checks_kinds_dtypes_and_shapes():
    component, _ = stepped(components.Kf, 20)
    good = component.get_state()
    for mutate, message in (
            (lambda t: t["fields"]["engine"].__setitem__("P", np.zeros((14, 14))), "shape"),
            (lambda t: t["fields"].__setitem__("nav_time", "1.0"), "expected float"),
            (lambda t: t["fields"]["out"].pop("nis"), "keys differ"),
            (lambda t: t["params"].__setitem__("r_pos_n", "5"), "expected float"),
            (lambda t: t["fields"]["engine"].__setitem__("extra", 1), "unknown: extra"),
            (lambda t: t["fields"]["engine"].__setitem__("last", ("x",)), "numeric data")):
        tree = state.copy_value(good)
        mutate(tree)
        with pytest.raises(StateError, match=message):
            components.Kf.from_state(tree)
