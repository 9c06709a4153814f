"""FMU states are data: the byte format, the declared state of every component, and the
refusal of crafted, foreign or damaged states through raw FMI calls (fmpy's FMU2Slave).

pythonfmu 0.7.0 cannot return fmi2Error from fmi2SetFMUstate (see fmus/fmushell.py), so a
refused state shows as an fmi2Error-status log message at fmi2SetFMUstate and an
fmi2Discard from the next fmi2DoStep (which does not step); the tests check both, that the
attack's side effect did not happen, and that the instance then continues exactly from its
previous state.
"""
from __future__ import annotations

import base64
import collections
import hashlib
import json
import math
import os
import pickle
import struct

import numpy as np
import pytest
from fmpy.fmi1 import FMICallException

from navcore import components, state, state_format
from navcore.components import REGISTRY
from navcore.state import StateError
from navcore.state_format import MAGIC, StateFormatError
from test_fmus import FMU_NAMES, _Fmu, dist  # noqa: F401  (dist: the build fixture)

FMI2_DISCARD, FMI2_ERROR = 2, 3
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


def params_of(name):
    return PARAMS.get(name, FILTER_PARAMS)


def inputs_at(cls, k):
    """Inputs of step k (from t = k H): a moving truth for the receiver; for the filters
    stationary increments and a fix every 10 steps, every 7th fix 30 m off (so the adaptive
    and robust branches run)."""
    t1 = (k + 1) * H
    if cls.model_name == "GnssReceiver":
        return {"truth_time": t1, "truth_lat": 0.7 + 1e-7 * t1, "truth_lon": 2.0,
                "truth_h": 100.0, "truth_vn": 1.0, "truth_ve": 0.0, "truth_vd": 0.0}
    inputs = cls.default_inputs()
    if not inputs:
        return inputs
    epoch = (k + 1) // 10
    jump = 30.0 / 6.4e6 if (k + 1) % 70 == 0 else 0.0
    inputs.update(imu_time=t1, imu_dt=H, imu_dvel_z=-9.8 * H, imu_dtheta_x=1e-7 * math.sin(k),
                  gnss_time=epoch * 10 * H, gnss_lat=LAT + 1e-7 * math.cos(epoch) + jump,
                  gnss_h=100.0, gnss_valid=epoch > 0, gnss_epoch=epoch)
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


def bits(x: float) -> bytes:
    return struct.pack(">d", x)


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


def _payload_tree(blob):
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


def assert_same(a, b, where="component"):
    """Bit-identical object graphs (declared objects by their attributes)."""
    assert type(a) is type(b), where
    if isinstance(a, np.ndarray):
        assert a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes(), where
    elif isinstance(a, float):
        assert bits(a) == bits(b), where
    elif isinstance(a, np.random.Generator):
        assert a.bit_generator.state == b.bit_generator.state, where
    elif isinstance(a, (list, tuple, collections.deque)):
        assert len(a) == len(b) and getattr(a, "maxlen", 0) == getattr(b, "maxlen", 0), where
        for i, (x, y) in enumerate(zip(a, b)):
            assert_same(x, y, f"{where}[{i}]")
    elif isinstance(a, dict):
        assert a.keys() == b.keys(), where
        for k in a:
            assert_same(a[k], b[k], f"{where}.{k}")
    elif hasattr(a, "__dict__"):
        assert vars(a).keys() == vars(b).keys(), where
        for k in vars(a):
            assert_same(getattr(a, k), getattr(b, k), f"{where}.{k}")
    else:
        assert a == b, where


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


def test_restore_checks_kinds_dtypes_and_shapes():
    component, _ = stepped(components.Kf, 20)
    good = component.get_state()
    for mutate, message in (
            (lambda t: t["fields"]["engine"].__setitem__("P", np.zeros((14, 14))), "shape"),
            (lambda t: t["fields"].__setitem__("nav_time", "1.0"), "expected float"),
            (lambda t: t["fields"]["out"].pop("nis"), "keys differ"),
            (lambda t: t["params"].__setitem__("r_pos_n", "5"), "expected float"),
            (lambda t: t["fields"]["engine"].__setitem__("extra", 1), "unknown: extra"),
            (lambda t: t["fields"]["engine"].__setitem__("last", "x"), "number or an array")):
        tree = state.copy_value(good)
        mutate(tree)
        with pytest.raises(StateError, match=message):
            components.Kf.from_state(tree)


# -- raw FMI calls ---------------------------------------------------------------------------
def fmu_names_of(f, causality):
    return [v.name for v in f.md.modelVariables if v.causality == causality]


