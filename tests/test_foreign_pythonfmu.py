"""Our FMUs beside an FMU built with the stock pythonfmu library, in one host process.

Every pythonfmu binary keeps its interpreter owner in a static ``shared_ptr`` that its own
``__attribute__((destructor))`` resets again after the static destructor destroyed it: a
decrement inside a freed heap block, which glibc reports as "corrupted unsorted chunks" or
"corrupted double-linked list" at exit when the block sits in a bin.  Our binary no longer
does that (native/vendor/pythonfmu-export/README.md) and fmushell has every pythonfmu binary
in the process, the third party's too, reset its owner first thing at exit
(fmushell.pythonfmu_fixes.finalize_python_at_exit).  Checked here in a native host
(tests/chost/fmi2_pair_host.c) and in fmpy, both orders, instances freed and left alive,
under glibc's heap checks; under valgrind in the slow run.
"""
from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import sys
import textwrap
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest
from fmpy import extract, read_model_description

from orchestrator.building import build as fmu_build

from native_hosts import compile_c_host

ROOT = Path(__file__).resolve().parent.parent
HOST_SOURCE = Path(__file__).resolve().parent / "chost" / "fmi2_pair_host.c"
OURS = "TrajectoryImu"
#: instantiate/step/free cycles of every FMU per process, before the last instantiation
CYCLES = 2
RUNS_PER_CHECKER = 2
STOCK_SCRIPT = '''
from pythonfmu import Fmi2Causality, Fmi2Slave, Real


class Stock(Fmi2Slave):
    """A plain pythonfmu slave: y = 2 u + t + h after each step."""

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.u = 1.0
        self.y = 0.0
        self.register_variable(Real("u", causality=Fmi2Causality.input))
        self.register_variable(Real("y", causality=Fmi2Causality.output))

    def do_step(self, current_time, step_size):
        self.y = 2.0 * self.u + current_time + step_size
        return True
'''
MALLOC_DEBUG = Path("/lib/x86_64-linux-gnu/libc_malloc_debug.so.0")


def _checkers():
    """glibc's heap checks, two ways: every freed block binned at once (no per-thread cache,
    so a write into a freed block hits the bin's links), checked by libc_malloc_debug where
    glibc has it (2.34 on); and the default heap.  Freed memory is perturbed in both."""
    binned = {"GLIBC_TUNABLES": "glibc.malloc.tcache_count=0", "MALLOC_CHECK_": "3"}
    if MALLOC_DEBUG.is_file():
        binned["LD_PRELOAD"] = str(MALLOC_DEBUG)
    return {"binned": binned, "default": {}}


CHECKERS = _checkers()


@pytest.fixture(scope="module")
def stock_fmu(tmp_path_factory):
    """The plain slave built by pythonfmu itself, with its own library (not ours)."""
    import pythonfmu
    from pythonfmu.builder import FmuBuilder
    folder = tmp_path_factory.mktemp("stock")
    script = folder / "Stock.py"
    script.write_text(STOCK_SCRIPT)
    fmu = FmuBuilder.build_FMU(script, dest=folder)
    wheel_library = (Path(pythonfmu.__file__).parent / "resources" / "binaries" / "linux64"
                     / "libpythonfmu-export.so")
    unzipped = Path(extract(str(fmu), unzipdir=str(folder / "unzipped")))
    library = unzipped / "binaries" / "linux64" / "Stock.so"
    assert library.read_bytes() == wheel_library.read_bytes(), "not the stock library"
    return fmu, unzipped


@pytest.fixture(scope="module")
def our_fmu(tmp_path_factory):
    fmu_build.build([OURS], log=None)
    fmu = fmu_build.fmu_path(OURS)
    return fmu, Path(extract(str(fmu), unzipdir=str(tmp_path_factory.mktemp(OURS))))


def _host_args(fmu, unzipped):
    md = read_model_description(str(fmu))
    name = md.coSimulation.modelIdentifier
    step = md.defaultExperiment.stepSize if md.defaultExperiment else None
    return [str(unzipped / "binaries" / "linux64" / f"{name}.so"), md.guid,
            (unzipped / "resources").as_uri(), str(step or 0.1)]


@pytest.fixture(scope="module")
def pair_host(tmp_path_factory):
    return compile_c_host(HOST_SOURCE, tmp_path_factory.mktemp("pairhost"))


