"""Property-based tests (hypothesis) over the option values of ``montecarlo``, ``tune``,
``report``, ``convert``, ``export`` and ``package`` (``tests/test_fuzz.py`` covers the run
path of ``run`` and ``compare``).

Whatever the values (valid ones, boundaries, junk text, empty text, numbers beyond 64 bits,
paths nothing can be written to), the command either succeeds (exit 0) or refuses with
exit 2 and a first line ``navfmu: error: ...``: never an internal error or a traceback, and
a refused command leaves its folder exactly as it found it (nothing written, nothing made).
Each example runs in a fresh folder that is also the working directory (default output
folders land there).  Valid campaigns and tunings are kept tiny (a fraction of a second of
simulated time, one run, two individuals).  The default run draws 10 examples per command
(about 20 s in all on 2 cores), ``-m slow`` 60 more per command.
"""
from __future__ import annotations

import contextlib
import io
import os
import tempfile
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from orchestrator.building import build as fmu_build
from orchestrator.cli.commands import main

ROOT = fmu_build.ROOT
MODEL = str(ROOT / "models" / "aircraft_500s")
GIS = str(ROOT / "tests" / "data" / "gnss-ins-sim" / "motion_def-3d_mid_100Hz")
UNWRITABLE = "/proc/navfmu-fuzz"
DEFAULT_EXAMPLES = 10
SLOW_EXAMPLES = 60
#: text that is no number, no name and no path
JUNK = ["", "x", "-", "nan", "1e999", "99999999999999999999", "-99999999999999999999", " "]


@pytest.fixture(scope="module", autouse=True)
def _fmus():
    fmu_build.build(log=None)


def _listing(folder: Path):
    return sorted((str(p.relative_to(folder)), p.is_dir()) for p in folder.rglob("*"))


def _navfmu(folder: Path, args):
    """Run ``navfmu args`` in ``folder`` (its working directory); (code, stdout, stderr)."""
    out, err = io.StringIO(), io.StringIO()
    here = os.getcwd()
    os.chdir(folder)
    try:
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            try:
                main([str(a) for a in args])
                code = 0
            except SystemExit as exc:
                code = exc.code
    finally:
        os.chdir(here)
    return code, out.getvalue(), err.getvalue()


def _check(build_args, prepare=None):
    """Run the command ``build_args(folder)`` in a fresh folder (after ``prepare(folder)``)
    and assert the clean outcome of the module docstring."""
    with tempfile.TemporaryDirectory(prefix="navfmu-fuzz-") as tmp:
        folder = Path(tmp)
        if prepare is not None:
            prepare(folder)
        before = _listing(folder)
        args = build_args(folder)
        code, out, err = _navfmu(folder, args)
        assert "internal error" not in err and "Traceback" not in err + out, (args, err)
        assert code in (0, 2), (args, code, err)
        if code == 2:
            lines = err.strip().splitlines()
            assert lines and lines[0].startswith("navfmu: error: "), (args, err)
            assert err.count("navfmu: error:") == 1, (args, err)
            assert _listing(folder) == before, (args, err)


def _path(kind: str):
    """An output path: in the example's folder, empty, unwritable, or the folder itself."""
    return st.sampled_from([("in", kind), ("empty", ""), ("unwritable", UNWRITABLE + kind),
                            ("folder", ""), ("missing-parent", kind)])


def _resolve(path, folder: Path):
    where, kind = path
    return {"in": lambda: folder / f"out{kind}", "empty": lambda: "",
            "unwritable": lambda: kind, "folder": lambda: folder,
            "missing-parent": lambda: folder / "a" / "b" / f"out{kind}"}[where]()


def _option(name, values):
    """``[name, value]`` or nothing."""
    return st.one_of(st.just([]), st.sampled_from(values).map(lambda v: [name, v]))


def _options(**choices):
    return st.fixed_dictionaries({k: _option(f"--{k.replace('_', '-')}", v)
                                  for k, v in choices.items()})


def _flat(options):
    return [x for pair in options.values() for x in pair]


# -- montecarlo ----------------------------------------------------------------------------
MONTECARLO = _options(
    runs=["1", "0", "-1", "2"] + JUNK, filters=["Kf", "Nope", "Kf,Kf", ",", "Kf,InsOnly"],
    workers=["1", "0", "-3"] + JUNK, seed=["1", "0", "-1", "2147483647", "2147483000"] + JUNK,
    seed_offset=["gnss=1", "gnss", "radar=1", "gnss=99999999999999999999"],
    backend=["direct", "fmu", "x"], stop=["0.05", "-5", "0", "inf", "1e9"] + JUNK,
    window=["0:0.04", "nan:3", "1:0", "0:inf"] + JUNK, samples=["all", "fixes", "x"],
    set=["gnss.seed=nan", "gnss.output_delay=nan", "filter.nope=1", "bad", "gnss.seed=7",
         "gnss.seed=99999999999999999999", "trajectory.imu_period=0"],
    series=["csv", "parquet", "x"], scheduler=["foo", "tcp://:x", "tcp://host:notaport"])


