"""FMI 3.0 co-simulation FMUs as components, next to FMI 2.0 ones: the master's exchange
(Gauss-Seidel and Jacobi) against the analytic answer of a model written here in C after the
standard (``tests/fmi3c``, :mod:`fmi3_fixtures`), a mixed FMI 2 -> FMI 3 -> FMI 2 chain
against the all-FMI-2 model, ``compare`` on it, state save and restore, ``terminateSimulation``,
and every refusal in its one line."""
from __future__ import annotations

import json
import math
import re
import shutil
from pathlib import Path

import numpy as np
import pytest
from fmpy import simulate_fmu

import fmi3_fixtures as fx
from conftest import component_xml, connection_xml, ssd_text
from navcore.core import signals
from orchestrator.building import build as fmu_build
from orchestrator.cosim.fmi3_instance import Fmi3Instance
from orchestrator.cosim.hosted_instance import HostedFmuInstance
from orchestrator.cosim.isolation import Isolation
from orchestrator.cosim.master import Simulation
from orchestrator.errors import (NavfmuError, NavfmuWarning, SimulationError,
                                 SimulationTerminated, WiringError)
from orchestrator.model.ssp_archive import load_model
from test_export_package import export_equals_jacobi

H, STOP = 0.01, 1.0
K_A, X0_A, K_B, OFFSET = 2.0, 3.0, 0.5, 7
LINKS = (("x", "u"), ("count_out", "count_in"), ("flag_out", "flag"))
CONNECTORS = [("x", "output", "Real", "m"), ("u", "input", "Real", "m"),
              ("count_out", "output", "Integer"), ("count_in", "input", "Integer"),
              ("flag_out", "output", "Boolean"), ("flag", "input", "Boolean")]


@pytest.fixture(scope="session")
def fmi3_libraries(tmp_path_factory):
    """The C models compiled once per session."""
    if fx.compiler() is None:
        pytest.skip("no C compiler or no FMI 3 headers in fmpy")
    folder = tmp_path_factory.mktemp("fmi3c")
    return {name: fx.compile_model(name, folder) for name in ("dahlquist3", "passthrough3")}


@pytest.fixture(scope="session")
def dahlquist(fmi3_libraries, tmp_path_factory):
    return fx.pack(fx.DAHLQUIST_XML, fmi3_libraries["dahlquist3"],
                   tmp_path_factory.mktemp("d3") / "Dahlquist3.fmu")


def _chain(folder: Path, fmu: Path, a_params=None, b_connectors=CONNECTORS) -> Path:
    """a -> b, two Dahlquist3 FMUs: b's u, count_in and flag fed by a's x, count_out and
    flag_out."""
    a = component_xml("a", str(fmu), CONNECTORS, {"k": ("Real", K_A), "x0": ("Real", X0_A),
                                                  "label": ("String", "A"), **(a_params or {})})
    b = component_xml("b", str(fmu), b_connectors, {"k": ("Real", K_B), "x0": ("Real", 0.0),
                                                    "offset": ("Integer", OFFSET)})
    links = "\n".join(connection_xml(f"a.{s}", f"b.{e}") for s, e in LINKS)
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "SystemStructure.ssd").write_text(ssd_text(a + "\n" + b, links, base_step=H,
                                                         stop=STOP, name="chain"))
    return folder


def _expected_b(t, algorithm):
    """b's x by its own exact step with u held: a's x at the end of the step (Gauss-Seidel)
    or at its start (Jacobi: one step late)."""
    x_a = X0_A * np.exp(-K_A * t)
    x_b = np.zeros_like(t)
    decay = math.exp(-K_B * H)
    for n in range(len(t) - 1):
        u = x_a[n + 1] if algorithm == "gauss-seidel" else x_a[n]
        x_b[n + 1] = u + (x_b[n] - u) * decay
    return x_b


@pytest.mark.parametrize("algorithm,isolate", [("gauss-seidel", "foreign"),
                                               ("jacobi", "never")])
