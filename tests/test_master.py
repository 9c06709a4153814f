"""The master's stepping semantics with toy Python components (exact numbers)."""
from __future__ import annotations

import os

import numpy as np
import pytest

from conftest import component_xml, connection_xml, ssd_text
from navcore.core.component import Component, InputError, boolean, integer, real
from orchestrator.results import run_results as results_module
from orchestrator.errors import NavfmuError, SimulationError, WiringError
from orchestrator.cosim.master import Simulation, step_order
from orchestrator.results.run_results import Results
from orchestrator.model.ssp import Connection, load_ssd


# -- toy components ---------------------------------------------------------------------
class Ramp(Component):
    """y = offset + slope * t; ``t_seen`` is the t of the last step call."""
    model_name = "Ramp"
    parameters = (real("slope", "m/s", start=1.0), real("offset", "m"))
    outputs = (real("y", "m"), real("t_seen", "s"), integer("steps"), boolean("odd"))

    def initialize(self, start_time):
        self.steps = 0
        return self._out(start_time, start_time)

    def _out(self, t, t_seen):
        return {"y": self.params["offset"] + self.params["slope"] * t, "t_seen": t_seen,
                "steps": self.steps, "odd": bool(self.steps % 2)}

    def step(self, t, h, inputs):
        self.steps += 1
        return self._out(t + h, t)


class Gain(Component):
    """y = k * u with the input given at this step."""
    model_name = "Gain"
    parameters = (real("k", start=2.0),)
    inputs = (real("u", "m"),)
    outputs = (real("y", "m"),)

    def initialize(self, start_time):
        return {"y": 0.0}

    def step(self, t, h, inputs):
        self.check_inputs(inputs, ["u"])
        if inputs["u"] > self.params.get("limit", np.inf):
            raise InputError(f"{self.model_name}: input 'u' = {inputs['u']} is too large")
        return {"y": self.params["k"] * inputs["u"]}


class LimitedGain(Gain):
    model_name = "LimitedGain"
    parameters = Gain.parameters + (real("limit", start=1.0),)


class Accumulator(Component):
    """s += u * h per call; also reports the (t, h) it was called with and its input count."""
    model_name = "Accumulator"
    inputs = (real("u", "m"), integer("count_in"))
    outputs = (real("s", "m.s"), real("t0", "s"), real("h", "s"), integer("last_count"))
    state_fields = ("s",)

    def initialize(self, start_time):
        self.s = 0.0
        return {"s": 0.0, "t0": start_time, "h": 0.0, "last_count": 0}

    def step(self, t, h, inputs):
        self.s += inputs["u"] * h
        return {"s": self.s, "t0": t, "h": h, "last_count": inputs["count_in"]}


class Adder(Component):
    """y(after step) = u + 1; y(start) = y0."""
    model_name = "Adder"
    parameters = (real("y0"),)
    inputs = (real("u"),)
    outputs = (real("y"),)

    def initialize(self, start_time):
        return {"y": self.params["y0"]}

    def step(self, t, h, inputs):
        return {"y": inputs["u"] + 1.0}


class UnitRamp(Ramp):
    """A ramp without parameters (slope 1): swapping it in drops the SSD's 'slope'."""
    model_name = "UnitRamp"
    parameters = ()

    def _out(self, t, t_seen):
        return {"y": t, "t_seen": t_seen, "steps": self.steps, "odd": bool(self.steps % 2)}


class GainWithoutU(Component):
    model_name = "GainWithoutU"
    inputs = (real("x", "m"),)
    outputs = (real("y", "m"),)

    def initialize(self, start_time):
        return {"y": 0.0}

    def step(self, t, h, inputs):
        return {"y": inputs["x"]}


REGISTRY = {c.model_name: c for c in (Ramp, UnitRamp, Gain, LimitedGain, Accumulator, Adder,
                                      GainWithoutU)}

RAMP = component_xml("ramp", "Ramp.fmu", [("y", "output", "Real", "m"),
                                          ("steps", "output", "Integer")],
                     parameters={"slope": ("Real", 1.0)})
GAIN = component_xml("gain", "Gain.fmu", [("u", "input", "Real"), ("y", "output", "Real")],
                     parameters={"k": ("Real", 2.0)})
