"""``navfmu tune`` piece by piece, fast: the ``--range`` syntax, the search ranges read from
the declared limits (open ends one float inside) or from another FMU's model description, the
current values (bound, else the declared start), one evaluation's cost against the attitude
RMS computed here from a direct run, and what the summary holds for a stub cost."""
from __future__ import annotations

import dataclasses
import json
import math
import shutil
from pathlib import Path

import numpy as np
import pytest

from orchestrator.campaigns import tune as tuner
from orchestrator.campaigns.defaults import DEFAULT_SEED
from orchestrator.cosim.master import Simulation
from orchestrator.errors import NavfmuError
from orchestrator.model.ssp import load_ssd
from orchestrator.results import metrics
from orchestrator.running.scenarios import registry

MODEL = Path(__file__).resolve().parent.parent / "models" / "ahrs_turntable"


@pytest.fixture(scope="module")
def model():
    return tuner.load_scenario(MODEL)


def test_range_syntax():
    assert tuner.parse_ranges([" gain =0.5:4", "b=-1e-3:2e-3"]) == {
        "gain": (0.5, 4.0), "b": (-1e-3, 2e-3)}
    for bad in ["gain=2:2", "gain=3:1", "gain0.5:4", "gain=1", "gain=1:2:3", "gain=a:b",
                "gain=-inf:1", "gain=0:nan", "gain==1:2"]:
        with pytest.raises(NavfmuError, match="--range"):
            tuner.parse_ranges([bad])


def test_declared_limits_are_the_ranges_open_ends_one_float_inside(model):
    """FuzzyUkfAhrs declares mag_inclination in (-pi/2, pi/2), gravity_mps2 in (0, 100],
    fuzzy_window an Integer in [2, 100000] and ukf_beta unbounded (docs/signals.md)."""
    declared = tuner._declared_ranges(model, "filter", "direct")
    assert declared["mag_inclination"] == (
        "Real", math.nextafter(-math.pi / 2, 0.0), math.nextafter(math.pi / 2, 0.0),
        math.radians(60.0))
    assert declared["gravity_mps2"] == ("Real", 5e-324, 100.0, 9.80665)
    assert declared["fuzzy_window"] == ("Integer", 2, 100000, 20.0)
    assert declared["ukf_beta"] == ("Real", None, None, 2.0)
    assert "init_attitude" not in declared                   # a String is not tunable


DESCRIPTION = """<?xml version="1.0" encoding="UTF-8"?>
<fmiModelDescription fmiVersion="2.0" modelName="Other" guid="{0}">
  <CoSimulation modelIdentifier="Other"/>
  <ModelVariables>
    <ScalarVariable name="gain" valueReference="0" causality="parameter" variability="fixed"
      initial="exact"><Real start="2.5" min="0.5" max="4"/></ScalarVariable>
    <ScalarVariable name="count" valueReference="1" causality="parameter" variability="fixed"
      initial="exact"><Integer start="3" min="1"/></ScalarVariable>
    <ScalarVariable name="offset" valueReference="4" causality="parameter" variability="fixed"
      initial="exact"><Real start="0" max="9"/></ScalarVariable>
    <ScalarVariable name="label" valueReference="2" causality="parameter" variability="fixed"
      initial="exact"><String start="x"/></ScalarVariable>
    <ScalarVariable name="y" valueReference="3" causality="output"><Real/></ScalarVariable>
  </ModelVariables>
  <ModelStructure><Outputs><Unknown index="4"/></Outputs></ModelStructure>
</fmiModelDescription>
"""