def test_fmi3_fmus_in_the_exchange_give_the_analytic_answer(dahlquist, tmp_path, algorithm,
                                                            isolate):
    r = Simulation(load_model(_chain(tmp_path / "chain", dahlquist)), algorithm=algorithm,
                   isolation=Isolation(isolate)).run()
    t = r.time
    assert len(t) == round(STOP / H) + 1
    np.testing.assert_allclose(r.column("a", "x"), X0_A * np.exp(-K_A * t), rtol=1e-13)
    np.testing.assert_allclose(r.column("b", "x"), _expected_b(t, algorithm), rtol=1e-12,
                               atol=1e-15)
    # the continuous solution of x_b' = -k_b (x_b - x_a), within the hold's first order
    exact = X0_A * K_B / (K_B - K_A) * (np.exp(-K_A * t) - np.exp(-K_B * t))
    assert np.max(np.abs(r.column("b", "x") - exact)) < 0.01
    n = np.arange(len(t))
    # Int32 through the exchange: b adds its steps to a's; Int64 steps with b's offset
    lag = 0 if algorithm == "gauss-seidel" else 1
    np.testing.assert_array_equal(r.column("a", "count_out"), n)
    np.testing.assert_array_equal(r.column("b", "count_out")[1:], 2 * n[1:] - lag)
    np.testing.assert_array_equal(r.column("b", "steps"), n + OFFSET)
    # Boolean: a's flag_out (not its false flag) is true, b's is its negation
    assert set(r.column("a", "flag_out")) == {1.0} and set(r.column("b", "flag_out")) == {0.0}
    assert r.units["a"][r.columns["a"].index("x")] == "m"
    assert r.metadata["builds"]["a"]["fmi_version"] == "3.0"
    assert r.metadata["hosted"] == (["a", "b"] if isolate == "foreign" else [])


def _state_roundtrip(inst):
    inst.prepare([], ["x", "steps"])
    inst.set_parameters({"k": K_A, "x0": X0_A})
    inst.initialize(0.0, 1.0)
    for k in range(10):
        inst.do_step(k * H, H)
    saved = inst.get_state()
    runs = []
    for _ in range(2):
        for k in range(10, 15):
            inst.do_step(k * H, H)
        runs.append(inst.get_outputs()[0].copy())
        inst.set_state(saved)
    real, integer, _ = inst.get_outputs()
    after_restore = (real[0], integer[0])
    inst.free_state(saved)
    return runs, after_restore


@pytest.mark.parametrize("where", ["here", "hosted"])
def test_fmi3_state_save_and_restore(dahlquist, where):
    inst = (Fmi3Instance(dahlquist, "d") if where == "here"
            else HostedFmuInstance(dahlquist, "d", 60.0))
    try:
        (first, second), restored = _state_roundtrip(inst)
    finally:
        inst.terminate()
    # 15 steps, then back to the state after 10 and the same 5 steps again
    assert math.isclose(first[0], X0_A * math.exp(-K_A * 15 * H), rel_tol=1e-13)
    assert first.tobytes() == second.tobytes()
    assert math.isclose(restored[0], X0_A * math.exp(-K_A * 10 * H), rel_tol=1e-13)
    assert restored[1] == 10


def test_an_fmu_without_state_is_refused_by_name(fmi3_libraries, tmp_path):
    fmu = fx.pack(fx.variant('canGetAndSetFMUState="true"', 'canGetAndSetFMUState="false"'),
                  fmi3_libraries["dahlquist3"], tmp_path / "NoState.fmu")
    with Fmi3Instance(fmu, "d") as inst:
        with pytest.raises(NavfmuError) as info:
            inst.get_state()
    assert str(info.value) == ("component 'd': NoState.fmu cannot get/set its state "
                               "(canGetAndSetFMUstate is false)")


END = ("component 'a' (Dahlquist3.fmu) ended the simulation at t = 0.5 s (fmi3DoStep "
       "returned terminateSimulation): A: stop_at = 0.5 s reached")


@pytest.mark.parametrize("isolate", ["never", "foreign"])
def test_terminate_simulation_ends_the_run_cleanly(dahlquist, tmp_path, isolate):
    """a asks to end at 0.5 s (in macro step 49, b not yet stepped): the results end at
    0.49 s, the last point both reached, with their numbers, and a warning says so."""
    folder = _chain(tmp_path / "stops", dahlquist, {"stop_at": ("Real", 0.5)})
    full = Simulation(load_model(folder), isolation=Isolation(isolate)).run(0.4)
    with pytest.warns(NavfmuWarning) as caught:
        r = Simulation(load_model(_chain(tmp_path / "stops", dahlquist,
                                         {"stop_at": ("Real", 0.5)})),
                       isolation=Isolation(isolate)).run()
    assert [str(w.message) for w in caught] == [
        END + "; the results end at t = 0.49 s, the last recorded communication point every "
        "component reached"]
    assert len(r.time) == 50 and r.time[-1] == pytest.approx(0.49)
    assert r.metadata["stop_time"] == pytest.approx(0.49) and r.metadata["n_steps"] == 49
    assert r.metadata["ended_by"] == {"component": "a", "time": 0.5, "message": END}
    np.testing.assert_allclose(r.column("b", "x"), _expected_b(r.time, "gauss-seidel"),
                               rtol=1e-12, atol=1e-15)
    assert r.data["b"][:41].tobytes() == full.data["b"].tobytes()