ACC = component_xml("acc", "Accumulator.fmu", [("u", "input", "Real"),
                                               ("count_in", "input", "Integer")], step_hint=1.0)
CHAIN = (connection_xml("ramp.y", "gain.u") + connection_xml("gain.y", "acc.u")
         + connection_xml("ramp.steps", "acc.count_in"))


def chain_model(write_ssd, stop=3.0):
    # declared in reverse order: the topological order must still be ramp, gain, acc
    return load_ssd(write_ssd(ssd_text(ACC + GAIN + RAMP, CHAIN, base_step=0.25, stop=stop)))


def run_direct(model, **kw):
    return Simulation(model, backend="direct", registry=REGISTRY, **kw).run()


# -- ordering ---------------------------------------------------------------------------
def test_step_order_ties_by_declaration_and_cycles():
    assert step_order(3, [(2, 1, "c->b"), (1, 0, "b->a")]) == ([2, 1, 0], [])
    assert step_order(3, []) == ([0, 1, 2], [])
    # cycle 1 <-> 2 fed by 0: the earliest-declared member (1) has its in-cycle input delayed
    order, delayed = step_order(4, [(0, 1, "a"), (1, 2, "b"), (2, 1, "c"), (3, 0, "d")])
    assert (order, delayed) == ([3, 0, 1, 2], ["c"])
    # self-loop is always delayed and does not block
    assert step_order(2, [(0, 0, "self"), (0, 1, "x")]) == ([0, 1], ["self"])
    # three-cycle: connections into the earliest (0) from the cycle are delayed
    assert step_order(3, [(0, 1, "a"), (1, 2, "b"), (2, 0, "c"), (1, 0, "e")]) == \
        ([0, 1, 2], ["c", "e"])


def test_order_gauss_seidel_decimation_and_hold(write_ssd):
    sim = Simulation(chain_model(write_ssd), backend="direct", registry=REGISTRY)
    assert sim.order == ["ramp", "gain", "acc"]
    assert sim.decimation == {"acc": 4, "gain": 1, "ramp": 1}
    assert sim.delayed_connections == []
    res = sim.run()
    t = res.time
    np.testing.assert_array_equal(t, np.arange(13) * 0.25)
    # ramp at row j is y(t_j); it was called with t = t_{j-1}
    np.testing.assert_array_equal(res.column("ramp", "y"), t)
    np.testing.assert_array_equal(res.column("ramp", "t_seen")[1:], t[:-1])
    # gain sees the ramp's output at the end of the same macro step (Gauss-Seidel)
    np.testing.assert_array_equal(res.column("gain", "y"), 2 * t)
    # acc (step 1.0 = 4 base steps) steps at rows 4, 8, 12 over [t-1, t] with u = 2 t
    s = res.column("acc", "s")
    np.testing.assert_array_equal(s, [0, 0, 0, 0, 2, 2, 2, 2, 6, 6, 6, 6, 12])
    np.testing.assert_array_equal(res.column("acc", "t0")[[3, 4, 7, 8, 12]], [0, 0, 0, 1, 2])
    np.testing.assert_array_equal(res.column("acc", "h")[[3, 4, 12]], [0, 1, 1])
    # the Integer connection carries the ramp's step counter at the acc's step
    np.testing.assert_array_equal(res.column("acc", "last_count")[[4, 8, 12]], [4, 8, 12])
    np.testing.assert_array_equal(res.column("ramp", "odd")[:4], [0, 1, 0, 1])
    assert res.metadata["step_calls"] == {"acc": 3, "gain": 12, "ramp": 12}
    assert res.units["acc"] == ["m.s", "s", "s", ""]
    assert set(res.step_time_s) == {"acc", "gain", "ramp"}
    assert all(v > 0 for v in res.step_time_s.values())


def test_partial_last_interval_holds_and_progress(write_ssd):
    calls = []
    sim = Simulation(chain_model(write_ssd, stop=2.5), backend="direct", registry=REGISTRY)
    res = sim.run(progress=lambda done, total: calls.append((done, total)))
    assert calls == [(k, 10) for k in range(1, 11)]
    # 10 steps: acc (every 4) is due at 4 and 8 only and holds to the end
    np.testing.assert_array_equal(res.column("acc", "s")[-3:], [6, 6, 6])
    assert res.metadata["step_calls"]["acc"] == 2