def test_another_fmu_s_ranges_are_its_min_and_max(model, tmp_path):
    description = tmp_path / "OtherSlave.xml"
    description.write_text(DESCRIPTION)
    other = model.replace_source("filter", description)
    assert tuner._declared_ranges(other, "filter", "direct") == {
        "gain": ("Real", 0.5, 4.0, 2.5), "count": ("Integer", 1.0, None, 3.0),
        "offset": ("Real", None, 9.0, 0.0)}
    for one_sided in ("count", "offset"):                  # half a range is no range
        with pytest.raises(NavfmuError, match="declares no range"):
            tuner.resolve_parameters(other, "filter", [one_sided], {}, "direct")
    with pytest.raises(NavfmuError, match="not found"):
        tuner._declared_ranges(model.replace_source("filter", tmp_path / "None.fmu"),
                               "filter", "direct")


def test_current_values_are_the_bindings_else_the_declared_start(model):
    """filter_tuned.ssv binds r_accel_mps2 = 0.0208; ukf_alpha is unbound (start 1.0)."""
    names = ["r_accel_mps2", "ukf_alpha", "fuzzy_window"]
    lo, hi, types, current = tuner.resolve_parameters(
        model, "filter", names, {"r_accel_mps2": (0.01, 0.05)}, "direct")
    assert lo.tolist() == [0.01, 5e-324, 2.0] and hi.tolist() == [0.05, 1.0, 100000.0]
    assert types == ("Real", "Real", "Integer")
    assert current.tolist() == [0.0208, 1.0, 20.0]
    for names, ranges, match in [([], {}, "at least one"),
                                 (["ukf_alpha", "ukf_alpha"], {}, "twice"),
                                 (["ukf_alpha"], {"ukf_beta": (0.0, 1.0)}, "not one of"),
                                 (["seed"], {}, "seed")]:
        with pytest.raises(NavfmuError, match=match):
            tuner.resolve_parameters(model, "filter", names, ranges, "direct")
    # the trajectory's seed is declared, and still refused (the cost would fit one draw)
    with pytest.raises(NavfmuError, match="--train-seeds"):
        tuner.resolve_parameters(model, "trajectory", ["seed"], {"seed": (0.0, 9.0)},
                                 "direct")
    # an explicit range makes an unbounded parameter tunable
    assert tuner.resolve_parameters(model, "filter", ["ukf_beta"], {"ukf_beta": (0.0, 4.0)},
                                    "direct")[1].tolist() == [4.0]


def _attitude_rms_deg(results, window=None, name="filter"):
    """Paper 003 eq. 20 written out: RMS over the valid samples in the window and the three
    Euler angles of the attitude error of filter ``name``, in degrees."""
    e = metrics.navigation_errors(results, name)
    keep = e["valid"].copy()
    if window is not None:
        keep &= (e["time"] >= window[0]) & (e["time"] <= window[1])
    squares = [e[f"att_{a}"][keep] ** 2 for a in ("roll", "pitch", "yaw")]
    return math.degrees(math.sqrt(np.mean(np.concatenate(squares))))


def _direct_run(parameters, stop):
    return Simulation(tuner.load_scenario(MODEL), backend="direct", registry=registry(),
                      parameters=parameters).run(stop_time=stop)


def test_a_cost_is_the_attitude_rms_averaged_over_the_training_seeds():
    values = {"r_accel_mps2": 0.5}
    spec = tuner.TuneSpec(str(MODEL), "filter", ("r_accel_mps2",), (1, 2), "direct", 1.0,
                          (0.4, 1.0), ("trajectory.seed",))
    by_seed = [_attitude_rms_deg(_direct_run({"filter.r_accel_mps2": 0.5,
                                              "trajectory.seed": s}, 1.0), (0.4, 1.0))
               for s in (1, 2)]
    assert by_seed[0] != by_seed[1]                    # the seed reaches the trajectory
    assert tuner.evaluate(spec, values) == pytest.approx(np.mean(by_seed), rel=1e-12)
    # no training seed: the model's own noise, and the candidate's values do reach the filter
    own = tuner.TuneSpec(str(MODEL), "filter", ("r_accel_mps2",), (None,), "direct", 1.0, None,
                         ())
    expected = _attitude_rms_deg(_direct_run({"filter.r_accel_mps2": 0.5}, 1.0))
    assert tuner.evaluate(own, values) == pytest.approx(expected, rel=1e-12)
    assert tuner.evaluate(own, {"r_accel_mps2": 0.005}) != pytest.approx(expected, rel=1e-6)


