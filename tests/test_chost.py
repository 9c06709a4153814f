"""Every FMU in a native (non-Python) FMI host: a small C program, tests/chost/fmi2_host.c,
compiled here with the system ``cc`` against the FMI 2 headers fmpy ships, run with exactly
the environment ``navfmu env`` prints.  Each run must exit with status 0 (no crash at exit)
and print the values fmpy reads from the same FMU after the same calls.  Also: what
``navfmu env`` prints, and the two causes of the crash at exit that used to kill about half of
the native runs (see navcore/innovation_stats.py and
fmushell.pythonfmu_fixes.balance_loader_decref).
"""
from __future__ import annotations

import json
import os
import re
import shlex
import shutil
import signal
import subprocess
import sys
import textwrap
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path

import fmpy
import pytest
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave

from orchestrator.building import build as fmu_build

from native_hosts import compile_c_host

ROOT = Path(__file__).resolve().parent.parent
HOST_SOURCE = Path(__file__).resolve().parent / "chost" / "fmi2_host.c"
FMU_NAMES = [s.stem for s in fmu_build.slave_scripts()]
N_STEPS = 5
#: host runs per FMU in the default suite (concurrent, to shake out exit-time crashes);
#: the intermittent ones are the 100-run slow test's job
RUNS_DEFAULT = 4
RUNS_SLOW = 100
WORKERS = max(2, min(4, os.cpu_count() or 1))
#: input values an FMU cannot run on the generic constants with (a guided vehicle refuses a
#: navigation solution far from its route): name -> value
INPUT_VALUES = {"GuidedUav": {"nav_lat": 0.6998770300497261, "nav_lon": 2.069960492865275,
                              "nav_h": 150.0, "nav_vn": 25.0}}
#: String parameters an FMU cannot run without
STRING_PARAMETERS = {"ImuGnssReplay": {"log": str(ROOT / "models" / "replay_gnss_ins_sim" / "log")}}


def _navfmu(*args):
    return subprocess.run([sys.executable, "-m", "orchestrator.cli", *args], cwd=ROOT,
                          capture_output=True, text=True, timeout=120)


@pytest.fixture(scope="module")
def host(tmp_path_factory):
    return compile_c_host(HOST_SOURCE, tmp_path_factory.mktemp("chost"))


@pytest.fixture(scope="module")
def env_file(tmp_path_factory):
    r = _navfmu("env")
    assert r.returncode == 0, r.stderr
    path = tmp_path_factory.mktemp("hostenv") / "navfmu-env.sh"
    path.write_text(r.stdout)
    return path


@dataclass
class Case:
    """One FMU prepared for the host: its command-line arguments and fmpy's values."""
    name: str
    args: list
    expected: list


def _prepare(name, folder):
    """Extract the FMU, choose its inputs (time tags follow the step, the rest constants)
    and read the Real outputs through fmpy after the calls the C host makes."""
    strings = STRING_PARAMETERS.get(name, {})
    fmu = fmu_build.fmu_path(name)
    md = read_model_description(str(fmu))
    unzipped = extract(str(fmu), unzipdir=str(folder))
    h = float(md.defaultExperiment.stepSize)
    inputs, input_args, outputs, string_params = [], [], [], []
    for v in md.modelVariables:
        if v.type == "String" and v.name in strings:
            string_params.append((v.valueReference, strings[v.name]))
            input_args.append(f"{v.valueReference}=s:{strings[v.name]}")
        if v.type != "Real":
            continue
        if v.causality == "output":
            outputs.append(v.valueReference)
        elif v.causality == "input":
            kind = "t" if v.name.endswith("_time") else "h" if v.name.endswith("_dt") else \
                repr(INPUT_VALUES.get(name, {}).get(v.name, 1e-3 * (len(inputs) + 1)))
            inputs.append((v.valueReference, kind))
            input_args.append(f"{v.valueReference}={kind}")
    slave = FMU2Slave(guid=md.guid, unzipDirectory=unzipped,
                      modelIdentifier=md.coSimulation.modelIdentifier, instanceName="host")
    slave.instantiate()
    slave.setupExperiment(startTime=0.0)
    if string_params:
        slave.setString([vr for vr, _ in string_params], [text for _, text in string_params])
    slave.enterInitializationMode()
    slave.exitInitializationMode()
    for k in range(N_STEPS):
        if inputs:
            values = [(k + 1) * h if kind == "t" else h if kind == "h" else float(kind)
                      for _, kind in inputs]
            slave.setReal([vr for vr, _ in inputs], values)
        slave.doStep(k * h, h)
    expected = slave.getReal(outputs)
    slave.terminate()
    slave.freeInstance()
    library = Path(unzipped) / "binaries" / "linux64" / f"{md.coSimulation.modelIdentifier}.so"
    args = [str(library), md.guid, Path(unzipped, "resources").as_uri(), repr(h), str(N_STEPS),
            *input_args, *map(str, outputs)]
    return Case(name, args, expected)