def test_parameters_overrides_and_record_selection(write_ssd):
    res = run_direct(chain_model(write_ssd), parameters={"ramp.offset": 1.0, "gain.k": -1},
                     record=["gain", "ramp.y"], record_every=2)
    assert res.columns == {"acc": [], "gain": ["y"], "ramp": ["y"]}
    np.testing.assert_array_equal(res.time, np.arange(7) * 0.5)
    # row 0 is the gain's own initial output (0); then y = k * (offset + t)
    np.testing.assert_array_equal(res.column("gain", "y"), np.r_[0.0, -(1 + res.time[1:])])
    assert res.metadata["parameters"]["gain"] == {"k": -1}


def test_algebraic_loop_delays_connection_into_earliest_declared(write_ssd):
    a = component_xml("a", "Adder.fmu", [("u", "input", "Real"), ("y", "output", "Real")])
    b = component_xml("b", "Adder.fmu", [("u", "input", "Real"), ("y", "output", "Real")],
                      parameters={"y0": ("Real", 10.0)})
    loop = connection_xml("b.y", "a.u") + connection_xml("a.y", "b.u")
    sim = Simulation(load_ssd(write_ssd(ssd_text(a + b, loop, base_step=1.0, stop=3.0))),
                     backend="direct", registry=REGISTRY)
    assert sim.order == ["a", "b"]
    assert sim.delayed_connections == [Connection("b", "y", "a", "u")]
    res = sim.run()
    # a sees b's previous value; b sees a's new value
    np.testing.assert_array_equal(res.column("a", "y"), [0, 11, 13, 15])
    np.testing.assert_array_equal(res.column("b", "y"), [10, 12, 14, 16])
    assert res.metadata["delayed_connections"] == ["b.y -> a.u"]


def test_self_loop_sees_previous_output(write_ssd):
    a = component_xml("a", "Adder.fmu", [("u", "input", "Real"), ("y", "output", "Real")])
    sim = Simulation(load_ssd(write_ssd(ssd_text(a, connection_xml("a.y", "a.u"),
                                                 base_step=1.0, stop=3.0))),
                     backend="direct", registry=REGISTRY)
    np.testing.assert_array_equal(sim.run().column("a", "y"), [0, 1, 2, 3])


def test_swap_with_missing_variable_names_it(write_ssd, tmp_path):
    model = chain_model(write_ssd)
    swapped = model.replace_source("gain", tmp_path / "GainWithoutU.fmu")
    with pytest.raises(WiringError) as info:
        Simulation(swapped, backend="direct", registry=REGISTRY)
    msg = str(info.value)
    assert "component 'gain'" in msg and "no variable 'u'" in msg and "ramp.y -> gain.u" in msg
    assert "GainWithoutU" in msg


def test_swap_keeps_applicable_parameters(write_ssd, tmp_path):
    # LimitedGain has k (kept) and its own limit; a parameter it lacks would be skipped
    model = chain_model(write_ssd).replace_source("gain", tmp_path / "LimitedGain.fmu")
    sim = Simulation(model, backend="direct", registry=REGISTRY,
                     parameters={"gain.limit": 100.0})
    assert sim.skipped_parameters == []
    np.testing.assert_array_equal(sim.run().column("gain", "y"), 2 * np.arange(13) * 0.25)


def test_swap_skips_parameters_the_new_component_lacks(write_ssd, tmp_path):
    model = chain_model(write_ssd).replace_source("ramp", tmp_path / "UnitRamp.fmu")
    with pytest.warns(UserWarning, match="ramp.slope"):
        sim = Simulation(model, backend="direct", registry=REGISTRY)
    assert sim.skipped_parameters == ["ramp.slope"]
    res = sim.run()
    assert res.metadata["skipped_parameters"] == ["ramp.slope"]
    assert res.metadata["replaced_sources"] == {"ramp": str(model.path.parent / "Ramp.fmu")}


def _ssv(path, **values):
    params = "".join(f'<ssv:Parameter name="{k}"><ssv:Real value="{v}"/></ssv:Parameter>'
                     for k, v in values.items())
    path.write_text('<ssv:ParameterSet version="1.0" name="p" xmlns:ssv="http://ssp-standard.org/'
                    f'SSP1/SystemStructureParameterValues"><ssv:Parameters>{params}'
                    '</ssv:Parameters></ssv:ParameterSet>')


