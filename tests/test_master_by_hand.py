"""The co-simulation master (orchestrator.cosim.master) on the direct backend with toy
components, against its docstring's rules written out by hand: the checks of the base step,
the decimation and the run length at their tolerance (rules 1 and 2), the wiring and parameter
checks (rules 5 and 8), the record selection (rule 6), a streamed run's chunks, the progress
calls, the start time, units, metadata and step times of the results, and the shorthand."""
from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from conftest import component_xml, connection_xml, ssd_text
from navcore.core.component import Component, Port, real, string
from navcore.errors import ParameterError
from orchestrator.cosim.master import Simulation, simulate
from orchestrator.errors import NavfmuError, SimulationError, WiringError
from orchestrator.model.ssp import load_ssd
from test_master import ACC, CHAIN, GAIN, RAMP, REGISTRY, Ramp, chain_model


class Labelled(Component):
    """A Real output without a unit (not even the dimensionless "1"), a String output and a
    notice at its first step."""
    model_name = "Labelled"
    parameters = (real("bias"),)
    inputs = (real("u"),)
    outputs = (Port("y", "Real", ""), string("label"))

    def initialize(self, start_time):
        return {"y": 0.0, "label": "start"}

    def step(self, t, h, inputs):
        if t == self.initial_time:
            self.notify(f"first step at t = {t}")
        return {"y": inputs["u"] + self.params["bias"], "label": "stepped"}


class ShiftedUnitRamp(Ramp):
    """y = offset + t: a ramp with an offset but no slope (swapping it in drops 'slope')."""
    model_name = "ShiftedUnitRamp"
    parameters = (real("offset", "m"),)

    def _out(self, t, t_seen):
        return {"y": self.params["offset"] + t, "t_seen": t_seen, "steps": self.steps,
                "odd": bool(self.steps % 2)}


class LimitedRamp(Ramp):
    """A ramp that cannot run past ``last_time`` (as a replayed log cannot)."""
    model_name = "LimitedRamp"
    parameters = Ramp.parameters + (real("last_time", "s", start=2.0),)

    def check_stop_time(self, stop_time):
        if stop_time > self.params["last_time"]:
            raise ParameterError(f"cannot run to {stop_time} s, only to "
                                 f"{self.params['last_time']} s")


TOYS = {**REGISTRY, "Labelled": Labelled, "ShiftedUnitRamp": ShiftedUnitRamp,
        "LimitedRamp": LimitedRamp}


def simulation(model, **options):
    return Simulation(model, backend="direct", registry=TOYS, **options)


# ----------------------------------------------------------------------------------------
# rules 1 and 2: base step, decimation, run length
# ----------------------------------------------------------------------------------------
def test_a_base_step_given_replaces_the_model_s_and_sets_the_decimation(write_ssd):
    sim = simulation(chain_model(write_ssd), base_step=0.5)
    assert sim.base_step == 0.5 and sim.decimation == {"acc": 2, "gain": 1, "ramp": 1}
    res = sim.run()
    np.testing.assert_array_equal(res.time, np.arange(7) * 0.5)
    # acc (hint 1.0 = 2 base steps) steps at rows 2, 4, 6 over [t - 1, t] with u = 2 t
    np.testing.assert_array_equal(res.column("acc", "s"), [0, 0, 2, 2, 6, 6, 12])
    assert res.metadata["base_step"] == 0.5 and res.metadata["n_steps"] == 6
    # a hint equal to the base step: every macro step
    assert simulation(chain_model(write_ssd), base_step=1.0).decimation["acc"] == 1


@pytest.mark.parametrize("base_step", [0.0, -0.25])
def test_a_base_step_not_positive_is_refused(write_ssd, base_step):
    with pytest.raises(NavfmuError, match="the base step must be > 0"):
        simulation(chain_model(write_ssd), base_step=base_step)


@pytest.mark.parametrize("base_step", [0.3, 4.0, 0.25 * (1 + 1.5e-9)])
def test_a_step_hint_not_a_multiple_of_the_base_step_is_refused(write_ssd, base_step):
    """1.0 / 0.3 = 3.33; 1.0 / 4.0 rounds to 0 steps; 1.0 / (0.25 (1 + 1.5e-9)) is 4 - 6e-9,
    off by more than 1e-9 of the ratio (4e-9)."""
    with pytest.raises(NavfmuError, match="component 'acc': its step 1.0 s is not an integer "
                                          "multiple of the base step"):
        simulation(chain_model(write_ssd), base_step=base_step)