@pytest.fixture(scope="module")
def cases(tmp_path_factory):
    fmu_build.build(log=None)
    cache = {}

    def get(name):
        if name not in cache:
            cache[name] = _prepare(name, tmp_path_factory.mktemp(name))
        return cache[name]

    return get


def _run_host(host, env_file, case):
    """One run in a clean environment plus what ``navfmu env`` printed: (status, values, err)."""
    r = subprocess.run(["sh", "-c", '. "$0" && exec "$@"', str(env_file), str(host), *case.args],
                       env={"PATH": os.environ.get("PATH", "/usr/bin:/bin")},
                       capture_output=True, text=True, timeout=300)
    values = [float(x) for x in r.stdout.split()] if r.returncode == 0 else None
    return r.returncode, values, r.stderr[-2000:]


def _describe(status):
    return f"killed by {signal.Signals(-status).name}" if status < 0 else f"exit status {status}"


def _run_many(host, env_file, case, n):
    with ThreadPoolExecutor(WORKERS) as pool:
        results = list(pool.map(lambda _: _run_host(host, env_file, case), range(n)))
    failures = [(s, err) for s, _, err in results if s != 0]
    assert not failures, (f"{case.name}: {len(failures)} of {n} native-host runs failed; first: "
                          f"{_describe(failures[0][0])}\n{failures[0][1]}")
    for _, values, _ in results:
        assert values == case.expected, f"{case.name}: native host and fmpy disagree"


@pytest.mark.parametrize("name", FMU_NAMES)
def test_native_host_runs_fmu_and_reads_fmpy_values(host, env_file, cases, name):
    case = cases(name)
    assert any(v != 0.0 for v in case.expected), "pick outputs that the steps change"
    _run_many(host, env_file, case, RUNS_DEFAULT)


@pytest.mark.slow
@pytest.mark.parametrize("name", FMU_NAMES)
def test_native_host_100_runs_without_a_crash(host, env_file, cases, name):
    _run_many(host, env_file, cases(name), RUNS_SLOW)


def test_navfmu_env_names_this_interpreter():
    sh, js = _navfmu("env"), _navfmu("env", "--format", "json")
    assert sh.returncode == 0 and js.returncode == 0, sh.stderr + js.stderr
    env = json.loads(js.stdout)
    assert sh.stdout.split("\n")[:3] == [f"export {k}={shlex.quote(v)}" for k, v in env.items()]
    assert set(env) == {"LD_PRELOAD", "PYTHONHOME", "PYTHONPATH"}
    assert env["PYTHONHOME"] == sys.base_prefix
    import numpy
    import scipy
    folders = env["PYTHONPATH"].split(os.pathsep)
    for package in (numpy, scipy):
        assert str(Path(package.__file__).resolve().parent.parent) in folders
    # the library the interpreter itself runs on, as the dynamic linker resolves it
    if shutil.which("ldd") is None:
        pytest.skip("no ldd on PATH: cannot ask the dynamic linker which libpython runs")
    ldd = subprocess.run(["ldd", sys.executable], capture_output=True, text=True)
    linked = re.findall(r"(libpython\S+) => (\S+)", ldd.stdout)
    if not linked:
        pytest.skip(f"{sys.executable} does not link libpython dynamically; nothing to compare")
    assert Path(env["LD_PRELOAD"]).resolve() == Path(linked[0][1]).resolve()