def test_terminate_simulation_keeps_the_run_in_the_cli(dahlquist, tmp_path, navfmu_cli):
    folder = _chain(tmp_path / "stops", dahlquist, {"stop_at": ("Real", 0.5)})
    code, out, err = navfmu_cli("run", folder, "--no-plots", "--format", "csv", "--out",
                                tmp_path / "out")
    assert code == 0, err
    assert "navfmu: warning: " + END + "; the results end at t = 0.49 s" in err
    rows = (tmp_path / "out" / "results.csv").read_text().splitlines()
    assert len(rows) == 51 and rows[-1].startswith("0.49,")


def test_terminate_simulation_before_the_first_row_fails_in_one_line(dahlquist, tmp_path):
    folder = _chain(tmp_path / "stops", dahlquist, {"stop_at": ("Real", 0.01)})
    with pytest.raises(SimulationTerminated) as info:
        Simulation(load_model(folder), isolation=Isolation("never")).run()
    assert str(info.value) == END.replace("0.5 s", "0.01 s")


def test_verify_probes_drive_an_fmi3_fmu(dahlquist, tmp_path):
    """verify's FMI probes (state restore and serialization, variable step, hostile calls)
    through FMU3Slave: the state restored gives the same run bit for bit, one exact step of
    k periods differs from k steps in x only by rounding, and the hostile calls are refused."""
    from fmpy import extract, read_model_description
    from orchestrator.verification import fmi_probe
    from orchestrator.verification.roles import read_fmu

    facts = read_fmu(dahlquist)
    assert (facts.variables["steps"].type, facts.variables["flag_out"].type) == ("Integer",
                                                                                 "Boolean")
    assert facts.can_get_set_state and facts.variables["x"].unit == "m"
    md = read_model_description(str(dahlquist))
    unzip = extract(str(dahlquist), str(tmp_path / "unzipped"))
    table = {"u": np.linspace(0.0, 1.0, 40), "count_in": np.arange(40)}
    params = {"k": K_A, "x0": X0_A}
    state = fmi_probe.probe_state(str(dahlquist), md, unzip, params, table, H)
    assert state["set_state"] is None and state["steps"] == 40 and "deserialize" not in state
    variable = fmi_probe.probe_variable_step(str(dahlquist), md, unzip, params, table, H, 4)
    assert variable["coarse_steps"] == 10
    # x first, by rounding only (exp(-k 4h) against exp(-k h)^4); the counts of steps later
    what = variable["difference"]["what"]
    assert what.startswith("x at t = 0.04 s: ")
    fine, coarse = (float(x) for x in what.split(": ")[1].split(" against "))
    assert fine != coarse and math.isclose(fine, coarse, rel_tol=1e-14)
    hostile = fmi_probe.probe_hostile(str(dahlquist), md, unzip, params, table, H)
    assert hostile["statuses"] == {"unknown value reference": 3, "set of an output": 3,
                                   "step back in time": 3}


def test_a_hosted_fmi3_fmu_crashing_is_named_in_its_fmi3_call(dahlquist, tmp_path):
    folder = _chain(tmp_path / "m", dahlquist, {"abort_at": ("Real", 0.5)})
    with pytest.raises(SimulationError) as info:
        Simulation(load_model(folder)).run()
    assert str(info.value) == ("component 'a' (Dahlquist3.fmu): the FMU process died with "
                               "SIGABRT in fmi3DoStep at t = 0.49 s")