def test_integer_values_are_rounded_to_the_nearest():
    spec = tuner.TuneSpec("", "filter", ("fuzzy_window", "r_accel_mps2"), (None,), "direct",
                          None, None, ())
    values = tuner._values(spec, ("Integer", "Real"), [7.6, 0.25])
    assert values == {"fuzzy_window": 8, "r_accel_mps2": 0.25}
    assert type(values["fuzzy_window"]) is int


class StubCost:
    """A cost lowest at r_accel_mps2 = 0.3 that keeps every spec and candidate it is given."""

    def __init__(self):
        self.calls = []

    def __call__(self, spec, values):
        self.calls.append((spec, values))
        return 0.01 + abs(values["r_accel_mps2"] - 0.3) + 1e-3 * values["fuzzy_window"]


def test_the_summary_of_a_tune(monkeypatch):
    stub = StubCost()
    monkeypatch.setattr(tuner, "evaluate", stub)
    progress, lines = [], []
    names = ["r_accel_mps2", "fuzzy_window"]
    res = tuner.run_tune(MODEL, "filter", names, batch=1, generations=3, population=4, seed=1,
                         ranges={"r_accel_mps2": (0.1, 0.9), "fuzzy_window": (2, 40)},
                         train_seeds=[5, 6], stop_time=2.0, window=(1.0, 2.0),
                         progress=lambda done, total: progress.append((done, total)),
                         log=lines.append)
    spec = stub.calls[0][0]
    assert spec.train_seeds == (5, 6) and spec.seed_parameters == ("trajectory.seed",)
    assert (spec.component, spec.names, spec.stop_time, spec.window) == (
        "filter", tuple(names), 2.0, (1.0, 2.0))
    assert progress == [(4, 12), (8, 12), (12, 12)]
    assert len(lines) == 3 and lines[0].startswith("generation 1/3: best cost ")
    assert res["evaluations"] == len(stub.calls) <= 12
    assert res["ranges"] == {"r_accel_mps2": [0.1, 0.9], "fuzzy_window": [2.0, 40.0]}
    assert res["train_seeds"] == [5, 6] and res["window"] == [1.0, 2.0]
    assert (res["population"], res["generations"], res["seed"]) == (4, 3, 1)
    best = res["best_values"]
    assert type(best["fuzzy_window"]) is int and 2 <= best["fuzzy_window"] <= 40
    assert 0.1 <= best["r_accel_mps2"] <= 0.9
    # the best values are the candidate of the lowest cost seen, and that cost is reported
    costs = [stub(spec, values) for _, values in stub.calls[:]]
    assert res["best_cost"] == min(costs) == stub(spec, best)
    assert res["best_so_far"][-1] == res["best_cost"]
    # the other bound parameters go with the result, the tuned one not
    assert res["bound_parameters"]["r_mag_T"] == ["Real", 1e-7]
    assert "r_accel_mps2" not in res["bound_parameters"]
    assert len(res["bound_parameters"]) == 17


def test_without_training_seeds_the_model_s_own_noise_is_used(monkeypatch):
    stub = StubCost()
    monkeypatch.setattr(tuner, "evaluate", stub)
    res = tuner.run_tune(MODEL, "filter", ["r_accel_mps2", "fuzzy_window"], batch=1, generations=1,
                         population=2, log=lambda m: None)
    assert stub.calls[0][0].train_seeds == (None,) and stub.calls[0][0].seed_parameters == ()
    assert res["window"] is None and res["workers"] == 1 and res["backend"] == "direct"


