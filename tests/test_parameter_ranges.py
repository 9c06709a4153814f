"""Declared ranges of the components' parameters and inputs (navcore, no FMI).

Every numeric parameter declares its accepted range once, on its port; setting a value
outside it (or a non-finite Real) is refused with the parameter, the value and the range.
"""
from __future__ import annotations

import inspect
import math

import pytest

from docs_tables import documented_parameters, parse_range, printed_exactly
from navcore.components import registry as components
from navcore.core import signals
from navcore.core.component import InputError, Limits, ParameterError
from navcore.errors import StepSizeError
from navcore.components.filter_component import InsGnssFilter
from navcore.sensors.gnss_errors import GnssErrorModel
from navcore.sensors.imu_errors import ImuErrorModel

NUMERIC = [(cls, p) for cls in components.REGISTRY.values() for p in cls.parameters
           if p.type in ("Real", "Integer")]


def _engine_keywords(engine_class):
    """{name: default} of the keyword-only options of an engine and its bases."""
    keywords = {}
    for klass in engine_class.__mro__:
        init = vars(klass).get("__init__")
        if init is None:
            continue
        for param in inspect.signature(init).parameters.values():
            if param.kind is param.KEYWORD_ONLY:
                keywords[param.name] = param.default
    return keywords


@pytest.mark.parametrize("cls", [c for c in components.REGISTRY.values()
                                 if issubclass(c, InsGnssFilter)], ids=lambda c: c.model_name)
def test_engine_options_are_declared_once_on_the_component(cls):
    """The component's ports hold the one default and range of each engine option: the engine
    takes exactly the options the component passes, and none of them has a default there."""
    keywords = _engine_keywords(cls.engine_class)
    assert sorted(cls().engine_options()) == sorted(keywords)
    with_default = [n for n, d in keywords.items() if d is not inspect.Parameter.empty]
    assert not with_default, f"{cls.engine_class.__name__} has defaults for {with_default}"


def test_limits_text_and_membership():
    assert Limits(0.0, 1.0, low_open=True).text("m") == "(0, 1] m"
    assert Limits().text() == "finite" and Limits(0.0).text() == "[0, inf)"
    assert Limits(-math.pi / 2, math.pi / 2, True, True).text("rad") == "(-1.5708, 1.5708) rad"
    lim = Limits(0.0, 1.0, low_open=True)
    assert [lim.contains(x) for x in (0.0, 1e-300, 1.0, 1.0000001, math.nan, math.inf)] == [
        False, True, True, False, False, False]


def test_self_consistency_defaults_inside_and_extremes_refused_naming_the_declared_range():
    """Self-consistency (the refusal quotes the code's own declaration; the documented
    ranges are checked independently below): every default is inside its declared range,
    non-finite and huge values are refused naming the parameter and that range."""
    for cls, port in NUMERIC:
        assert port.limits.contains(port.default()), (cls.model_name, port.name)
        cls(**{port.name: port.default()})
        bad = [math.nan, math.inf, -math.inf] if port.type == "Real" else []
        bad += [x for x in (1e300, -1e300) if not port.limits.contains(x)]
        for value in bad:
            with pytest.raises(ParameterError) as err:
                cls(**{port.name: value})
            text = str(err.value)
            assert f"parameter '{port.name}'" in text, text
            assert port.limits.text(port.unit) in text, text


def _range_refusal(cls, name, value):
    """The ParameterError text if ``cls(name=value)`` is refused for its range, else None
    (other refusals, such as the order of the membership feet, are not this test's)."""
    try:
        cls(**{name: value})
    except ParameterError as err:
        return str(err) if f"'{name}' = " in str(err) and "accepted range" in str(err) else None
    return None


def _probes(documented):
    """(value, inside) pairs at the documented bounds: the bound itself (inside if closed)
    and a value just outside where the printed bound is exact, else values 1e-5 relative
    inside and outside of it (the table prints 6 digits)."""
    bounds = parse_range(documented.range)
    integer = documented.type == "Integer"
    probes = []
    for bound, closed, outward in ((bounds.low, bounds.low_closed, -1.0),
                                   (bounds.high, bounds.high_closed, 1.0)):
        if not math.isfinite(bound):
            continue
        if printed_exactly(bound):
            step = 1 if integer else max(abs(bound), 1.0) * 1e-9
            probes += [(bound, closed), (bound + outward * step, False)]
        else:
            off = abs(bound) * 1e-5
            probes += [(bound - outward * off, True), (bound + outward * off, False)]
    return [(int(round(v)) if integer else v, inside) for v, inside in probes]