def test_swap_variant_file_applies_to_the_swapped_in_model_only(write_ssd, tmp_path):
    """gain.ssv binds k = 3; gain.LimitedGain.ssv (not in the .ssd) sets k = 5 and limit for a
    swap to LimitedGain only: the .ssd's own Gain, and a swap to another model, never read it."""
    gain = GAIN.replace('<ssd:ParameterBindings><ssd:ParameterBinding><ssd:ParameterValues>',
                        '<ssd:ParameterBindings><ssd:ParameterBinding source="gain.ssv"/>'
                        '</ssd:ParameterBindings><!--')
    gain = gain.replace('</ssd:ParameterBinding></ssd:ParameterBindings>', '-->')
    path = write_ssd(ssd_text(ACC + gain + RAMP, CHAIN, base_step=0.25, stop=3.0))
    _ssv(path.parent / "gain.ssv", k=3.0)
    _ssv(path.parent / "gain.LimitedGain.ssv", k=5.0, limit=100.0)
    model = load_ssd(path)
    assert model.component("gain").parameters == {"k": ("Real", 3.0)}
    np.testing.assert_array_equal(run_direct(model).column("gain", "y"), 3 * np.arange(13) * 0.25)
    swapped = model.replace_source("gain", tmp_path / "LimitedGain.fmu")
    np.testing.assert_array_equal(run_direct(swapped).column("gain", "y"),
                                  5 * np.arange(13) * 0.25)
    assert model.replace_source("gain", tmp_path / "Gain.fmu").component("gain").parameters == {
        "k": ("Real", 3.0)}
    # a variant written for a model must fit it: not skipped like the scenario's own parameters
    _ssv(path.parent / "gain.Gain.ssv", limit=1.0)
    with pytest.raises(WiringError, match="parameter 'limit', which does not exist"):
        Simulation(load_ssd(path).replace_source("gain", tmp_path / "Gain.fmu"),
                   backend="direct", registry=REGISTRY)


def test_direct_instance_state_round_trip():
    from orchestrator.cosim.direct_instance import DirectInstance

    inst = DirectInstance.from_registry("Accumulator", "acc", REGISTRY)
    inst.prepare(["u", "count_in"], ["s"])
    inst.initialize(0.0)
    inst.set_inputs(np.array([2.0]), np.array([1], dtype=np.int32))
    inst.do_step(0.0, 0.5)
    saved = inst.get_state()
    inst.do_step(0.5, 0.5)
    assert inst.get_outputs()[0][0] == 2.0
    inst.set_state(saved)
    assert inst.get_outputs()[0][0] == 1.0
    inst.do_step(0.5, 0.5)
    assert inst.get_outputs()[0][0] == 2.0


def test_wiring_errors_for_parameters_and_overrides(write_ssd):
    model = chain_model(write_ssd)
    with pytest.raises(WiringError, match="component 'gain' .* has no parameter 'kk'"):
        Simulation(model, backend="direct", registry=REGISTRY, parameters={"gain.kk": 1})
    with pytest.raises(WiringError, match="no component named 'gane'"):
        Simulation(model, backend="direct", registry=REGISTRY, parameters={"gane.k": 1})
    bad = ssd_text(ACC + GAIN.replace('name="k"', 'name="gain_k"') + RAMP, CHAIN, base_step=0.25)
    with pytest.raises(WiringError, match="sets parameter 'gain_k', which does not exist"):
        Simulation(load_ssd(write_ssd(bad)), backend="direct", registry=REGISTRY)
    with pytest.raises(NavfmuError, match="no Python component registered for model 'Accumulator'"):
        Simulation(model, backend="direct", registry={"Ramp": Ramp})
    with pytest.raises(NavfmuError, match="not an integer number of base steps"):
        Simulation(model, backend="direct", registry=REGISTRY).run(stop_time=1.1)