class Driven:
    """An FMU instance with batched input setting and all Real outputs read per step."""

    def __init__(self, dist, name, params):
        self.name, self.cls = name, REGISTRY[name]
        self.f = _Fmu(dist / f"{name}.fmu", name.lower(), params)
        md = {v.name: v for v in self.f.md.modelVariables}
        self.inputs = {t: [n for n in fmu_names_of(self.f, "input") if md[n].type == t]
                       for t in ("Real", "Integer", "Boolean")}
        self.real_out = [self.f.vr[n] for n in fmu_names_of(self.f, "output")
                         if md[n].type == "Real"]

    def set_inputs(self, k):
        values = inputs_at(self.cls, k)
        fmu, vr = self.f.fmu, self.f.vr
        for typ, setter in (("Real", fmu.setReal), ("Integer", fmu.setInteger),
                            ("Boolean", fmu.setBoolean)):
            names = self.inputs[typ]
            if names:
                setter([vr[n] for n in names], [values[n] for n in names])

    def run(self, k0, n):
        rows = []
        for k in range(k0, k0 + n):
            self.set_inputs(k)
            self.f.fmu.doStep(k * H, H)
            rows.append(self.f.fmu.getReal(self.real_out))
        return np.array(rows)

    def errors(self):
        return [m for s, m in self.f.records if s >= FMI2_ERROR]

    def close(self):
        self.f.close()


@pytest.mark.parametrize("steps", [0, 1, 1000])
@pytest.mark.parametrize("name", FMU_NAMES)
def test_fmu_state_serialized_and_loaded_continues_bit_identically(dist, name, steps):
    """fmi2SerializeFMUstate, fmi2DeSerializeFMUstate + fmi2SetFMUstate into the same
    instance and into a second instance built with the default parameters (the state brings
    its own): both continue exactly like the original."""
    a = Driven(dist, name, params_of(name))
    b = Driven(dist, name, {})
    try:
        a.run(0, steps)
        saved = a.f.fmu.getFMUstate()
        blob = a.f.fmu.serializeFMUstate(saved)
        a.f.fmu.freeFMUstate(saved)
        reference = a.run(steps, 40)
        for inst in (a, b):
            loaded = inst.f.fmu.deSerializeFMUstate(blob)
            inst.f.fmu.setFMUstate(loaded)
            inst.f.fmu.freeFMUstate(loaded)
        again, other = a.run(steps, 40), b.run(steps, 40)
        assert a.errors() == [] and b.errors() == []
    finally:
        a.close()
        b.close()
    assert blob.startswith(MAGIC) and len(blob) < 50_000
    assert np.array_equal(reference, again) and np.array_equal(reference, other)


SPLIT = 50


@pytest.fixture(scope="module")
def victim(dist):
    """Kf.fmu after SPLIT steps: its state, its blob, the 40 steps that follow; and a blob
    of Iakf.fmu (another FMU with the same variables plus its own)."""
    kf = Driven(dist, "Kf", FILTER_PARAMS)
    iakf = Driven(dist, "Iakf", FILTER_PARAMS)
    kf.run(0, SPLIT)
    iakf.run(0, SPLIT)
    kf.saved = kf.f.fmu.getFMUstate()
    kf.blob = kf.f.fmu.serializeFMUstate(kf.saved)
    kf.reference = kf.run(SPLIT, 40)
    iakf_state = iakf.f.fmu.getFMUstate()
    kf.foreign_state, kf.foreign_blob = iakf_state, iakf.f.fmu.serializeFMUstate(iakf_state)
    yield kf
    kf.close()
    iakf.close()


class Pwn:
    """Unpickling this runs a shell command (the attack of issue 15)."""

    def __init__(self, path):
        self.path = path

    def __reduce__(self):
        return os.system, (f"echo pwned > {self.path}",)


def reblob(blob, mutate):
    """``blob`` with its payload JSON changed by ``mutate`` and a matching header."""
    node = _payload_tree(blob)
    mutate(node)
    head = json.loads(blob.split(b"\n", 2)[1])
    return handmade_blob(node, (head["model"], head["build"]))


def at(node, *keys):
    """The node reached through dict keys (tags skipped)."""
    for key in keys:
        node = node["dict"][key] if "dict" in node else node[key]
    return node