DOCUMENTED = [(component, name, row) for component, rows in documented_parameters().items()
              for name, row in rows.items() if row.range not in ("-", "finite")]


@pytest.mark.parametrize("component, name, row", DOCUMENTED,
                         ids=[f"{c}.{n}" for c, n, _ in DOCUMENTED])
def test_documented_ranges_are_the_accepted_ones(component, name, row):
    """Each range in docs/signals.md's parameter tables (read from the document) against the
    component: a value on a closed bound is accepted, beyond a bound refused, the refusal
    quoting the documented range."""
    cls = components.REGISTRY[component]
    for value, inside in _probes(row):
        refusal = _range_refusal(cls, name, value)
        if inside:
            assert refusal is None, (value, refusal)
        else:
            assert refusal is not None, f"{component}.{name} = {value!r} accepted"
            assert f"accepted range {row.range}" in refusal, refusal


def test_huge_sigma_and_bias_name_the_range():
    with pytest.raises(ParameterError, match=r"'pos_sigma_n' = 1e\+300 is outside the "
                                             r"accepted range \[0, 10000\] m"):
        components.GnssReceiver(pos_sigma_n=1e300)
    with pytest.raises(ParameterError, match=r"'accel_bias_ug' = 1e\+300 is outside the "
                                             r"accepted range \[0, 1e\+06\] ug"):
        components.TrajectoryImu(accel_bias_ug=1e300)


def test_error_models_use_the_same_declaration():
    """The error models read their tables' ranges, so a direct user of the model gets the
    same refusal as the component."""
    with pytest.raises(ParameterError, match=r"\[0, 1e\+06\] ug"):
        ImuErrorModel({"accel_bias_ug": 2e6}, seed=1)
    with pytest.raises(ParameterError, match=r"\[0, 100\] m/s"):
        GnssErrorModel({"vel_sigma_n": 1e3}, seed=1)
    port = {p.name: p for p in components.GnssReceiver.parameters}["vel_sigma_n"]
    assert port.limits is GnssErrorModel.PARAMETERS["vel_sigma_n"][3]


def test_inputs_out_of_range_name_the_input():
    kf = components.Kf()
    kf.initialize(0.0)
    inputs = {p.name: p.default() for p in components.Kf.inputs}
    inputs.update(imu_time=0.01, imu_dt=0.01, imu_dtheta_x=1e300)
    with pytest.raises(InputError, match=r"input 'imu_dtheta_x' = 1e\+300 is outside the "
                                         r"accepted range \[-3.14159, 3.14159\] rad"):
        kf.step(0.0, 0.01, inputs)
    assert {p.name: p for p in signals.GNSS}["gnss_lat"].limits is signals.LATITUDE


def test_stop_time_beyond_the_profile():
    traj = components.TrajectoryImu(profile="aircraft_500s")
    traj.start(0.0)
    traj.check_stop_time(500.0)  # up to the end: fine
    with pytest.raises(ParameterError, match="after the end of profile 'aircraft_500s' at 500 s"):
        traj.check_stop_time(500.5)
    traj = components.TrajectoryImu(profile="aircraft_500s", extend_profile=True)
    traj.start(0.0)
    traj.check_stop_time(500.5)


@pytest.mark.parametrize("cls", [components.Kf, components.Ukf, components.UkfAhrs],
                         ids=lambda c: c.model_name)
def test_a_skipped_imu_interval_is_a_step_size_error_in_every_filter_family(cls):
    """A host stepping a filter more coarsely than the IMU delivers samples gets the same
    error class (StepSizeError, an InputError) from the INS/GNSS and the attitude filters."""
    component = cls()
    component.start(0.0)
    inputs = {p.name: p.default() for p in cls.inputs}
    dt = 0.01
    inputs.update(imu_dt=dt, imu_dvel_z=-9.8 * dt, mag_x=2e-5, mag_z=4e-5)
    inputs["imu_time"] = dt
    component.advance(0.0, dt, inputs)
    inputs["imu_time"] = 3 * dt                   # the interval (dt, 2 dt] never arrived
    with pytest.raises(StepSizeError, match="'imu_time'") as err:
        component.advance(dt, dt, inputs)
    assert isinstance(err.value, InputError)