def test_fmi3_units_are_compared_as_for_fmi2(fmi3_libraries, tmp_path):
    """b's input u declared in seconds by the FMU (and its connector): the connection from
    a's x in metres is refused before anything runs."""
    fmu = fx.pack(fx.variant('<Float64 name="u" valueReference="4" causality="input" '
                             'variability="continuous" unit="m"',
                             '<Float64 name="u" valueReference="4" causality="input" '
                             'variability="continuous" unit="s"'),
                  fmi3_libraries["dahlquist3"], tmp_path / "Seconds.fmu")
    connectors = [c if c[0] != "u" else ("u", "input", "Real", "s") for c in CONNECTORS]
    with pytest.raises(NavfmuError) as info:
        Simulation(load_model(_chain(tmp_path / "m", fmu, b_connectors=connectors)))
    assert str(info.value) == ("connection a.x -> b.u: unit 'm' against 's' (a connection "
                               "passes the value unchanged: give both ends one unit)")


# -- refusals ------------------------------------------------------------------------------
REFUSED = {
    "float32 output": (
        '<Float64 name="x" valueReference="1" causality="output"',
        '<Float32 name="x" valueReference="1" causality="output"',
        "component 'a' (Refused.fmu): FMI 3.0 output 'x' is a Float32, which no connector type "
        "holds (FMI 3.0 Float64, Int32, Int64 and Boolean are exchanged)"),
    "uint8 input": (
        '<Int32 name="count_in"', '<UInt8 name="count_in"',
        "component 'a' (Refused.fmu): FMI 3.0 input 'count_in' is a UInt8, which no connector "
        "type holds (FMI 3.0 Float64, Int32, Int64 and Boolean are exchanged)"),
    "int16 output": (
        '<Int32 name="count_out"', '<Int16 name="count_out"',
        "component 'a' (Refused.fmu): FMI 3.0 output 'count_out' is an Int16, which no "
        "connector type holds (FMI 3.0 Float64, Int32, Int64 and Boolean are exchanged)"),
    "array output": (
        '<Float64 name="x" valueReference="1" causality="output" variability="continuous" '
        'unit="m"/>',
        '<Float64 name="x" valueReference="1" causality="output" variability="continuous" '
        'unit="m"><Dimension start="3"/></Float64>',
        "component 'a' (Refused.fmu): FMI 3.0 output 'x' is an array (Float64[3]); only scalar "
        "variables can be connected or recorded"),
    "clock": (
        "</ModelVariables>",
        '<Clock name="tick" valueReference="20" causality="input" variability="discrete" '
        'intervalVariability="triggered"/></ModelVariables>',
        "component 'a' (Refused.fmu): FMI 3.0 clock 'tick': clocked FMUs need event mode, "
        "which the master does not use"),
}


@pytest.mark.parametrize("case", sorted(REFUSED))
def test_unexchangeable_fmi3_variables_are_refused_before_anything_runs(
        case, fmi3_libraries, tmp_path, navfmu_cli):
    old, new, message = REFUSED[case]
    fmu = fx.pack(fx.variant(old, new), fmi3_libraries["dahlquist3"], tmp_path / "Refused.fmu")
    folder = _chain(tmp_path / "m", fmu)
    with pytest.raises(NavfmuError) as info:
        Simulation(load_model(folder))
    assert str(info.value) == message
    code, _, err = navfmu_cli("run", folder, "--no-plots", "--out", tmp_path / "out")
    assert code == 2 and err.splitlines() == ["navfmu: error: " + message]


def test_a_float32_parameter_is_refused_when_set(fmi3_libraries, tmp_path):
    fmu = fx.pack(fx.variant('<Float64 name="k"', '<Float32 name="k"'),
                  fmi3_libraries["dahlquist3"], tmp_path / "Refused.fmu")
    with pytest.raises(WiringError) as info:
        Simulation(load_model(_chain(tmp_path / "m", fmu)))
    assert str(info.value) == (f"component 'a' ({fmu}): parameter 'k' has type Float32, "
                               f"which cannot be set (settable: Real, Integer, Enumeration, "
                               f"Boolean, String)")


def test_an_int64_output_beyond_32_bits_is_refused_when_read(dahlquist, tmp_path):
    folder = _chain(tmp_path / "m", dahlquist)
    with pytest.raises(SimulationError) as info:
        Simulation(load_model(folder), parameters={"b.offset": 2 ** 31 - 1},
                   isolation=Isolation("never")).run()
    assert str(info.value) == ("component 'b' (Dahlquist3.fmu): Int64 output 'steps' = "
                               "2147483648 at t = 0.01 s does not fit an FMI Integer "
                               "connector (32 bits)")