def test_a_step_hint_within_the_relative_tolerance_is_a_multiple(write_ssd):
    """1.0 / (0.25 (1 + 5e-10)) is 4 - 2e-9: within 1e-9 of the ratio (4e-9), not within
    1e-9 / ratio (2.5e-10)."""
    assert simulation(chain_model(write_ssd), base_step=0.25 * (1 + 5e-10)).decimation["acc"] == 4


@pytest.mark.parametrize("record_every", [0, -2, 1.5])
def test_record_every_must_be_a_positive_integer(write_ssd, record_every):
    with pytest.raises(NavfmuError, match="record_every must be a positive integer"):
        simulation(chain_model(write_ssd), record_every=record_every)


def test_record_every_as_a_float_integer_records_every_second_row(write_ssd):
    res = simulation(chain_model(write_ssd), record_every=2.0).run()
    np.testing.assert_array_equal(res.time, np.arange(7) * 0.5)
    np.testing.assert_array_equal(res.column("ramp", "y"), np.arange(7) * 0.5)
    assert res.metadata["record_every"] == 2 and type(res.metadata["record_every"]) is int


@pytest.mark.parametrize("stop", [0.0, -1.0])
def test_a_stop_time_not_after_the_start_is_refused(write_ssd, stop):
    with pytest.raises(NavfmuError, match=f"the stop time {stop} must be greater than"):
        simulation(chain_model(write_ssd)).run(stop_time=stop)


def test_a_run_of_one_base_step(write_ssd):
    calls = []
    res = simulation(chain_model(write_ssd)).run(
        stop_time=0.25, progress=lambda done, total: calls.append((done, total)))
    np.testing.assert_array_equal(res.time, [0.0, 0.25])
    np.testing.assert_array_equal(res.column("gain", "y"), [0.0, 0.5])
    assert res.metadata["n_steps"] == 1 and calls == [(1, 1)]


def test_the_stop_time_reaches_the_components_at_initialization(write_ssd, tmp_path):
    """LimitedRamp refuses a run past its last_time 2.0: the run to 3.0 fails, the run to 2.0
    does not."""
    model = chain_model(write_ssd).replace_source("ramp", tmp_path / "LimitedRamp.fmu")
    with pytest.raises(SimulationError, match="component 'ramp' \\(LimitedRamp\\): cannot "
                                              "run to 3.0 s, only to 2.0 s"):
        simulation(model).run()
    assert simulation(model).run(stop_time=2.0).metadata["n_steps"] == 8


def test_the_run_length_tolerance_is_relative_to_the_number_of_steps(write_ssd):
    """Base step 0.25: a stop of 3 (1 + 5e-10) is 12 (1 + 5e-10) steps, off by 6e-9 < 12e-9;
    one of 0.25 (1 + 1.5e-9) is 1 + 1.5e-9 steps, off by more than 1e-9 of max(ratio, 1)."""
    sim = simulation(chain_model(write_ssd), record=["ramp.y"])
    res = sim.run(stop_time=3.0 * (1 + 5e-10))
    assert res.metadata["n_steps"] == 12
    np.testing.assert_array_equal(res.time, np.arange(13) * 0.25)
    with pytest.raises(NavfmuError, match="not an integer number of base steps of 0.25 s"):
        sim.run(stop_time=0.25 * (1 + 1.5e-9))
    with pytest.raises(NavfmuError, match="not an integer number of base steps"):
        sim.run(stop_time=0.1)              # 0.4 steps: rounds to none


def test_a_stop_time_given_as_an_integer_is_a_float_in_the_metadata(write_ssd):
    res = simulation(chain_model(write_ssd), record=["ramp.y"]).run(stop_time=2)
    assert res.metadata["n_steps"] == 8
    assert res.metadata["stop_time"] == 2.0 and type(res.metadata["stop_time"]) is float


def test_a_run_from_a_later_start_time_stamps_its_rows_from_it(write_ssd):
    model = load_ssd(write_ssd(ssd_text(ACC + GAIN + RAMP, CHAIN, base_step=0.25, start=1.0,
                                        stop=3.0)))
    res = simulation(model, record_every=2).run()
    np.testing.assert_array_equal(res.time, 1.0 + np.arange(5) * 0.5)
    np.testing.assert_array_equal(res.column("ramp", "y"), res.time)
    # acc's windows end 4 and 8 base steps after the start: [1, 2] and [2, 3], u = 2 t
    np.testing.assert_array_equal(res.column("acc", "s"), [0, 0, 4, 4, 10])
    assert (res.metadata["start_time"], res.metadata["stop_time"]) == (1.0, 3.0)