def test_fmu_import_chain_loads_no_scipy_stats_or_uarray():
    """scipy.stats pulls in scipy.fft and the C++ extension scipy._lib._uarray, whose static
    destructors run before pythonfmu's Py_FinalizeEx in a native host that calls exit():
    a segfault at exit in about half of the runs (navcore/innovation_stats.py)."""
    code = textwrap.dedent(f"""
        import sys
        sys.path.insert(0, {str(fmu_build.FMU_SOURCES)!r})
        for name in {FMU_NAMES!r}:
            __import__(name)
        print(" ".join(m for m in sys.modules
                       if m.startswith(("scipy.stats", "scipy.fft", "scipy._lib._uarray"))))
    """)
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    assert r.stdout.split() == []


def test_pythonfmu_loader_leaves_script_globals_fully_referenced(cases):
    """pythonfmu 0.7 drops one reference to the script's module dict per fmi2Instantiate
    (a Py_DECREF of a borrowed reference); fmushell gives it back.  Every object that refers
    to the dict must be counted in its reference count, however many instances were made."""
    case = cases("GnssReceiver")
    unzipped = Path(case.args[0]).parents[2]
    code = textwrap.dedent(f"""
        import gc, sys
        from fmpy import read_model_description
        from fmpy.fmi2 import FMU2Slave
        md = read_model_description({str(unzipped)!r})
        slaves = []
        for i in range(4):
            s = FMU2Slave(guid=md.guid, unzipDirectory={str(unzipped)!r},
                          modelIdentifier="GnssReceiver", instanceName=f"r{{i}}")
            s.instantiate()
            slaves.append(s)
        gc.collect()
        module = open({str(unzipped / "resources" / "slavemodule.txt")!r}).read().strip()
        d = sys.modules[module].__dict__
        print(sys.getrefcount(d) - 1, len(gc.get_referrers(d)))
    """)
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    counted, referrers = map(int, r.stdout.split())
    assert counted >= referrers


# -- every refusal path, in a host whose logger builds std::strings (as OMSimulator's does) ----
REFUSAL_SOURCE = Path(__file__).resolve().parent / "chost" / "fmi2_refusals.cpp"
#: FMUs driven through every refusal path: a filter, a sensor, the replay, an AHRS
REFUSAL_FMUS = ["Kf", "GnssReceiver", "ImuGnssReplay", "UkfAhrs"]
#: String values whose initialization must be refused, per FMU
BAD_STRINGS = {"ImuGnssReplay": {"log": ["", "/nonexistent/navfmu/log"]}}
FMI2_OK, FMI2_WARNING, FMI2_DISCARD, FMI2_ERROR, FMI2_FATAL = range(5)
#: the status each refused call must return (the exit_init_* cases: FMI2_ERROR)
REFUSAL_STATUS = {
    "instantiate_without_script": FMI2_FATAL, "instantiate_null_resources": FMI2_FATAL,
    "callback_structure_released_after_instantiation": FMI2_ERROR,
    "do_step_before_initialization": FMI2_ERROR, "get_unknown_value_reference": FMI2_ERROR,
    "get_real_as_integer": FMI2_ERROR, "set_output": FMI2_ERROR,
    "set_fixed_parameter_after_initialization": FMI2_ERROR, "do_step_at_wrong_time": FMI2_ERROR,
    "do_step_of_zero_size": FMI2_ERROR, "do_step_with_nan_input": FMI2_ERROR,
    "do_step_after_an_error": FMI2_ERROR, "do_step_after_an_error_again": FMI2_ERROR,
    "deserialize_foreign_blob": FMI2_ERROR, "calls_without_an_instance": FMI2_ERROR,
    "set_debug_logging_null_category": FMI2_ERROR, "get_directional_derivative": FMI2_ERROR,
    "set_real_input_derivatives": FMI2_ERROR, "get_real_output_derivatives": FMI2_ERROR,
    "cancel_step": FMI2_ERROR, "get_status": FMI2_ERROR,
    "get_real_status_of_wrong_kind": FMI2_DISCARD, "get_integer_status": FMI2_DISCARD,
    "get_boolean_status_of_wrong_kind": FMI2_DISCARD, "get_string_status": FMI2_DISCARD,
}
#: refused without a message: no instance to log through
SILENT = {"calls_without_an_instance"}