def _montecarlo(options, out):
    options = dict(options)
    options.setdefault("runs", [])
    if not options["runs"]:
        options["runs"] = ["--runs", "1"]
    if not options.get("filters"):
        options["filters"] = ["--filters", "Kf"]
    if not options.get("stop"):
        options["stop"] = ["--stop", "0.05"]
    return lambda folder: ["montecarlo", MODEL, "--out", _resolve(out, folder), *_flat(options)]


@settings(max_examples=DEFAULT_EXAMPLES, deadline=None, derandomize=True,
          suppress_health_check=list(HealthCheck))
@given(MONTECARLO, _path(""))
def test_montecarlo_options(options, out):
    _check(_montecarlo(options, out))


@pytest.mark.slow
@settings(max_examples=SLOW_EXAMPLES, deadline=None, suppress_health_check=list(HealthCheck))
@given(MONTECARLO, _path(""))
def test_montecarlo_options_more(options, out):
    _check(_montecarlo(options, out))


# -- tune ------------------------------------------------------------------------------------
TUNE = _options(
    component=["filter", "gnss", "nope", ""], range=["r_pos_n=1:10", "r_pos_n=10:1",
                                                     "r_pos_n=nan:1", "nope=1:2", "x"],
    generations=["1", "0", "-1"] + JUNK, population=["2", "1", "0", "-2"] + JUNK,
    workers=["1", "0"] + JUNK, seed=["0", "-1", "99999999999999999999"] + JUNK,
    train_seeds=["1", "1,2", "x", "99999999999999999999", ",", "-1"],
    backend=["direct", "x"], stop=["0.05", "-1", "0"] + JUNK, window=["0:0.04", "nan:1"],
    scheduler=["foo"])
TUNE_PARAMS = st.sampled_from(["r_pos_n", "r_pos_n,p0_pos", "seed", "nope", "r_pos_n,r_pos_n",
                               "", ","])


def _tune(options, params, out, ssv):
    options = dict(options)
    for key, default in (("generations", "1"), ("population", "2"), ("stop", "0.05")):
        if not options.get(key):
            options[key] = [f"--{key}", default]

    def args(folder):
        extra = [] if ssv is None else ["--ssv", _resolve(ssv, folder)]
        return ["tune", MODEL, "--params", params, "--out", _resolve(out, folder), *extra,
                *_flat(options)]
    return args


@settings(max_examples=DEFAULT_EXAMPLES, deadline=None, derandomize=True,
          suppress_health_check=list(HealthCheck))
@given(TUNE, TUNE_PARAMS, _path(""), st.one_of(st.none(), _path(".ssv")))
def test_tune_options(options, params, out, ssv):
    _check(_tune(options, params, out, ssv))


@pytest.mark.slow
@settings(max_examples=SLOW_EXAMPLES, deadline=None, suppress_health_check=list(HealthCheck))
@given(TUNE, TUNE_PARAMS, _path(""), st.one_of(st.none(), _path(".ssv")))
def test_tune_options_more(options, params, out, ssv):
    _check(_tune(options, params, out, ssv))


# -- report (--only-finished: the option checks, never a 25-minute campaign) ---------------
REPORT = _options(runs=["1", "0", "-1", "3"] + JUNK, workers=["1", "0", "-1", "2"] + JUNK,
                  stop=["0.05", "-1", "0"] + JUNK, scheduler=["foo", "tcp://:x"])


def _report(options, out, local_cluster):
    return lambda folder: (["report", "--only-finished", "--out", _resolve(out, folder),
                            *_flat(options)] + (["--local-cluster"] if local_cluster else []))


@settings(max_examples=DEFAULT_EXAMPLES, deadline=None, derandomize=True,
          suppress_health_check=list(HealthCheck))
@given(REPORT, _path(""), st.booleans())
def test_report_options(options, out, local_cluster):
    _check(_report(options, out, local_cluster))


@pytest.mark.slow
@settings(max_examples=SLOW_EXAMPLES, deadline=None, suppress_health_check=list(HealthCheck))
@given(REPORT, _path(""), st.booleans())
def test_report_options_more(options, out, local_cluster):
    _check(_report(options, out, local_cluster))