def attack_blob(case, blob, foreign_blob, pwn):
    payload = b64(pickle.dumps(pwn))
    if case == "old-format pickle (issue 15)":
        return json.dumps({"values": {}, "component": payload}).encode()
    if case == "pickle in a state array":
        return reblob(blob, lambda n: at(n, "component", "fields", "engine")["dict"]
                      .__setitem__("P", payload))
    if case == "object-dtype array":
        return reblob(blob, lambda n: at(n, "component", "fields", "engine")["dict"]
                      .__setitem__("P", {"array": ["|O", [1], payload]}))
    if case == "pickle node":
        return reblob(blob, lambda n: at(n, "component", "fields")["dict"]
                      .__setitem__("engine", {"pickle": payload}))
    if case == "code in a parameter":
        return reblob(blob, lambda n: at(n, "component", "params")["dict"].__setitem__(
            "measurement", f"__import__('pickle').loads(__import__('base64').b64decode('{payload}'))"))
    if case == "100 MB blob":
        return MAGIC + b"0" * (100 * 1024 * 1024)
    if case == "another FMU's blob":
        return foreign_blob
    if case.startswith("one byte changed"):
        index = {"magic": 2, "header": len(MAGIC) + 20, "payload": len(blob) // 2,
                 "end": len(blob) - 1}[case.split()[-1]]
        return blob[:index] + bytes([blob[index] ^ 0x01]) + blob[index + 1:]
    if case == "older format version":
        return blob.replace(b'"version":1', b'"version":0', 1)
    if case == "truncated":
        return blob[:len(blob) * 2 // 3]
    if case == "wrong shape":
        return reblob(blob, lambda n: at(n, "component", "fields", "engine")["dict"]
                      .__setitem__("P", {"array": ["<f8", [14, 14], b64(bytes(8 * 196))]}))
    raise AssertionError(case)


ATTACKS = ["old-format pickle (issue 15)", "pickle in a state array", "object-dtype array",
           "pickle node", "code in a parameter", "100 MB blob", "another FMU's blob",
           "one byte changed: magic", "one byte changed: header", "one byte changed: payload",
           "one byte changed: end", "older format version", "truncated", "wrong shape"]


def assert_refused_then_usable(victim, attempts, tmp_path):
    """Each attempt (a deserialized state or a state handle) is refused at fmi2SetFMUstate
    with an Error-status message; the next step is not taken (Discard), the steps after it
    continue from the previous state exactly; nothing was written."""
    fmu = victim.f.fmu
    fmu.setFMUstate(victim.saved)
    before = len(victim.f.records)
    for attempt in attempts:
        handle = attempt() if callable(attempt) else fmu.deSerializeFMUstate(attempt)
        fmu.setFMUstate(handle)                     # pythonfmu: status OK (module docstring)
        if not callable(attempt):
            fmu.freeFMUstate(handle)
    refusals = [m for s, m in victim.f.records[before:]
                if s == FMI2_ERROR and "fmi2SetFMUstate refused" in m]
    assert len(refusals) == len(attempts), victim.f.records[before:]
    victim.set_inputs(SPLIT)
    with pytest.raises(FMICallException) as info:
        fmu.doStep(SPLIT * H, H)
    assert info.value.status == FMI2_DISCARD
    assert np.array_equal(victim.run(SPLIT, 40), victim.reference)
    assert not list(tmp_path.iterdir())
    return refusals


@pytest.mark.parametrize("case", ATTACKS)
def test_crafted_or_foreign_state_is_refused_without_side_effect(victim, case, tmp_path):
    blob = attack_blob(case, victim.blob, victim.foreign_blob, Pwn(tmp_path / "pwned"))
    (message,) = assert_refused_then_usable(victim, [blob], tmp_path)
    assert "the instance keeps its previous state" in message


def test_another_fmus_in_memory_state_is_refused(victim, tmp_path):
    (message,) = assert_refused_then_usable(victim, [lambda: victim.foreign_state], tmp_path)
    assert "'Iakf'" in message


def leaf_paths(node, path=()):
    """Paths to every leaf of a payload node that is not text (text replaced by other text
    is a value, not a payload; the shell's error message is text)."""
    if isinstance(node, dict) and len(node) == 1 and next(iter(node)) in ("dict", "tuple",
                                                                          "deque"):
        tag, body = next(iter(node.items()))
        children = body.items() if tag == "dict" else enumerate(body if tag == "tuple"
                                                                else body[1])
        for key, child in children:
            yield from leaf_paths(child, path + ((tag, key),))
    elif isinstance(node, list):
        for i, child in enumerate(node):
            yield from leaf_paths(child, path + ((None, i),))
    elif not isinstance(node, str):
        yield path


def replaced(node, path, value):
    node = json.loads(json.dumps(node))
    target = node
    for tag, key in path[:-1]:
        target = target if tag is None else target[tag]
        target = target[1] if tag == "deque" else target
        target = target[key]
    tag, key = path[-1]
    target = target if tag is None else target[tag]
    (target[1] if tag == "deque" else target)[key] = value
    return node


@pytest.mark.parametrize("name", ["Kf", "TrajectoryImu", "NewtonRobustKf", "ImmUkf"])
def test_a_payload_in_any_field_is_refused(dist, name, tmp_path):
    """Every non-text leaf of the state, replaced by a pickle of the attack (as a string)
    with a valid header and checksum, is refused."""
    inst = Driven(dist, name, params_of(name))
    try:
        inst.run(0, SPLIT)
        inst.saved = inst.f.fmu.getFMUstate()
        inst.blob = inst.f.fmu.serializeFMUstate(inst.saved)
        inst.reference = inst.run(SPLIT, 40)
        payload = b64(pickle.dumps(Pwn(tmp_path / "pwned")))
        tree = _payload_tree(inst.blob)
        head = json.loads(inst.blob.split(b"\n", 2)[1])
        paths = [p for p in leaf_paths(tree) if p[:1] != (("dict", "failed"),)]
        assert len(paths) > 60
        blobs = [handmade_blob(replaced(tree, p, payload), (head["model"], head["build"]))
                 for p in paths]
        assert_refused_then_usable(inst, blobs, tmp_path)
    finally:
        inst.close()