@pytest.fixture(scope="module")
def refusal_host(tmp_path_factory):
    cxx = shutil.which("c++") or shutil.which("g++")
    if cxx is None:
        pytest.skip("no C++ compiler (c++, g++) on PATH: cannot build the C++ FMI host")
    include = Path(fmpy.__file__).parent / "c-code"
    exe = tmp_path_factory.mktemp("cxxhost") / "fmi2_refusals"
    r = subprocess.run([cxx, "-std=c++17", "-O1", "-Wall", "-Wextra", "-Werror", "-I",
                        str(include), "-o", str(exe), str(REFUSAL_SOURCE), "-ldl"],
                       capture_output=True, text=True)
    assert r.returncode == 0, f"compiling {REFUSAL_SOURCE} failed:\n{r.stderr}"
    return exe


def _refusal_args(name, folder):
    """The host's arguments for FMU ``name`` and the model description's LogCategories."""
    fmu = fmu_build.fmu_path(name)
    md = read_model_description(str(fmu))
    unzipped = Path(extract(str(fmu), unzipdir=str(folder / "fmu")))
    (folder / "empty").mkdir()
    by_name = {v.name: v for v in md.modelVariables}
    real = [v for v in md.modelVariables if v.type == "Real"]
    output = next(v for v in real if v.causality == "output")
    inputs = [v for v in real
              if v.causality == "input" and not v.name.endswith(("_time", "_dt"))]
    parameter = next((v for v in real if v.causality == "parameter"), None)
    args = [str(unzipped / "binaries" / "linux64" / f"{md.coSimulation.modelIdentifier}.so"),
            md.guid, (unzipped / "resources").as_uri(), (folder / "empty").as_uri(),
            md.defaultExperiment.stepSize, str(output.valueReference),
            str(inputs[0].valueReference if inputs else -1),
            str(parameter.valueReference if parameter else -1)]
    for pname, text in STRING_PARAMETERS.get(name, {}).items():
        args.append(f"s:{by_name[pname].valueReference}={text}")
    for pname, texts in BAD_STRINGS.get(name, {}).items():
        args += [f"bad_s:{by_name[pname].valueReference}={t}" for t in texts]
    if parameter is not None:
        args.append(f"bad_r:{parameter.valueReference}=nan")
    return args, {c.name for c in md.logCategories}, bool(inputs), parameter is not None


def _parse_cases(stdout):
    cases, current = {}, None
    for line in stdout.splitlines():
        kind, *rest = line.split()
        if kind == "case":
            current = cases[rest[0]] = {"status": int(rest[2]), "messages": []}
        elif kind == "msg":
            current["messages"].append((int(rest[0]), rest[1] if len(rest) > 1 else ""))
    return cases


@pytest.mark.parametrize("name", REFUSAL_FMUS)
def test_every_refusal_reaches_a_cxx_host_log_with_a_declared_category(
        refusal_host, env_file, tmp_path, name):
    """With loggingOn = fmi2False, every refused call returns its FMI status and logs a
    message of that status or worse (errors are reported whatever loggingOn says; a step
    after an error is refused in FMI's error state, each time with a message), each with a
    category
    is one the model description declares: never NULL, which would end this host (its
    logger builds std::strings, as OMSimulator's does) with std::terminate, status 134."""
    fmu_build.build([name], log=None)
    args, categories, has_inputs, has_real = _refusal_args(name, tmp_path)
    r = subprocess.run(["sh", "-c", '. "$0" && exec "$@"', str(env_file), str(refusal_host),
                        *args], env={"PATH": os.environ.get("PATH", "/usr/bin:/bin")},
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, f"{_describe(r.returncode)}\n{r.stderr[-3000:]}"
    cases = _parse_cases(r.stdout)
    expected = dict(REFUSAL_STATUS)
    if not has_inputs:
        for case in ("do_step_with_nan_input", "do_step_after_an_error",
                     "do_step_after_an_error_again"):
            expected.pop(case)
    init_cases = {c for c in cases if c.startswith("exit_init_")}
    n_bad = has_real + sum(len(t) for t in BAD_STRINGS.get(name, {}).values())
    assert len(init_cases) == n_bad
    expected.update({c: FMI2_ERROR for c in init_cases})
    assert {c: v["status"] for c, v in cases.items()} == expected, r.stderr[-3000:]
    for case, result in cases.items():
        statuses = [s for s, _ in result["messages"]]
        if case in SILENT:
            assert statuses == [], case
        else:
            assert statuses and max(statuses) >= expected[case], (case, result["messages"])
        assert {c for _, c in result["messages"]} <= categories, (case, result["messages"])