def test_failure_mid_run_names_component_and_time(write_ssd, tmp_path):
    model = chain_model(write_ssd).replace_source("gain", tmp_path / "LimitedGain.fmu")
    sim = Simulation(model, backend="direct", registry=REGISTRY, parameters={"gain.limit": 1.3})
    with pytest.raises(SimulationError) as info:
        sim.run()
    msg = str(info.value)
    # the ramp reaches 1.5 > 1.3 in the step ending at t = 1.5
    first, detail = msg.splitlines()[:2]
    assert (
        first.startswith("component 'gain' (LimitedGain): ") and "'u' = 1.5 is too large" in first
    )
    assert "(step from t = 1.25 s to t = 1.5 s failed)" in detail
    assert info.value.component == "gain" and info.value.time == 1.25


# -- results files ------------------------------------------------------------------------
def test_csv_header_round_trip_and_npz(write_ssd, tmp_path):
    res = run_direct(chain_model(write_ssd))
    path = res.to_csv(tmp_path / "out.csv")
    header = path.read_text().splitlines()[0]
    assert header.startswith("time [s],acc.s [m.s],acc.t0 [s],acc.h [s],acc.last_count,gain.y [m]")
    back = Results.from_csv(path)
    np.testing.assert_array_equal(back.time, res.time)
    for c in res.components:
        np.testing.assert_array_equal(back.data[c], res.data[c])
        assert back.columns[c] == res.columns[c] and back.units[c] == res.units[c]
    npz = Results.from_npz(res.to_npz(tmp_path / "out.npz"))
    np.testing.assert_array_equal(npz.column("acc", "s"), res.column("acc", "s"))
    assert npz.metadata["order"] == ["ramp", "gain", "acc"]
    assert npz.step_time_s == res.step_time_s
    assert sorted(os.listdir(tmp_path)) == ["out.csv", "out.npz", "system0"]


def test_failed_write_leaves_no_file(write_ssd, tmp_path, monkeypatch):
    res = run_direct(chain_model(write_ssd))
    out = tmp_path / "out"
    out.mkdir()

    def broken_writer(f, table, titles=None):
        f.write(b"0,1,2\n")  # half a file ...
        raise OSError("disk full")  # ... then the failure

    monkeypatch.setattr(results_module, "write_csv_table", broken_writer)
    with pytest.raises(NavfmuError, match=f"cannot write {out / 'r.csv'}: disk full"):
        res.to_csv(out / "r.csv")
    assert os.listdir(out) == []
    (out / "r.csv").write_text("previous")
    with pytest.raises(NavfmuError):
        res.to_csv(out / "r.csv")
    assert os.listdir(out) == ["r.csv"] and (out / "r.csv").read_text() == "previous"


def test_master_overhead_is_the_loop_time_outside_the_components(write_ssd, monkeypatch):
    """The master's timing bookkeeping on a clock the test drives (no wall time): each
    component's step takes a fixed time (ramp 3, gain 5, acc 7 us; acc steps every 4th macro
    step), reading its outputs 2 us, the master's own work is the progress callback (11 us
    each of its 100 calls), and reading the clock is free.  The size of the real overhead
    is a benchmark figure (`navfmu bench` prints it), not a pass/fail bound here."""
    from types import SimpleNamespace

    from orchestrator.cosim import exchange, macro_loop
    from orchestrator.cosim.direct_instance import DirectInstance

    clock = {"ns": 0}
    fake_time = SimpleNamespace(perf_counter_ns=lambda: clock["ns"])
    monkeypatch.setattr(exchange, "_time", fake_time)
    monkeypatch.setattr(macro_loop, "_time", fake_time)
    cost_ns = {Ramp: 3000, Gain: 5000, Accumulator: 7000}
    for cls, ns in cost_ns.items():
        def step(self, t, h, inputs, _step=cls.step, _ns=ns):
            clock["ns"] += _ns
            return _step(self, t, h, inputs)
        monkeypatch.setattr(cls, "step", step)

    def get_outputs(self, _get=DirectInstance.get_outputs):
        clock["ns"] += 2000
        return _get(self)
    monkeypatch.setattr(DirectInstance, "get_outputs", get_outputs)

    def progress(done, total):
        clock["ns"] += 11000

    res = Simulation(chain_model(write_ssd, stop=250.0), backend="direct",
                     registry=REGISTRY).run(progress=progress)
    n = res.metadata["n_steps"]
    assert n == 1000
    assert res.step_time_s == pytest.approx({"ramp": 3e-6, "gain": 5e-6, "acc": 7e-6},
                                            rel=1e-12)
    assert res.exchange_step_time_s == pytest.approx({"ramp": 5e-6, "gain": 7e-6, "acc": 9e-6},
                                                     rel=1e-12)
    components_ns = 1000 * 5000 + 1000 * 7000 + 250 * 9000
    assert res.metadata["wall_time_s"] == pytest.approx((components_ns + 100 * 11000) * 1e-9,
                                                        rel=1e-12)
    assert res.metadata["master_overhead_s_per_step"] == pytest.approx(100 * 11000e-9 / n,
                                                                       rel=1e-12)