# ----------------------------------------------------------------------------------------
# rules 3, 4 and 3J: the loop under Jacobi
# ----------------------------------------------------------------------------------------
ADDERS = (component_xml("a", "Adder.fmu", [("u", "input", "Real"), ("y", "output", "Real")])
          + component_xml("b", "Adder.fmu", [("u", "input", "Real"), ("y", "output", "Real")],
                          parameters={"y0": ("Real", 10.0)}))
LOOP = connection_xml("b.y", "a.u") + connection_xml("a.y", "b.u")


def test_jacobi_delays_no_connection_of_a_loop(write_ssd):
    """Every connection is one step late: a(k+1) = b(k) + 1 and b(k+1) = a(k) + 1 from
    a(0) = 0, b(0) = 10 (the adders' initial outputs)."""
    model = load_ssd(write_ssd(ssd_text(ADDERS, LOOP, base_step=1.0, stop=3.0)))
    sim = simulation(model, algorithm="jacobi")
    assert sim.order == ["a", "b"] and sim.delayed_connections == []
    res = sim.run()
    np.testing.assert_array_equal(res.column("a", "y"), [0, 11, 2, 13])
    np.testing.assert_array_equal(res.column("b", "y"), [10, 1, 12, 3])
    assert res.metadata["delayed_connections"] == []
    assert res.metadata["algorithm"] == "jacobi"


# ----------------------------------------------------------------------------------------
# rule 8: wiring checks
# ----------------------------------------------------------------------------------------
def _labelled(connectors):
    return component_xml("lab", "Labelled.fmu", connectors)


def test_a_connection_from_an_input_is_refused(write_ssd):
    """The SSD calls gain's u an output; the component's u is an input."""
    gain = component_xml("gain", "Gain.fmu", [("u", "output", "Real"), ("y", "output", "Real")])
    lab = _labelled([("u", "input", "Real")])
    model = load_ssd(write_ssd(ssd_text(gain + lab, connection_xml("gain.u", "lab.u"))))
    with pytest.raises(WiringError, match="variable 'u' has causality 'input'"):
        simulation(model)


def test_a_connection_into_an_output_is_refused(write_ssd):
    gain = component_xml("gain", "Gain.fmu", [("y", "output", "Real")])
    lab = _labelled([("y", "input", "Real")])
    model = load_ssd(write_ssd(ssd_text(gain + lab, connection_xml("gain.y", "lab.y"))))
    with pytest.raises(WiringError, match="variable 'y' has causality 'output'"):
        simulation(model)


def test_a_connector_declared_with_another_type_is_refused(write_ssd):
    """ramp.steps is an Integer; the SSD declares it (and acc.count_in) Real."""
    ramp = RAMP.replace('name="steps" kind="output"><ssc:Integer',
                        'name="steps" kind="output"><ssc:Real')
    acc = ACC.replace('name="count_in" kind="input"><ssc:Integer',
                      'name="count_in" kind="input"><ssc:Real')
    assert ramp != RAMP and acc != ACC
    model = load_ssd(write_ssd(ssd_text(acc + GAIN + ramp, CHAIN, base_step=0.25)))
    with pytest.raises(WiringError, match="variable 'steps' is a Integer, but the system "
                                          "structure declares it as Real"):
        simulation(model)


def test_a_connection_to_a_connector_the_model_does_not_declare_is_checked_by_the_component(
        write_ssd):
    """A model built in code may leave a component's connectors out: no declared type to
    compare, the component's own variables decide (acc.u Real, acc.count_in Integer)."""
    model = chain_model(write_ssd)
    bare = [dataclasses.replace(c, connectors={}) if c.name == "acc" else c
            for c in model.components]
    res = simulation(dataclasses.replace(model, components=bare)).run()
    np.testing.assert_array_equal(res.column("acc", "s")[[4, 8, 12]], [2, 6, 12])
    np.testing.assert_array_equal(res.column("acc", "last_count")[[4, 8, 12]], [4, 8, 12])


def test_a_string_variable_cannot_be_connected(write_ssd):
    src = _labelled([("label", "output", "String")])
    dest = component_xml("dest", "Labelled.fmu", [("u", "input", "String")])
    model = load_ssd(write_ssd(ssd_text(src + dest, connection_xml("lab.label", "dest.u"))))
    with pytest.raises(WiringError, match="variable 'label' is a String; only Real"):
        simulation(model)


