"""FMU states through raw FMI calls (fmpy's FMU2Slave): serialized states continue bit for
bit, crafted, foreign or damaged ones are refused without side effect.

A refused blob or state is fmi2Error from fmi2DeSerializeFMUstate or fmi2SetFMUstate with an
Error-status message (the FMUs' patched pythonfmu library,
orchestrator/building/native_library.py; the tests skip with its reason where it could not be
built); the tests check that, that the attack's side effect did not happen, and that the
instance then continues exactly from its previous state. The fallback of pythonfmu's own library
(fmi2OK, the message, fmi2Discard at the next fmi2DoStep) is tested in
tests/test_native_library.py.
"""
from __future__ import annotations

import json
import os
import pickle

import numpy as np
import pytest
from fmpy.fmi1 import FMICallException

from navcore.components.registry import REGISTRY
from navcore.core.state_format import MAGIC
from test_fmus import FMU_NAMES, _Fmu, dist  # noqa: F401  (dist: the build fixture)
from test_native_library import require_patched
from test_state_format import (FILTER_PARAMS, H, b64, handmade_blob, inputs_at, params_of,
                               payload_tree)

FMI2_ERROR = 3
#: parameters without which an FMU cannot initialize at all (the replay needs its log)
REQUIRED_PARAMS = {"ImuGnssReplay": params_of("ImuGnssReplay")}


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
    b = Driven(dist, name, REQUIRED_PARAMS.get(name, {}))
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
    assert blob.startswith(MAGIC) and len(blob) < 56_000   # ImmUkf, the largest: 52.4 kB (with the land aids and static alignment)
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
    node = payload_tree(blob)
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
        return reblob(
            blob,
            lambda n: at(n, "component", "params")["dict"].__setitem__(
                "measurement",
                f"__import__('pickle').loads(__import__('base64').b64decode('{payload}'))",
            ),
        )
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


def refused_with_error(call, *args):
    """True if ``call`` returned fmi2Error (any other failure status fails the test)."""
    try:
        handle = call(*args)
    except FMICallException as exc:
        assert exc.status == FMI2_ERROR, exc
        return True
    return handle


def assert_refused_then_usable(victim, attempts, tmp_path):
    """Each attempt (a blob or a function giving a state handle) is refused with fmi2Error,
    by fmi2DeSerializeFMUstate or else by fmi2SetFMUstate, with one Error-status message;
    the steps that follow continue from the previous state exactly; nothing was written."""
    require_patched(victim.f.path)
    fmu = victim.f.fmu
    fmu.setFMUstate(victim.saved)
    before = len(victim.f.records)
    for attempt in attempts:
        handle = attempt() if callable(attempt) else refused_with_error(
            fmu.deSerializeFMUstate, attempt)
        if handle is True:
            continue
        assert refused_with_error(fmu.setFMUstate, handle) is True
        if not callable(attempt):
            fmu.freeFMUstate(handle)
    refusals = [m for s, m in victim.f.records[before:] if s == FMI2_ERROR]
    assert len(refusals) == len(attempts), victim.f.records[before:]
    assert all("refused the" in m or "unknown or was freed" in m for m in refusals), refusals
    assert np.array_equal(victim.run(SPLIT, 40), victim.reference)
    assert not list(tmp_path.iterdir())
    return refusals


@pytest.mark.parametrize("case", ATTACKS)
def test_crafted_or_foreign_state_is_refused_without_side_effect(victim, case, tmp_path):
    blob = attack_blob(case, victim.blob, victim.foreign_blob, Pwn(tmp_path / "pwned"))
    (message,) = assert_refused_then_usable(victim, [blob], tmp_path)
    assert message.startswith(("fmi2DeSerializeFMUstate refused the blob: ",
                               "kf: fmi2SetFMUstate refused the state, the instance keeps its "
                               "previous state: "))


def test_another_fmus_in_memory_state_is_refused(victim, tmp_path):
    """Another FMU's binary made the handle: it is no live state of this one's (the patched
    library's registry), refused before the slave sees it."""
    (message,) = assert_refused_then_usable(victim, [lambda: victim.foreign_state], tmp_path)
    assert message.startswith("kf: fmi2SetFMUstate: the FMUstate is unknown or was freed")


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
        tree = payload_tree(inst.blob)
        head = json.loads(inst.blob.split(b"\n", 2)[1])
        paths = [p for p in leaf_paths(tree) if p[:1] != (("dict", "failed"),)]
        assert len(paths) > 60
        blobs = [handmade_blob(replaced(tree, p, payload), (head["model"], head["build"]))
                 for p in paths]
        assert_refused_then_usable(inst, blobs, tmp_path)
    finally:
        inst.close()