# -- FMU back end (tiny pythonfmu FMUs built into a temporary folder) -------------------------
TOY_SCALER = '''
from pythonfmu.enums import Fmi2Status
from pythonfmu import Fmi2Slave, Fmi2Causality, Fmi2Variability, Real, Integer, Boolean


class ToyScaler(Fmi2Slave):
    """y = k * u; n counts the steps; big = y > 1; fails (Discard) when u > limit."""

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.k = 2.0
        self.limit = 1.0e9
        self.u = 0.0
        self.y = 0.0
        self.n = 0
        self.big = False
        for name in ("k", "limit"):
            self.register_variable(Real(name, causality=Fmi2Causality.parameter,
                                        variability=Fmi2Variability.tunable))
        self.register_variable(Real("u", causality=Fmi2Causality.input))
        self.register_variable(Real("y", causality=Fmi2Causality.output))
        self.register_variable(Integer("n", causality=Fmi2Causality.output))
        self.register_variable(Boolean("big", causality=Fmi2Causality.output))

    def do_step(self, current_time, step_size):
        if self.u > self.limit:
            self.log(f"input u = {self.u} exceeds the limit {self.limit} (100%)",
                     status=Fmi2Status.error)
            return False
        self.y = self.k * self.u
        self.n += 1
        self.big = self.y > 1.0
        return True
'''

TOY_RAMP = '''
from pythonfmu import Fmi2Slave, Fmi2Causality, Fmi2Variability, Real


class ToyRamp(Fmi2Slave):
    """y = slope * t at the end of each step."""

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.slope = 1.0
        self.y = 0.0
        self.register_variable(Real("slope", causality=Fmi2Causality.parameter,
                                    variability=Fmi2Variability.tunable))
        self.register_variable(Real("y", causality=Fmi2Causality.output))

    def do_step(self, current_time, step_size):
        self.y = self.slope * (current_time + step_size)
        return True
'''


@pytest.fixture(scope="module")
def toy_fmus(tmp_path_factory):
    import subprocess
    import sys

    root = tmp_path_factory.mktemp("toy_fmus")
    for name, text in (("ToyScaler", TOY_SCALER), ("ToyRamp", TOY_RAMP)):
        script = root / f"{name}.py"
        script.write_text(text)
        subprocess.run([sys.executable, "-m", "pythonfmu", "build", "-f", str(script),
                        "-d", str(root / "dist")], check=True, capture_output=True)
    return root / "dist"


def fmu_model(write_ssd, dist, k=3.0):
    ramp = component_xml("ramp", f"{dist}/ToyRamp.fmu", [("y", "output", "Real", "m")],
                         parameters={"slope": ("Real", 0.5)})
    scaler = component_xml("scaler", f"{dist}/ToyScaler.fmu",
                           [("u", "input", "Real", "m"), ("y", "output", "Real", "m")],
                           parameters={"k": ("Real", k)}, step_hint=0.2)
    return load_ssd(write_ssd(ssd_text(scaler + ramp, connection_xml("ramp.y", "scaler.u"),
                                       base_step=0.1, stop=1.0)))