# ----------------------------------------------------------------------------------------
# rule 5: parameters and overrides
# ----------------------------------------------------------------------------------------
def test_an_override_sets_an_unconnected_input_s_start_value(write_ssd):
    """acc.count_in not connected: the override is its value at every step."""
    chain = connection_xml("ramp.y", "gain.u") + connection_xml("gain.y", "acc.u")
    model = load_ssd(write_ssd(ssd_text(ACC + GAIN + RAMP, chain, base_step=0.25, stop=3.0)))
    res = simulation(model, parameters={"acc.count_in": 7}).run()
    np.testing.assert_array_equal(res.column("acc", "last_count")[[0, 4, 8, 12]], [0, 7, 7, 7])
    assert res.metadata["parameters"]["acc"] == {"count_in": 7}


def test_a_swap_skips_each_parameter_the_new_component_lacks_and_sets_the_others(
        write_ssd, tmp_path):
    """The SSD sets the ramp's slope, then its offset; ShiftedUnitRamp has only the offset."""
    ramp = component_xml("ramp", "Ramp.fmu", [("y", "output", "Real", "m"),
                                              ("steps", "output", "Integer")],
                         parameters={"slope": ("Real", 3.0), "offset": ("Real", 0.5)})
    model = load_ssd(write_ssd(ssd_text(ACC + GAIN + ramp, CHAIN, base_step=0.25, stop=1.0)))
    swapped = model.replace_source("ramp", tmp_path / "ShiftedUnitRamp.fmu")
    with pytest.warns(UserWarning, match="skipped: ramp.slope$"):
        sim = simulation(swapped)
    assert sim.skipped_parameters == ["ramp.slope"]
    np.testing.assert_array_equal(sim.run().column("ramp", "y"), 0.5 + np.arange(5) * 0.25)


def test_an_override_of_an_unknown_component_is_named_as_an_override(write_ssd):
    with pytest.raises(WiringError, match="^parameter override 'gane.k': no component named "
                                          "'gane' \\(components: acc, gain, ramp\\)"):
        simulation(chain_model(write_ssd), parameters={"gane.k": 1.0})


def test_an_ssd_parameter_that_is_an_output_is_refused(write_ssd):
    gain = GAIN.replace('name="k"', 'name="y"')
    model = load_ssd(write_ssd(ssd_text(ACC + gain + RAMP, CHAIN, base_step=0.25)))
    with pytest.raises(WiringError, match="sets parameter 'y', which has causality 'output'"):
        simulation(model)


@pytest.mark.parametrize("key, message", [
    ("gain.y", "component 'gain' .* has no parameter 'y' \\(it is an output\\)"),
    ("gain", "component 'gain' .* has no parameter ''"),
])
def test_an_override_of_an_output_or_of_no_variable_is_refused(write_ssd, key, message):
    with pytest.raises(WiringError, match=message):
        simulation(chain_model(write_ssd), parameters={key: 1.0})


def test_ssd_parameters_then_overrides_reach_the_components(write_ssd):
    res = simulation(chain_model(write_ssd), parameters={"ramp.offset": 0.5}).run()
    # the SSD's slope 1.0 and k 2.0 with the offset given
    np.testing.assert_array_equal(res.column("gain", "y")[1:], 2.0 * (0.5 + res.time[1:]))
    assert res.metadata["parameters"] == {"acc": {}, "gain": {"k": 2.0},
                                          "ramp": {"slope": 1.0, "offset": 0.5}}


# ----------------------------------------------------------------------------------------
# rule 6: what is recorded
# ----------------------------------------------------------------------------------------
def test_a_component_named_alone_records_all_its_outputs_in_variable_order(write_ssd):
    res = simulation(chain_model(write_ssd), record="ramp").run()
    assert res.columns == {"acc": [], "gain": [], "ramp": ["y", "t_seen", "steps", "odd"]}
    np.testing.assert_array_equal(res.column("ramp", "steps"), np.arange(13))
    np.testing.assert_array_equal(res.column("ramp", "odd"), np.arange(13) % 2)


def test_picked_outputs_keep_variable_order_and_connected_ones_still_flow(write_ssd):
    """ramp.odd and ramp.y picked (in variable order y, odd); acc reads gain.y and ramp.steps,
    which are not recorded but still exchanged."""
    res = simulation(chain_model(write_ssd), record=["ramp.odd", "ramp.y", "acc.s"]).run()
    assert res.columns == {"acc": ["s"], "gain": [], "ramp": ["y", "odd"]}
    np.testing.assert_array_equal(res.data["ramp"],
                                  np.c_[np.arange(13) * 0.25, np.arange(13) % 2])
    np.testing.assert_array_equal(res.column("acc", "s"), [0, 0, 0, 0, 2, 2, 2, 2, 6, 6, 6, 6,
                                                           12])