def test_the_outputs_of_a_tune_bind_with_one_line(monkeypatch, tmp_path):
    """The written parameter set holds the best values and the other bindings (it replaces
    the component's bindings); tune.json is the summary."""
    monkeypatch.setattr(tuner, "evaluate", StubCost())
    res = tuner.run_tune(MODEL, "filter", ["r_accel_mps2", "fuzzy_window"], batch=1, generations=1,
                         population=2, log=lambda m: None)
    written = tuner.write_tune_outputs(res, tmp_path / "out" / "deeper")
    assert [p.relative_to(tmp_path).as_posix() for p in written] == [
        "out/deeper/filter_tuned.ssv", "out/deeper/tune.json", "out/deeper/fitness.png"]
    assert json.loads(written[1].read_text()) == res
    model = tmp_path / "model"
    shutil.copytree(MODEL, model)
    shutil.copy2(written[0], model / "filter_tuned.ssv")
    bound = load_ssd(model / "SystemStructure.ssd").component("filter").parameters
    assert bound["r_accel_mps2"] == ("Real", res["best_values"]["r_accel_mps2"])
    assert bound["fuzzy_window"] == ("Integer", res["best_values"]["fuzzy_window"])
    assert bound["r_mag_T"] == ("Real", 1e-7)


def test_the_seeds_go_to_every_random_component_even_after_one_not_described(model,
                                                                             tmp_path):
    """A component whose FMU is missing is skipped, not the end of the search."""
    missing_first = model.replace_source("filter", tmp_path / "Missing.fmu")
    missing_first = dataclasses.replace(missing_first,
                                        components=list(reversed(missing_first.components)))
    assert tuner._seed_parameters(missing_first, "direct") == ("trajectory.seed",)


def test_the_cost_is_measured_on_the_only_filter_whatever_its_name(tmp_path):
    """In a copy of the model whose filter component is called 'ahrs', not 'filter', the
    cost is that filter's attitude RMS."""
    renamed = tmp_path / "renamed"
    shutil.copytree(MODEL, renamed)
    ssd = renamed / "SystemStructure.ssd"
    ssd.write_text(ssd.read_text().replace('name="filter"', 'name="ahrs"')
                   .replace('Element="filter"', 'Element="ahrs"'))
    spec = tuner.TuneSpec(str(renamed), "ahrs", ("r_accel_mps2",), (None,), "direct", 1.0,
                          None, ())
    results = Simulation(tuner.load_scenario(renamed), backend="direct", registry=registry(),
                         parameters={"ahrs.r_accel_mps2": 0.5}).run(stop_time=1.0)
    expected = _attitude_rms_deg(results, name="ahrs")
    assert tuner.evaluate(spec, {"r_accel_mps2": 0.5}) == pytest.approx(expected, rel=1e-12)


class InlineExecutor:
    """Runs the tasks in this process and keeps the options it was made with."""

    made = []

    def __init__(self, **options):
        InlineExecutor.made.append(options)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        return False

    def map(self, tasks):
        return {t.key: t.func(*t.args) for t in tasks}