def test_fmu_backend_runs_and_cleans_up(write_ssd, toy_fmus, tmp_path, monkeypatch):
    import tempfile

    extract_dir = tmp_path / "extract"
    extract_dir.mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(extract_dir))  # where fmpy extracts FMUs
    sim = Simulation(fmu_model(write_ssd, toy_fmus), backend="fmu")
    assert sim.order == ["ramp", "scaler"] and sim.decimation["scaler"] == 2
    res = sim.run()
    t = np.arange(11) * 0.1
    np.testing.assert_allclose(res.column("ramp", "y"), 0.5 * t, rtol=0, atol=1e-15)
    # scaler steps every 0.2 s with u = ramp at the end of its step; holds in between
    expected = np.array([0, 0, 0.3, 0.3, 0.6, 0.6, 0.9, 0.9, 1.2, 1.2, 1.5])
    np.testing.assert_allclose(res.column("scaler", "y"), expected, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(res.column("scaler", "n"), [0, 0, 1, 1, 2, 2, 3, 3, 4, 4, 5])
    np.testing.assert_array_equal(res.column("scaler", "big")[[7, 8]], [0, 1])
    assert res.units["scaler"] == ["m", "", ""]  # from the SSD connector (pythonfmu writes none)
    assert res.metadata["step_calls"] == {"scaler": 5, "ramp": 10}
    assert os.listdir(extract_dir) == []


def test_fmu_failure_names_component_time_and_log(write_ssd, toy_fmus, tmp_path, monkeypatch):
    import tempfile

    extract_dir = tmp_path / "extract"
    extract_dir.mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(extract_dir))
    sim = Simulation(fmu_model(write_ssd, toy_fmus), backend="fmu",
                     parameters={"scaler.limit": 0.35})
    with pytest.raises(SimulationError) as info:
        sim.run()
    msg = str(info.value)
    # the FMU's own message first, the failed call after it, the whole log kept
    first, detail = msg.splitlines()[:2]
    assert first.startswith("component 'scaler' (ToyScaler.fmu): ")
    assert "input u = 0.4 exceeds the limit 0.35 (100%)" in first
    assert "fmi2DoStep from t = 0.6 s to t = 0.8 s" in detail and "status Discard" in detail
    assert any("exceeds the limit" in line for line in info.value.log)
    assert info.value.time == pytest.approx(0.6)
    assert os.listdir(extract_dir) == []


def test_fmu_swap_with_missing_variable(write_ssd, toy_fmus):
    swapped = fmu_model(write_ssd, toy_fmus).replace_source("scaler", toy_fmus / "ToyRamp.fmu")
    with pytest.raises(WiringError) as info:
        Simulation(swapped, backend="fmu")
    msg = str(info.value)
    assert "component 'scaler'" in msg and "no variable 'u'" in msg
    assert str(toy_fmus / "ToyRamp.fmu") in msg


def test_fmu_instance_errors(tmp_path):
    from orchestrator.cosim.fmu_instance import FmuInstance

    with pytest.raises(NavfmuError, match="FMU file not found: .*nothing.fmu"):
        FmuInstance(tmp_path / "nothing.fmu", "x")
    bogus = tmp_path / "bogus.fmu"
    bogus.write_text("not a zip")
    with pytest.raises(NavfmuError, match="cannot read the model description of .*bogus.fmu"):
        FmuInstance(bogus, "x")


def test_direct_and_fmu_paths_agree(write_ssd, toy_fmus):
    """The same system through FMUs and through Python objects gives the same numbers."""

    class ToyRamp(Component):
        model_name = "ToyRamp"
        parameters = (real("slope", start=1.0),)
        outputs = (real("y"),)

        def initialize(self, start_time):
            return {"y": 0.0}

        def step(self, t, h, inputs):
            return {"y": self.params["slope"] * (t + h)}

    class ToyScaler(Component):
        model_name = "ToyScaler"
        parameters = (real("k", start=2.0), real("limit", start=1e9))
        inputs = (real("u"),)
        outputs = (real("y"), integer("n"), boolean("big"))

        def initialize(self, start_time):
            self.n = 0
            return {"y": 0.0, "n": 0, "big": False}

        def step(self, t, h, inputs):
            self.n += 1
            y = self.params["k"] * inputs["u"]
            return {"y": y, "n": self.n, "big": y > 1.0}

    model = fmu_model(write_ssd, toy_fmus)
    via_fmu = Simulation(model, backend="fmu").run()
    direct = Simulation(model, backend="direct",
                        registry={"ToyRamp": ToyRamp, "ToyScaler": ToyScaler}).run()
    for c in ("ramp", "scaler"):
        assert via_fmu.columns[c] == direct.columns[c]
        np.testing.assert_array_equal(via_fmu.data[c], direct.data[c])