@pytest.mark.parametrize("item", ["gain.u", "gain.zz", "lab.label"])
def test_recording_an_input_an_unknown_or_a_string_variable_is_refused(write_ssd, item):
    lab = _labelled([("u", "input", "Real")])
    model = load_ssd(write_ssd(ssd_text(GAIN + lab, connection_xml("gain.y", "lab.u"))))
    with pytest.raises(WiringError, match=f"record '{item}': component .* has no Real/Integer/"
                                          "Boolean output"):
        simulation(model, record=[item])


def test_recording_an_unknown_component_is_refused(write_ssd):
    with pytest.raises(WiringError, match="^record 'pump.y': no component named 'pump'"):
        simulation(chain_model(write_ssd), record=["pump.y"])


def test_units_come_from_the_component_or_else_from_the_ssd(write_ssd):
    """Labelled's y has no unit of its own: the SSD's connector unit; gain's y is its own 'm'
    (a connector in another unit is refused: tests/test_bad_inputs.py); the String output is
    never recorded."""
    gain = component_xml("gain", "Gain.fmu", [("u", "input", "Real"),
                                              ("y", "output", "Real", "m")])
    lab = _labelled([("u", "input", "Real"), ("y", "output", "Real", "V")])
    model = load_ssd(write_ssd(ssd_text(gain + lab, connection_xml("gain.y", "lab.u"),
                                        stop=0.2)))
    res = simulation(model).run()
    assert res.columns == {"gain": ["y"], "lab": ["y"]}
    assert res.units == {"gain": ["m"], "lab": ["V"]}
    assert res.metadata["warnings"] == ["lab: first step at t = 0.0"]


# ----------------------------------------------------------------------------------------
# streaming, progress, results
# ----------------------------------------------------------------------------------------
class ListSink:
    """A sink keeping the chunks it is handed (``chunk_rows`` rows at most each)."""

    def __init__(self, chunk_rows):
        self.chunk_rows = chunk_rows
        self.chunks, self.closed_with, self.aborted = [], None, False

    def write(self, chunk):
        self.chunks.append(chunk)

    def close(self, header):
        self.closed_with = header

    def abort(self):
        self.aborted = True


@pytest.mark.parametrize("record_every, sizes", [(1, [5, 5, 3]), (2, [5, 2])])
def test_a_streamed_run_hands_its_rows_in_chunks_and_keeps_none(write_ssd, record_every,
                                                                sizes):
    in_memory = simulation(chain_model(write_ssd), record_every=record_every).run()
    sink = ListSink(chunk_rows=5)
    res = simulation(chain_model(write_ssd), record_every=record_every).run(sink=sink)
    assert [len(c.time) for c in sink.chunks] == sizes
    np.testing.assert_array_equal(np.concatenate([c.time for c in sink.chunks]), in_memory.time)
    for name in ("acc", "gain", "ramp"):
        np.testing.assert_array_equal(np.concatenate([c.data[name] for c in sink.chunks]),
                                      in_memory.data[name])
        assert res.data[name].shape == (0, len(in_memory.columns[name]))
    assert res.columns == in_memory.columns and res.units == in_memory.units
    assert len(res.time) == 0 and sink.closed_with is res and not sink.aborted
    assert res.metadata["n_steps"] == 12


def test_a_failing_streamed_run_aborts_its_sink_and_terminates_every_instance(
        write_ssd, tmp_path, monkeypatch):
    from orchestrator.cosim.direct_instance import DirectInstance

    terminated = []
    monkeypatch.setattr(DirectInstance, "terminate", lambda self: terminated.append(self.name))
    model = chain_model(write_ssd).replace_source("gain", tmp_path / "LimitedGain.fmu")
    sink = ListSink(chunk_rows=5)
    with pytest.raises(SimulationError, match="component 'gain'"):
        simulation(model, parameters={"gain.limit": 1.3}).run(sink=sink)
    assert sink.aborted and sink.closed_with is None
    assert sorted(terminated) == ["acc", "gain", "ramp"]


def _progress_calls(write_ssd, stop, **options):
    calls = []
    simulation(chain_model(write_ssd, stop=stop), record=["ramp.y"], **options).run(
        progress=lambda done, total: calls.append((done, total)))
    return calls