def test_defaults_executor_options_fmu_build_and_the_current_values_first(monkeypatch):
    """The defaults are 5 generations of 10 with seed 0; the executor gets the workers and
    scheduler asked; the fmu backend builds the FMUs first; the model's current values (here
    0.0208 in the range 0.01 .. 0.05, a lower bound that is not 0) are in the first
    generation, so a cost lowest exactly there returns them."""
    current = 0.0208
    seen = []

    def spike(spec, values):
        seen.append(spec)
        return 1.0 if abs(values["r_accel_mps2"] - current) < 1e-12 else 2.0

    built = []
    monkeypatch.setattr(tuner, "evaluate", spike)
    monkeypatch.setattr(tuner, "Executor", InlineExecutor)
    monkeypatch.setattr(tuner, "ensure_fmus", lambda model, log: built.append((model, log)))
    InlineExecutor.made.clear()
    say = []
    res = tuner.run_tune(MODEL, "filter", ["r_accel_mps2"], batch=1,
                         workers=3, scheduler="tcp://x:1",
                         ranges={"r_accel_mps2": (0.01, 0.05)}, backend="fmu", log=say.append)
    assert InlineExecutor.made == [{"workers": 3, "scheduler": "tcp://x:1"}]
    assert len(built) == 1 and built[0][0].name == "ahrs_turntable" and built[0][1] == say.append
    assert (res["generations"], res["population"], res["seed"]) == (5, 10, DEFAULT_SEED)
    assert len(res["generation_best"]) == 5 and len(res["generation_mean"]) == 5
    assert res["best_cost"] == 1.0 and res["best_values"]["r_accel_mps2"] == \
        pytest.approx(current, rel=1e-12)
    assert res["ssd"] == str(MODEL / "SystemStructure.ssd") and res["backend"] == "fmu"
    assert res["cost"].startswith("attitude RMS over the window")
    assert {s.ssd for s in seen} == {res["ssd"]} and {s.backend for s in seen} == {"fmu"}
    # the same seed gives the same generations (the GA's seed is the one asked)
    again = tuner.run_tune(MODEL, "filter", ["r_accel_mps2"], batch=1, workers=3,
                           ranges={"r_accel_mps2": (0.01, 0.05)}, log=lambda m: None)
    assert again["generation_mean"] == res["generation_mean"]
    other = tuner.run_tune(MODEL, "filter", ["r_accel_mps2"], batch=1, workers=3,
                           seed=DEFAULT_SEED + 1,
                           ranges={"r_accel_mps2": (0.01, 0.05)}, log=lambda m: None)
    assert other["generation_mean"] != res["generation_mean"]


def test_outputs_go_into_an_existing_folder_only(monkeypatch, tmp_path):
    monkeypatch.setattr(tuner, "evaluate", StubCost())
    res = tuner.run_tune(MODEL, "filter", ["r_accel_mps2", "fuzzy_window"], batch=1, generations=1,
                         population=2, log=lambda m: None)
    (tmp_path / "kept.txt").write_text("a file of the user's")
    written = tuner.write_tune_outputs(res, tmp_path)                  # the folder exists
    assert sorted(p.name for p in written) == ["filter_tuned.ssv", "fitness.png", "tune.json"]
    assert all(p.parent == tmp_path for p in written)
    assert (tmp_path / "kept.txt").read_text() == "a file of the user's"


def test_with_two_filters_the_cost_is_that_of_the_one_called_filter(tmp_path):
    """A copy of the model with a second FuzzyUkfAhrs, 'early', declared before 'filter' and
    fed the same inputs: the candidate's values go to 'filter', and its RMS is the cost."""
    two = tmp_path / "two"
    shutil.copytree(MODEL, two)
    ssd = two / "SystemStructure.ssd"
    text = ssd.read_text()
    start = text.index('      <ssd:Component name="filter"')
    end = text.index("</ssd:Component>", start) + len("</ssd:Component>\n")
    block = text[start:end]
    feeds = [line for line in text.splitlines(keepends=True) if 'endElement="filter"' in line]
    text = text[:start] + block.replace('name="filter"', 'name="early"') + text[start:]
    text = text.replace("    <ssd:Connections>\n", "    <ssd:Connections>\n" + "".join(
        f.replace('endElement="filter"', 'endElement="early"') for f in feeds))
    ssd.write_text(text)
    model = tuner.load_scenario(two)
    assert [c.name for c in model.components] == ["trajectory", "early", "filter"]
    spec = tuner.TuneSpec(str(two), "filter", ("r_accel_mps2",), (None,), "direct", 1.0,
                          None, ())
    results = Simulation(model, backend="direct", registry=registry(),
                         parameters={"filter.r_accel_mps2": 0.5}).run(stop_time=1.0)
    assert metrics.filters_of(results) == ["early", "filter"]
    expected = _attitude_rms_deg(results)
    assert expected != pytest.approx(_attitude_rms_deg(results, name="early"), rel=1e-6)
    assert tuner.evaluate(spec, {"r_accel_mps2": 0.5}) == pytest.approx(expected, rel=1e-12)