# -- convert ---------------------------------------------------------------------------------
def _kf_gins_files(folder: Path):
    """KF-GINS IMU and GNSS files of a short level flight (tests/test_sensorlog.py writes
    them in KF-GINS's layout, independently of the converter)."""
    from test_sensorlog import _log, _write_kf_gins

    log = _log(n=40, dt=0.005, t0=456300.0)
    for k, s in (("std_n", 1.5), ("std_e", 1.2), ("std_d", 3.0)):
        log.gnss[k] = log.gnss["time"] * 0 + s
    (folder / "in").mkdir()
    _write_kf_gins(folder / "in", log)


SOURCES = st.sampled_from(["gis", "missing", "a-file", "", "the-folder"])
KF_FILES = st.sampled_from(["imu.txt", "gnss.txt", "truth.nav", "missing.txt", ""])


def _source(name, folder: Path):
    return {"gis": GIS, "missing": folder / "nope", "a-file": folder / "in" / "imu.txt",
            "": "", "the-folder": folder}[name]


def _convert_gis(source, dst, run):
    return lambda folder: (["convert", "gnss-ins-sim", _source(source, folder),
                            _resolve(dst, folder)] + ([] if run is None else ["--run", run]))


def _convert_kf(files, dst):
    return lambda folder: (["convert", "kf-gins"]
                           + [folder / "in" / f if f else "" for f in files]
                           + [_resolve(dst, folder)])


RUN_INDEX = st.one_of(st.none(), st.sampled_from(["0", "1", "-1"] + JUNK))


@settings(max_examples=DEFAULT_EXAMPLES, deadline=None, derandomize=True,
          suppress_health_check=list(HealthCheck))
@given(SOURCES, _path(""), RUN_INDEX, st.lists(KF_FILES, min_size=0, max_size=3))
def test_convert_options(source, dst, run, files):
    _check(_convert_gis(source, dst, run), _kf_gins_files)
    _check(_convert_kf(files, dst), _kf_gins_files)


@pytest.mark.slow
@settings(max_examples=SLOW_EXAMPLES, deadline=None, suppress_health_check=list(HealthCheck))
@given(SOURCES, _path(""), RUN_INDEX, st.lists(KF_FILES, min_size=0, max_size=3))
def test_convert_options_more(source, dst, run, files):
    _check(_convert_gis(source, dst, run), _kf_gins_files)
    _check(_convert_kf(files, dst), _kf_gins_files)


# -- export and package ----------------------------------------------------------------------
SCENARIOS = st.sampled_from(["model", "missing", "", "gis", "ssd"])
SUFFIXES = st.sampled_from([".fmu", ".ssp", ".txt", ""])


def _scenario(name, folder):
    return {"model": MODEL, "missing": folder / "nope", "": "", "gis": GIS,
            "ssd": Path(MODEL) / "SystemStructure.ssd"}[name]


def _system(command, scenario, out, suffix):
    where, _ = out
    return lambda folder: [command, _scenario(scenario, folder), "--out",
                           _resolve((where, suffix), folder)]


@settings(max_examples=DEFAULT_EXAMPLES, deadline=None, derandomize=True,
          suppress_health_check=list(HealthCheck))
@given(st.sampled_from(["export", "package"]), SCENARIOS, _path(""), SUFFIXES)
def test_export_and_package_options(command, scenario, out, suffix):
    _check(_system(command, scenario, out, suffix))


@pytest.mark.slow
@settings(max_examples=SLOW_EXAMPLES, deadline=None, suppress_health_check=list(HealthCheck))
@given(st.sampled_from(["export", "package"]), SCENARIOS, _path(""), SUFFIXES)
def test_export_and_package_options_more(command, scenario, out, suffix):
    _check(_system(command, scenario, out, suffix))


def test_the_strategies_reach_success_and_refusal():
    """The cases above are not all refusals: a valid campaign, tuning, conversion, export and
    package succeed through the same check (so a refusal is the options' doing)."""
    for build in (_montecarlo({}, ("in", "")), _tune({}, "r_pos_n", ("in", ""), None),
                  _convert_gis("gis", ("in", ""), None),
                  _system("export", "model", ("in", ""), ".fmu"),
                  _system("package", "model", ("in", ""), ".ssp")):
        with tempfile.TemporaryDirectory() as tmp:
            code, _, err = _navfmu(Path(tmp), build(Path(tmp)))
            assert code == 0, err
