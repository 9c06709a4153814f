"""Property-based tests (hypothesis) over the scenario parameters and the components' inputs.

Whatever the values, a run either completes with finite outputs or stops with a NavfmuError
whose first line names the component and the parameter or input; never another exception
(the command line would print it as an internal error), a crash or a NaN in an output.

Scenario cases run the three paper scenarios (with their papers' filters swapped in) for a
few seconds of simulated time through the direct backend, whose components and error path
are those inside the FMUs (tests/test_fmus.py checks the two paths give identical numbers);
the input cases step the filter components as the master does (DirectInstance) and the Kf
FMU through fmpy; a few scenario cases run through the FMUs.  The default run draws 100 + 6
scenario cases and 30 + 8 input cases; ``-m slow`` 600 and 150 more.
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from navcore.components import registry as components
from orchestrator.building import build as fmu_build
from orchestrator.running import scenarios
from orchestrator.cosim.direct_instance import DirectInstance
from orchestrator.cosim.fmu_instance import FmuInstance
from orchestrator.errors import NavfmuError, SimulationError

MODELS = fmu_build.ROOT / "models"
#: scenario -> the filters its paper compares
SCENARIOS = {
    "aircraft_500s": ("Kf", "SageHusaFading", "Iakf"),
    "aircraft_outliers": ("Kf", "NewtonRobustKf", "InsOnly"),
    "uav_maneuver": ("Ukf", "CtfaUkf", "ImmUkf"),
}
#: simulated seconds per case (two GNSS fixes: an update and its outlier tests run)
STOP_S = 2.0
_MODELS = {name: scenarios.load_scenario(MODELS / name) for name in SCENARIOS}
_SPECIAL = [0.0, -0.0, 1.0, -1.0, 1e-300, -1e-300, 5e-324, 1e300, -1e300, math.inf, -math.inf,
            math.nan, 1e9, -1e9, 0.5, 2.0 ** 31]
_TEXT_ALPHABET = "0123456789.,;-+e naposvelnedNaNinf"


def _real_values(port):
    lim = port.limits
    inside = []
    if math.isfinite(lim.low) and math.isfinite(lim.high):
        inside.append(st.floats(lim.low, lim.high, exclude_min=lim.low_open,
                                exclude_max=lim.high_open))
    bounds = [b for b in (lim.low, lim.high) if math.isfinite(b)]
    return st.one_of(st.sampled_from(_SPECIAL + bounds), st.floats(), *inside)


def _value(port):
    if port.type == "Real":
        return _real_values(port)
    if port.type == "Integer":
        lim = port.limits
        return st.one_of(st.integers(-2 ** 31, 2 ** 31 - 1),
                         st.sampled_from([b for b in (lim.low, lim.high) if math.isfinite(b)]
                                         or [0]).map(int))
    if port.type == "Boolean":
        return st.booleans()
    if port.name == "profile":
        return st.sampled_from(["aircraft_500s", "static", "uav_maneuver", "manoeuvre_1h",
                                "no_such_profile", "/", "/nonexistent.json", ""])
    if port.name == "measurement":
        return st.sampled_from(["position", "position_velocity", "velocity", ""])
    if port.name == "replacement_variance":
        return st.sampled_from(["propagated", "nominal", "other"])
    return st.text(_TEXT_ALPHABET, max_size=40)


def _ports(model, filter_name):
    """(component name, port) of every parameter in ``model`` with ``filter_name`` swapped in."""
    out = []
    for comp in model.components:
        cls = components.REGISTRY[filter_name if comp.name == scenarios.FILTER_COMPONENT
                                  else comp.source.stem]
        out += [(comp.name, p) for p in cls.parameters]
    return out


@st.composite
def scenario_cases(draw):
    name = draw(st.sampled_from(sorted(SCENARIOS)))
    filter_name = draw(st.sampled_from(SCENARIOS[name]))
    ports = _ports(_MODELS[name], filter_name)
    chosen = draw(st.lists(st.sampled_from(ports), min_size=1, max_size=4,
                           unique_by=lambda cp: (cp[0], cp[1].name)))
    overrides = {f"{c}.{p.name}": draw(_value(p)) for c, p in chosen}
    return name, filter_name, overrides


def _assert_finite(results):
    for comp, data in results.data.items():
        bad = ~np.isfinite(data)
        if bad.any():
            rows, cols = np.nonzero(bad)
            pytest.fail(f"non-finite output {comp}.{results.columns[comp][cols[0]]} at "
                        f"t = {results.time[rows[0]]} s")


def _assert_one_line_error(exc):
    first = str(exc).splitlines()[0]
    assert first.strip() and "Traceback" not in str(exc)
    assert "internal error" not in str(exc), str(exc)


def _run_case(case, backend="direct"):
    name, filter_name, overrides = case
    model = _MODELS[name]
    try:
        run = scenarios.simulate_scenario(model, filter=filter_name, backend=backend,
                                          stop_time=STOP_S, parameters=overrides,
                                          build=False, log=lambda m: None)
    except NavfmuError as exc:
        _assert_one_line_error(exc)
        if isinstance(exc, SimulationError):  # names the component, the FMU's own words first
            first = str(exc).splitlines()[0]
            assert first.startswith(f"component '{exc.component}'"), first
            assert "fmi2" not in first, first
        return
    _assert_finite(run.results)
    for metrics in run.metrics.values():
        for group in ("position_rms_m", "velocity_rms_mps", "attitude_rms_deg"):
            assert all(math.isfinite(v) for v in metrics[group].values()), metrics[group]


_FAST = settings(deadline=None, derandomize=True, database=None,
                 suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])


@settings(_FAST, max_examples=100)
@given(scenario_cases())
def test_scenario_parameters_run_or_fail_in_one_line(case):
    _run_case(case)


@pytest.mark.slow
@settings(_FAST, max_examples=600, derandomize=False)
@given(scenario_cases())
def test_scenario_parameters_run_or_fail_in_one_line_many(case):
    _run_case(case)


@settings(_FAST, max_examples=6)
@given(case=scenario_cases())
def test_scenario_parameters_through_the_fmus(fmus_built, case):
    _run_case(case, backend="fmu")


# -- inputs of the filter components ------------------------------------------------------
_INPUT_SPECIAL = st.sampled_from([0.0, -1.0, 1e300, -1e300, math.inf, -math.inf, math.nan,
                                  0.01, 1e-12])


@st.composite
def filter_inputs(draw):
    """A filter and 20 steps of inputs: a plausible IMU/GNSS stream with some values
    replaced by hostile ones (NaN, inf, huge, negative)."""
    cls = draw(st.sampled_from([components.Kf, components.Iakf, components.NewtonRobustKf,
                                components.Ukf, components.ImmUkf]))
    steps = []
    for k in range(1, 21):
        inputs = {p.name: p.default() for p in cls.inputs}
        inputs.update(imu_time=0.01 * k, imu_dt=0.01, imu_dvel_z=-9.8 * 0.01,
                      gnss_time=0.01 * k, gnss_epoch=k // 5, gnss_valid=True)
        for key in draw(st.lists(st.sampled_from(sorted(inputs)), max_size=2)):
            if isinstance(inputs[key], bool):
                inputs[key] = draw(st.booleans())
            elif isinstance(inputs[key], int):
                inputs[key] = draw(st.integers(-2 ** 31, 2 ** 31 - 1))
            else:
                inputs[key] = draw(st.one_of(_INPUT_SPECIAL, st.floats()))
        steps.append(inputs)
    return cls, steps


def _names(steps):
    """The filter inputs by FMI type, as the master groups them."""
    first = steps[0]
    return ([n for n, v in first.items() if isinstance(v, float)],
            [n for n, v in first.items() if type(v) is int],
            [n for n, v in first.items() if isinstance(v, bool)])


def _step_instance(inst, steps, outputs):
    """Step a prepared, initialized instance through ``steps``: each step either gives finite
    outputs or raises the SimulationError naming the component (then the case ends)."""
    reals, ints, bools = _names(steps)
    for k, inputs in enumerate(steps):
        inst.set_inputs([inputs[n] for n in reals], [inputs[n] for n in ints],
                        [int(inputs[n]) for n in bools])
        try:
            inst.do_step(0.01 * k, 0.01)
        except SimulationError as exc:
            _assert_one_line_error(exc)
            assert str(exc).startswith("component 'filter' ("), str(exc)
            return
        real_out, _, _ = inst.get_outputs()
        assert np.isfinite(real_out).all(), dict(zip(outputs, real_out))


def _step_filter(cls, steps):
    """The master's direct path (DirectInstance), which reports errors as the FMU shell does."""
    inst = DirectInstance(cls(), "filter")
    reals, ints, bools = _names(steps)
    outputs = [p.name for p in cls.outputs if p.type == "Real"]
    inst.prepare(reals + ints + bools, outputs)
    inst.initialize(0.0, 1.0)
    _step_instance(inst, steps, outputs)


@settings(_FAST, max_examples=30)
@given(filter_inputs())
def test_filter_inputs_step_or_fail_cleanly(case):
    _step_filter(*case)


@pytest.mark.slow
@settings(_FAST, max_examples=150, derandomize=False)
@given(filter_inputs())
def test_filter_inputs_step_or_fail_cleanly_many(case):
    _step_filter(*case)


@pytest.fixture(scope="module")
def fmus_built():
    fmu_build.build(log=None)


# -- the same inputs through a filter FMU -------------------------------------------------
@pytest.fixture(scope="module")
def kf_fmu(fmus_built):
    return fmu_build.fmu_path("Kf")


@settings(_FAST, max_examples=8, suppress_health_check=list(HealthCheck))
@given(case=filter_inputs())
def test_filter_fmu_inputs_step_or_fail_with_status(kf_fmu, case):
    _, steps = case
    reals, ints, bools = _names(steps)
    outputs = [p.name for p in components.Kf.outputs if p.type == "Real"]
    inst = FmuInstance(kf_fmu, "filter")
    try:
        inst.prepare(reals + ints + bools, outputs)
        inst.initialize(0.0, 1.0)
        _step_instance(inst, steps, outputs)
    finally:
        inst.terminate()