def test_package_and_libcosim_refuse_an_fmi3_component(dahlquist, tmp_path, navfmu_cli):
    from orchestrator.cosim.libcosim_run import run_libcosim

    folder = _chain(tmp_path / "m", dahlquist)
    with pytest.raises(NavfmuError) as info:
        run_libcosim(folder)
    assert str(info.value) == ("component 'a': Dahlquist3.fmu is an FMI 3.0 FMU, which "
                               "libcosim cannot load (navfmu run runs it)")
    code, _, err = navfmu_cli("package", folder, "--out", tmp_path / "m.ssp")
    assert code == 2 and err.splitlines() == [
        "navfmu: error: component 'a': Dahlquist3.fmu is an FMI 3.0 FMU, which libcosim, for "
        "which the archive is written, cannot load (navfmu run runs it)"]
    assert not (tmp_path / "m.ssp").exists()


# -- FMI 2 -> FMI 3 -> FMI 2 ---------------------------------------------------------------
TRUTH = [(p.name, p.unit) for p in signals.TRUTH]


@pytest.fixture(scope="module")
def aircraft_models(fmi3_libraries, tmp_path_factory):
    """models/aircraft_500s as it is (FMI 2.0 only) and with an FMI 3.0 pass-through between
    the trajectory's truth and the receiver."""
    fmu_build.build(["TrajectoryImu", "GnssReceiver", "Kf", "Iakf"], log=None)
    root = tmp_path_factory.mktemp("aircraft")
    passthrough = fx.pack(fx.passthrough_xml(TRUTH), fmi3_libraries["passthrough3"],
                          root / "Passthrough3.fmu")
    models = {}
    for kind in ("fmi2", "mixed"):
        folder = root / kind
        shutil.copytree(fmu_build.ROOT / "models" / "aircraft_500s", folder)
        ssd = folder / "SystemStructure.ssd"
        text = ssd.read_text().replace('source="../../fmus/dist/', f'source="{fmu_build.DIST}/')
        if kind == "mixed":
            text = _through(text, passthrough)
        ssd.write_text(text)
        models[kind] = folder
    return models


def _through(ssd: str, passthrough: Path) -> str:
    """The trajectory's truth to the receiver through the pass-through ``pass``."""
    element = component_xml("pass", str(passthrough),
                            [(f"in_{n}", "input", "Real", u) for n, u in TRUTH]
                            + [(n, "output", "Real", u) for n, u in TRUTH])
    ssd = ssd.replace("</ssd:Elements>", element + "\n</ssd:Elements>")
    link = re.compile(r'startElement="trajectory" startConnector="(truth_\w+)" '
                      r'endElement="gnss"')
    assert len(link.findall(ssd)) == len(TRUTH)
    ssd = link.sub(r'startElement="pass" startConnector="\1" endElement="gnss"', ssd)
    feeds = "\n".join(connection_xml(f"trajectory.{n}", f"pass.in_{n}") for n, _ in TRUTH)
    return ssd.replace("</ssd:Connections>", feeds + "\n</ssd:Connections>")


def test_a_mixed_fmi2_fmi3_chain_runs_as_the_all_fmi2_model(aircraft_models):
    fmi2 = Simulation(load_model(aircraft_models["fmi2"])).run(5.0)
    mixed = Simulation(load_model(aircraft_models["mixed"])).run(5.0)
    assert mixed.metadata["hosted"] == ["pass"]
    assert mixed.metadata["builds"]["pass"]["fmi_version"] == "3.0"
    np.testing.assert_array_equal(mixed.data["pass"], fmi2.data["trajectory"][
        :, [fmi2.columns["trajectory"].index(n) for n, _ in TRUTH]])
    for c in ("trajectory", "gnss", "filter"):
        assert mixed.columns[c] == fmi2.columns[c]
        assert mixed.data[c].tobytes() == fmi2.data[c].tobytes(), c
    assert fmi2.column("gnss", "gnss_epoch")[-1] == 5.0


def test_compare_runs_a_mixed_fmi2_fmi3_model(aircraft_models, tmp_path, navfmu_cli):
    metrics = {}
    for kind, folder in aircraft_models.items():
        out = tmp_path / kind
        code, _, err = navfmu_cli("compare", folder, "--filters", "Kf,Iakf", "--stop", "10",
                                  "--no-plots", "--out", out)
        assert code == 0, err
        metrics[kind] = json.loads((out / "metrics.json").read_text())
        for f in ("Kf", "Iakf"):
            assert (out / f"results_{f}.csv").is_file()
    for f in ("Kf", "Iakf"):
        mixed, fmi2 = metrics["mixed"][f], metrics["fmi2"][f]
        assert mixed["metadata"]["builds"]["pass"]["fmi_version"] == "3.0"
        # every number but the measured time per step
        for m in (mixed, fmi2):
            m["metrics"]["filter"].pop("time_per_step_ms")
        assert mixed["metrics"] == fmi2["metrics"]
        assert 0 < mixed["metrics"]["filter"]["position_rms_m"]["n"] < 10