@pytest.fixture(scope="module")
def host_env():
    """The environment ``navfmu env`` prints, in a clean process environment."""
    r = subprocess.run([sys.executable, "-m", "orchestrator.cli", "env", "--format", "json"],
                       cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    return {"PATH": os.environ.get("PATH", "/usr/bin:/bin"), **json.loads(r.stdout)}


def _checked(env, checker, run):
    """``env`` with the heap checks of ``checker`` (freed memory perturbed per run)."""
    extra = dict(CHECKERS[checker])
    preload = " ".join(p for p in (env.get("LD_PRELOAD"), extra.pop("LD_PRELOAD", None)) if p)
    return {**env, **extra, "MALLOC_PERTURB_": str(37 + 64 * run),
            **({"LD_PRELOAD": preload} if preload else {})}


def _ended(r):
    if r.returncode < 0:
        return f"killed by signal {-r.returncode}"
    return f"exit status {r.returncode}"


def _run_all(commands):
    """Run (label, argv, env) commands two at a time; the labels of those that failed."""
    def run(command):
        label, argv, env = command
        r = subprocess.run(argv, env=env, capture_output=True, text=True, timeout=300)
        ok = r.returncode == 0 and r.stdout.split()[-1:] == ["ok"]
        return None if ok else f"{label}: {_ended(r)}: {r.stderr.strip()[-300:]}"

    with ThreadPoolExecutor(2) as pool:
        return [f for f in pool.map(run, commands) if f]


@pytest.mark.parametrize("mode", ["free", "keep"])
def test_native_host_with_a_stock_pythonfmu_fmu_exits_cleanly(pair_host, host_env, stock_fmu,
                                                              our_fmu, mode):
    """Theirs first and ours first, each under both heap checks, twice: every process
    instantiates, steps and frees both FMUs, instantiates them again and exits (``keep``: with
    those instances alive) with status 0.  Before the fix about 6 in 10 of the ours-first
    processes and every theirs-first one with binned blocks and live instances aborted."""
    theirs, ours = _host_args(*stock_fmu), _host_args(*our_fmu)
    commands = [(f"{order} first, {checker} heap, run {run}",
                 [str(pair_host), mode, str(CYCLES), *pair], _checked(host_env, checker, run))
                for order, pair in (("theirs", theirs + ours), ("ours", ours + theirs))
                for checker in CHECKERS for run in range(RUNS_PER_CHECKER)]
    failures = _run_all(commands)
    assert not failures, f"{len(failures)} of {len(commands)} runs failed:\n" + "\n".join(failures)


PYTHON_HOST = textwrap.dedent('''
    import os, sys
    from fmpy import read_model_description
    from fmpy.fmi2 import FMU2Slave

    mode, folders = sys.argv[1], sys.argv[2:]
    libraries = set()
    for cycle in range(CYCLES + 1):
        slaves = []
        for folder in folders:
            md = read_model_description(folder)
            s = FMU2Slave(guid=md.guid, unzipDirectory=folder, instanceName=f"i{cycle}",
                          modelIdentifier=md.coSimulation.modelIdentifier)
            s.instantiate()
            s.setupExperiment(startTime=0.0)
            s.enterInitializationMode()
            s.exitInitializationMode()
            h = md.defaultExperiment.stepSize if md.defaultExperiment else None
            for k in range(3):
                s.doStep(k * float(h or 0.1), float(h or 0.1))
            slaves.append(s)
            libraries.add(md.coSimulation.modelIdentifier + ".so")
        if cycle < CYCLES or mode == "free":
            for s in slaves:
                s.terminate()
                s.freeInstance()
    hooks = [f for f in sys.meta_path if getattr(f, "navfmu_pythonfmu_exit_hooks", False)]
    hooked = {os.path.basename(p.decode()) for p in hooks[0].hooked} if hooks else set()
    if hooked != libraries:
        sys.exit(f"exit hooks registered for {sorted(hooked)}, binaries {sorted(libraries)}")
    print("ok")
''').replace("CYCLES", str(CYCLES))


@pytest.mark.parametrize("order", ["theirs", "ours"])
def test_fmpy_host_hooks_every_pythonfmu_binary_and_exits_cleanly(stock_fmu, our_fmu, order):
    """Both binaries, whichever fmpy loaded first, get their exit hook (the process checks
    the list and ends with status 1 otherwise), and the process exits with status 0 under the
    binned heap check, with the last instances freed and alive."""
    folders = [str(stock_fmu[1]), str(our_fmu[1])]
    if order == "ours":
        folders.reverse()
    env = {**os.environ, "PYTHONPATH": os.environ.get("PYTHONPATH", "")}
    commands = [(f"{mode}", [sys.executable, "-c", PYTHON_HOST, mode, *folders],
                 _checked(env, "binned", 0)) for mode in ("free", "keep")]
    failures = _run_all(commands)
    assert not failures, "\n".join(failures)


@pytest.mark.slow
def test_native_host_with_a_stock_pythonfmu_fmu_under_valgrind(pair_host, host_env,
                                                                stock_fmu, our_fmu, tmp_path):
    """valgrind memcheck finds no access to freed memory and no invalid write or free, ours
    first and instances alive at exit (before the fix: a read of 4 bytes inside the freed
    128-byte PyState block, from the stock binary's finalizePythonInterpreter in _dl_fini).
    About 45 s."""
    valgrind = shutil.which("valgrind")
    if valgrind is None:
        pytest.skip("no valgrind on PATH")
    log = tmp_path / "memcheck.log"
    argv = [valgrind, "--tool=memcheck", f"--log-file={log}", str(pair_host), "keep", "1",
            *_host_args(*our_fmu), *_host_args(*stock_fmu)]
    r = subprocess.run(argv, env={**host_env, "PYTHONMALLOC": "malloc"}, capture_output=True,
                       text=True, timeout=900)
    assert r.returncode == 0, f"{_ended(r)}\n{r.stderr[-2000:]}"
    report = log.read_text()
    bad = re.findall(r"(free'd|unallocated block|Invalid write|Invalid free)", report)
    assert not bad, report[-6000:]