def test_progress_is_called_every_hundredth_of_the_run_and_once_at_its_end(write_ssd):
    # 301 steps: every 3 (301 // 100) and at 301; 250 steps: every 2, 250 only once
    assert _progress_calls(write_ssd, 75.25) == [(k, 301) for k in range(3, 301, 3)] + [
        (301, 301)]
    assert _progress_calls(write_ssd, 62.5) == [(k, 250) for k in range(2, 251, 2)]
    assert _progress_calls(write_ssd, 1.0) == [(1, 4), (2, 4), (3, 4), (4, 4)]


def test_a_run_without_progress_of_a_length_not_a_multiple_of_its_hundredth(write_ssd):
    res = simulation(chain_model(write_ssd, stop=75.25), record=["ramp.y"]).run()
    assert res.metadata["n_steps"] == 301 and res.column("ramp", "y")[-1] == 75.25


def test_a_component_never_due_holds_its_outputs_and_has_no_step_time(write_ssd):
    """acc steps every 4 base steps: in a run of 3 it is never due."""
    res = simulation(chain_model(write_ssd, stop=0.75)).run()
    np.testing.assert_array_equal(res.column("acc", "s"), [0, 0, 0, 0])
    assert res.metadata["step_calls"] == {"acc": 0, "gain": 3, "ramp": 3}
    assert math.isnan(res.step_time_s["acc"]) and math.isnan(res.exchange_step_time_s["acc"])
    assert res.step_time_s["gain"] > 0 and res.exchange_step_time_s["gain"] > 0


def test_the_metadata_of_a_run(write_ssd, tmp_path):
    model = chain_model(write_ssd).replace_source("gain", tmp_path / "LimitedGain.fmu")
    res = simulation(model, parameters={"gain.limit": 100.0}).run(stop_time=2.0)
    meta = res.metadata
    module = "Python component test_master."
    assert {k: meta[k] for k in ("model", "backend", "algorithm", "base_step", "start_time",
                                 "stop_time", "n_steps", "record_every")} == {
        "model": "toy", "backend": "direct", "algorithm": "gauss-seidel", "base_step": 0.25,
        "start_time": 0.0, "stop_time": 2.0, "n_steps": 8, "record_every": 1}
    assert meta["ssd"] == str(model.path)
    assert meta["order"] == ["ramp", "gain", "acc"]
    assert meta["decimation"] == {"acc": 4, "gain": 1, "ramp": 1}
    assert meta["sources"] == {"acc": module + "Accumulator", "gain": module + "LimitedGain",
                               "ramp": module + "Ramp"}
    assert meta["model_names"] == {"acc": "Accumulator", "gain": "LimitedGain", "ramp": "Ramp"}
    assert meta["replaced_sources"] == {"gain": str(model.path.parent / "Gain.fmu")}
    assert meta["skipped_parameters"] == []
    assert meta["parameters"] == {"acc": {}, "gain": {"k": 2.0, "limit": 100.0},
                                  "ramp": {"slope": 1.0}}
    assert meta["step_calls"] == {"acc": 2, "gain": 8, "ramp": 8}
    assert meta["warnings"] == [] and meta["wall_time_s"] > 0


def test_simulate_is_simulation_then_run(write_ssd):
    calls = []
    res = simulate(chain_model(write_ssd), "direct", stop_time=1.0,
                   progress=lambda done, total: calls.append((done, total)), registry=TOYS,
                   record=["ramp.y"], record_every=2)
    np.testing.assert_array_equal(res.time, [0.0, 0.5, 1.0])
    np.testing.assert_array_equal(res.column("ramp", "y"), [0.0, 0.5, 1.0])
    assert calls == [(1, 4), (2, 4), (3, 4), (4, 4)]
    assert res.metadata["backend"] == "direct"


def test_the_fmus_are_run_unless_told_otherwise(write_ssd):
    """The chain model's sources, Accumulator.fmu and the others, are not files: the FMU
    backend, the default, refuses the first component declared."""
    with pytest.raises(NavfmuError, match="component 'acc': FMU file not found"):
        simulate(chain_model(write_ssd))
    with pytest.raises(NavfmuError, match="component 'acc': FMU file not found"):
        Simulation(chain_model(write_ssd))


def test_the_direct_backend_needs_a_registry(write_ssd):
    with pytest.raises(NavfmuError, match="the 'direct' backend needs a registry"):
        Simulation(chain_model(write_ssd), backend="direct")