def test_export_holds_fmi3_components(fmi3_libraries, tmp_path):
    """Two Dahlquist FMUs without their Int64 (which the container cannot pass), a -> b by x
    only (the container reads outputs after its transfers: a feedthrough output would be
    read one step earlier than by the Jacobi rule), exported and run by fmpy: our Jacobi run
    bit for bit, and the analytic answer."""
    xml = fx.DAHLQUIST_XML
    for line in ('<Int64 name="steps"', '<Int64 name="offset"', '<Output valueReference="7"',
                 '<InitialUnknown valueReference="7"'):
        start = xml.index(line)
        xml = xml[:start] + xml[xml.index("\n", start) + 1:]
    fmu = fx.pack(xml, fmi3_libraries["dahlquist3"], tmp_path / "Dahlquist3.fmu")
    real = [c for c in CONNECTORS if c[2] == "Real"]
    a = component_xml("a", str(fmu), real, {"k": ("Real", K_A), "x0": ("Real", X0_A)})
    b = component_xml("b", str(fmu), real, {"k": ("Real", K_B), "x0": ("Real", 0.0)})
    (tmp_path / "m").mkdir()
    (tmp_path / "m" / "SystemStructure.ssd").write_text(ssd_text(
        a + "\n" + b, connection_xml("a.x", "b.u"), base_step=H, stop=STOP))
    got = export_equals_jacobi(tmp_path / "m", tmp_path, stop=STOP, step=H)
    t = np.asarray(got["time"])
    np.testing.assert_allclose(got["b.x"], _expected_b(t, "jacobi"), rtol=1e-12, atol=1e-15)


def test_export_holds_a_mixed_fmi2_fmi3_model(aircraft_models, tmp_path):
    from orchestrator.packaging.export import export

    fmu = export(aircraft_models["mixed"], tmp_path / "system.fmu")
    got = simulate_fmu(str(fmu), stop_time=3.0, step_size=0.01, output_interval=0.01)
    # the pass-through repeats the trajectory's truth; the receiver fixes once a second
    np.testing.assert_array_equal(got["pass.truth_lat"], got["trajectory.truth_lat"])
    assert got["gnss.gnss_epoch"][-1] == 2 and got["filter.updated"].sum() == 2


def test_export_refuses_an_int64_it_cannot_pass(dahlquist, tmp_path):
    from orchestrator.packaging.export import export

    with pytest.raises(NavfmuError) as info:
        export(_chain(tmp_path / "m", dahlquist), tmp_path / "system.fmu")
    assert str(info.value) == ("component 'a' (Dahlquist3.fmu): output 'steps' has type "
                               "Int64, which the exported FMU cannot pass (fmpy's container "
                               "reads Float64, Int32 and Boolean)")
    assert not (tmp_path / "system.fmu").exists()


def test_a_campaign_runs_a_mixed_fmi2_fmi3_model(aircraft_models, tmp_path):
    """montecarlo on the FMU backend: two seeds of the mixed model give the all-FMI-2
    model's metrics (the seeds change the numbers, so the comparison can fail)."""
    from orchestrator.campaigns.campaign import CampaignSpec, run_campaign
    from orchestrator.campaigns.campaign_runs import read_run

    metrics = {}
    for kind, folder in aircraft_models.items():
        spec = CampaignSpec(scenario=str(folder), filters=("Kf",), runs=2, backend="fmu",
                            stop_time=5.0)
        run_campaign(spec, tmp_path / kind, workers=1, log=lambda *_: None)
        metrics[kind] = [dict(read_run(tmp_path / kind, "Kf", i)["metrics"]) for i in range(2)]
        for m in metrics[kind]:
            m.pop("time_per_step_ms")
    assert metrics["mixed"] == metrics["fmi2"]
    assert metrics["fmi2"][0]["position_rms_m"] != metrics["fmi2"][1]["position_rms_m"]
