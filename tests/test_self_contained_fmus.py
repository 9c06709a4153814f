"""The FMU given is the code that runs: any number of navfmu FMUs, two builds of one FMU, a
changed copy and a user's own pythonfmu FMU with a package named ``navcore`` share one Python
process, each running its own code (``orchestrator.building.private_names``,
``fmushell.private_paths``).

Each case runs in a fresh interpreter, as a user's script would (the test process has the
installed navcore imported already), and fmpy deletes each FMU's unpacked folder when its
simulation ends, so a later FMU cannot lean on an earlier one's folder.
"""
from __future__ import annotations

import json
import shutil
import subprocess
import sys
import textwrap
import zipfile
from pathlib import Path

import numpy as np
import pytest

from orchestrator.building import build as fmu_build
from orchestrator.building import private_names

ROOT = Path(__file__).resolve().parents[1]
REPLAY_LOG = ROOT / "models" / "replay_gnss_ins_sim" / "log"
#: what a changed copy of Kf adds to its height output (m)
ADDED_HEIGHT = 1000.0
CHANGE = textwrap.dedent(f"""

    _navfmu_test_advance = Kf.advance


    def _advance_higher(self, t, h, inputs):
        outputs = dict(_navfmu_test_advance(self, t, h, inputs))
        outputs["nav_h"] = outputs["nav_h"] + {ADDED_HEIGHT!r}
        return outputs


    Kf.advance = _advance_higher
    """)


@pytest.fixture(scope="module")
def dist():
    fmu_build.build(log=None)
    return fmu_build.DIST


def run_script(code: str, cwd: Path, prelude: str = "", timeout: float = 300) -> dict:
    """Run ``prelude`` then ``code`` in a fresh interpreter; the script prints one JSON line
    last, which is returned."""
    script = textwrap.dedent(prelude) + "\n" + textwrap.dedent(code)
    proc = subprocess.run([sys.executable, "-c", script], cwd=str(cwd),
                          capture_output=True, text=True, timeout=timeout)
    assert proc.returncode == 0, proc.stderr[-3000:]
    return json.loads(proc.stdout.strip().splitlines()[-1])


def changed_copy(original: Path, target: Path, change: str = CHANGE) -> Path:
    """A copy of the FMU ``original`` whose bundled ``kf_components.py`` has ``change``
    appended (its build file and names untouched: a user's edit of the archive)."""
    with zipfile.ZipFile(original) as src, zipfile.ZipFile(target, "w") as dst:
        for info in src.infolist():
            data = src.read(info)
            if info.filename.endswith("/components/kf_components.py"):
                data += change.encode()
            dst.writestr(info, data)
    return target


SIMULATE = """
import json, shutil, sys
from fmpy import extract, simulate_fmu

def height(path, **kwargs):
    folder = extract(path)
    try:
        result = simulate_fmu(folder, stop_time=1.0, output=["nav_h"], **kwargs)
        return float(result["nav_h"][-1])
    finally:
        shutil.rmtree(folder)
"""


def test_every_fmu_one_after_another_in_one_process(dist, tmp_path):
    """Every FMU of fmus/dist simulated in turn with fmpy's simulate_fmu in one process, each
    folder deleted before the next (an FMU imports modules its predecessors did not)."""
    names = [p.stem for p in sorted(dist.glob("*.fmu"))]
    got = run_script(f"""
        import json, shutil
        from fmpy import extract, simulate_fmu
        done = {{}}
        for name in {names!r}:
            path = {str(dist)!r} + "/" + name + ".fmu"
            folder = extract(path)
            start = {{"log": {str(REPLAY_LOG)!r}}} if name == "ImuGnssReplay" else {{}}
            if name == "GuidedUav":       # it flies on a navigation solution near its route
                start = {{"guide_on_truth": True}}
            try:
                result = simulate_fmu(folder, stop_time=0.5, start_values=start)
                done[name] = len(result)
            except Exception as exc:
                done[name] = str(exc)
            shutil.rmtree(folder)
        print(json.dumps(done))
        """, cwd=tmp_path)
    assert set(got) == set(names)
    failed = {n: v for n, v in got.items() if not isinstance(v, int)}
    assert failed == {}
    assert all(rows >= 2 for rows in got.values())


def _build_changed_kf(tmp_path: Path) -> Path:
    """Kf built from a copy of fmus/ whose kf_components.py differs by CHANGE."""
    sources = tmp_path / "fmus"
    sources.mkdir()
    shutil.copy(fmu_build.FMU_SOURCES / "Kf.py", sources / "Kf.py")
    for package in (fmu_build.SHELL, fmu_build.LIBRARY):
        shutil.copytree(fmu_build.FMU_SOURCES / package, sources / package,
                        ignore=shutil.ignore_patterns("__pycache__"))
    module = sources / fmu_build.LIBRARY / "components" / "kf_components.py"
    module.write_text(module.read_text() + CHANGE)
    # in a fresh interpreter: an FMU that ran in this one may have put its own pythonfmu
    # (no builder binaries) first on the path (build.builder_usable)
    built = run_script(f"""
        import json
        from pathlib import Path
        from orchestrator.building import build
        print(json.dumps(str(build.build_one(Path({str(sources / 'Kf.py')!r}),
              Path({str(tmp_path / 'dist')!r}), build.patched_library(log=None)))))
        """, cwd=tmp_path)
    return Path(built)


def test_two_builds_of_kf_run_their_own_code_side_by_side(dist, tmp_path):
    other = _build_changed_kf(tmp_path)
    ours = private_names.read_build(dist / "Kf.fmu")
    theirs = private_names.read_build(other)
    assert ours["packages"]["navcore"] != theirs["packages"]["navcore"]
    assert ours["module"] != theirs["module"]
    got = run_script(prelude=SIMULATE, code=f"""
        a, b = {str(dist / 'Kf.fmu')!r}, {str(other)!r}
        print(json.dumps([height(a), height(b), height(b), height(a)]))
        """, cwd=tmp_path)
    alone = run_script(prelude=SIMULATE, cwd=tmp_path,
                       code=f"print(json.dumps([height({str(dist / 'Kf.fmu')!r})]))")
    assert got[0] == got[3] == alone[0]
    assert got[1] == got[2] == alone[0] + ADDED_HEIGHT


def test_a_changed_copy_runs_alone_and_is_refused_beside_its_original(dist, tmp_path):
    """A copy edited after its build keeps its build's names: alone it runs its own code; in
    a process that loaded the original it is refused with a message saying why, instead of
    running the original's code."""
    copy = changed_copy(dist / "Kf.fmu", tmp_path / "KfCopy.fmu")
    assert private_names.archive_changed_since_build(copy)
    assert not private_names.archive_changed_since_build(dist / "Kf.fmu")
    alone = run_script(prelude=SIMULATE, code=f"""
        print(json.dumps([height({str(dist / 'Kf.fmu')!r}), 0.0]))
        """, cwd=tmp_path)
    copy_alone = run_script(prelude=SIMULATE, cwd=tmp_path,
                            code=f"print(json.dumps([height({str(copy)!r})]))")
    assert copy_alone[0] == alone[0] + ADDED_HEIGHT
    got = run_script(prelude=SIMULATE, code=f"""
        messages = []
        def logger(*args):
            messages.append(args[-1].decode() if isinstance(args[-1], bytes) else str(args[-1]))
        height({str(dist / 'Kf.fmu')!r})
        try:
            height({str(copy)!r}, logger=logger)
            outcome = "ran"
        except Exception as exc:
            outcome = str(exc)
        print(json.dumps([outcome, messages]))
        """, cwd=tmp_path)
    assert got[0] != "ran"
    assert any("changed after it was built" in m for m in got[1]), got[1]


def test_our_master_runs_a_changed_copy_s_own_code_beside_the_original(dist, tmp_path):
    """The master gives a changed copy names of its own: Kf and the copy in one process (not
    hosted apart, as the copy would be by default), each its own numbers; the results say
    which build ran and that the copy was changed."""
    from orchestrator.cosim.isolation import Isolation
    from orchestrator.cosim.master import Simulation
    from orchestrator.model.ssp import load_ssd

    copy = changed_copy(dist / "Kf.fmu", tmp_path / "KfCopy.fmu")
    model = load_ssd(ROOT / "models" / "aircraft_500s" / "SystemStructure.ssd")
    runs = {}
    for label, fmu in (("original", dist / "Kf.fmu"), ("copy", copy),
                       ("original again", dist / "Kf.fmu")):
        results = Simulation(model.replace_source("filter", fmu),
                             isolation=Isolation("never")).run(stop_time=3.0)
        runs[label] = results
    h = {k: np.asarray(r.column("filter", "nav_h")) for k, r in runs.items()}
    np.testing.assert_array_equal(h["original"], h["original again"])
    np.testing.assert_array_equal(h["copy"][1:], h["original"][1:] + ADDED_HEIGHT)
    build = runs["copy"].metadata["builds"]["filter"]
    assert build["changed_after_build"] is True
    assert build["fmu"] == str(copy)
    assert runs["original"].metadata["builds"]["filter"]["changed_after_build"] is False
    assert (runs["original"].metadata["builds"]["filter"]["navfmu_build"]
            == private_names.read_build(dist / "Kf.fmu")["build"])


def test_a_user_fmu_with_a_package_named_navcore_beside_ours(dist, tmp_path):
    """A user's own pythonfmu FMU (pythonfmu's stock library) shipping a package called
    ``navcore`` runs beside ours, before and after, each with its own code."""
    src = tmp_path / "user"
    (src / "navcore").mkdir(parents=True)
    (src / "navcore" / "__init__.py").write_text("ANSWER = 42.0\n")
    (src / "UserModel.py").write_text(textwrap.dedent("""
        from pythonfmu import Fmi2Causality, Fmi2Slave, Real
        from navcore import ANSWER


        class UserModel(Fmi2Slave):
            def __init__(self, **kwargs):
                super().__init__(**kwargs)
                self.answer = 0.0
                self.register_variable(Real("answer", causality=Fmi2Causality.output))

            def do_step(self, current_time, step_size):
                self.answer = ANSWER
                return True
        """))
    # built in a fresh interpreter: pythonfmu's builder imports the script, and this one
    # has navfmu's navcore imported already
    built = run_script(f"""
        import json
        from pythonfmu.builder import FmuBuilder
        print(json.dumps(str(FmuBuilder.build_FMU({str(src / 'UserModel.py')!r},
              dest={str(tmp_path)!r}, project_files=[{str(src / 'navcore')!r}]))))
        """, cwd=tmp_path)
    user = Path(built)
    got = run_script(prelude=SIMULATE, code=f"""
        def answer(path):
            folder = extract(path)
            try:
                return float(simulate_fmu(folder, stop_time=1.0)["answer"][-1])
            finally:
                shutil.rmtree(folder)
        kf = {str(dist / 'Kf.fmu')!r}
        print(json.dumps([answer({str(user)!r}), height(kf), answer({str(user)!r}),
                          height(kf)]))
        """, cwd=tmp_path)
    alone = run_script(prelude=SIMULATE, cwd=tmp_path,
                       code=f"print(json.dumps([height({str(dist / 'Kf.fmu')!r})]))")
    assert got[0] == got[2] == 42.0
    assert got[1] == got[3] == alone[0]


def test_fmpy_simulate_ssp_runs_two_models_in_one_process(dist, tmp_path):
    from orchestrator.packaging.package import package

    archives = [package(ROOT / "models" / name, tmp_path / f"{name}.ssp")
                for name in ("aircraft_500s", "ahrs_turntable")]
    got = run_script(f"""
        import json
        from fmpy.ssp.simulation import simulate_ssp
        rows = [len(simulate_ssp(a, stop_time=1.0, step_size=0.01))
                for a in {[str(a) for a in archives]!r}]
        print(json.dumps(rows))
        """, cwd=tmp_path)
    # fmpy records a row per step of 0.01 s (and one more when its accumulated time falls
    # short of the stop time)
    assert all(r in (100, 101) for r in got), got


def test_navfmu_compare_runs_a_changed_copy_beside_the_original(dist, tmp_path, navfmu_cli):
    """``navfmu compare --filters Kf,<a copy whose code adds 1000 m to its height>``: two
    rows, the copy's height error 1000 m larger (the copy's own code ran)."""
    copy = changed_copy(dist / "Kf.fmu", tmp_path / "KfHigher.fmu")
    status, out, err = navfmu_cli("compare", ROOT / "models" / "aircraft_500s", "--filters",
                                  f"Kf,{copy}", "--stop", "3", "--no-plots",
                                  "--out", tmp_path / "out")
    assert status == 0, err
    metrics = json.loads((tmp_path / "out" / "metrics.json").read_text())
    builds = {label: run["metadata"]["builds"]["filter"] for label, run in metrics.items()}
    assert builds["Kf"]["changed_after_build"] is False
    assert builds["KfHigher"]["changed_after_build"] is True
    h = {label: np.loadtxt(tmp_path / "out" / f"results_{label}.csv", delimiter=",",
                           skiprows=1, usecols=_column(tmp_path / "out" /
                                                       f"results_{label}.csv", "filter.nav_h"))
         for label in ("Kf", "KfHigher")}
    np.testing.assert_allclose(h["KfHigher"][1:] - h["Kf"][1:], ADDED_HEIGHT, rtol=0,
                               atol=1e-6)


def _column(csv: Path, name: str) -> int:
    header = csv.read_text().split("\n", 1)[0].split(",")
    return next(i for i, h in enumerate(header) if h.split(" [")[0] == name)


def test_verify_checks_a_changed_copy_s_own_code(dist, tmp_path):
    """verify's FMI checks on a copy whose code raises when imported fail (they ran the
    copy, not the installed navcore nor the unchanged Kf)."""
    from orchestrator.verification import roles
    from orchestrator.verification.fmi_checks import run_fmi_checks
    from orchestrator.verification.setting import make_setting

    copy = changed_copy(dist / "Kf.fmu", tmp_path / "KfRaises.fmu",
                        change="\nraise RuntimeError('this copy refuses to load')\n")
    facts = roles.read_fmu(copy)
    checks = {c.id: c for c in run_fmi_checks(make_setting(facts, roles.detect_role(facts),
                                                          (), None))}
    assert checks["fmi.state"].verdict == "fail"
    assert checks["fmi.validate"].verdict == "pass"


def test_the_kernel_cache_knows_a_module_of_its_package_in_another_folder(tmp_path):
    """The FMUs of one build share their packages, and a module may be imported from the
    second FMU's folder: the compiled-kernel cache must still take it as its own (else it
    compiled every kernel of that module at every run), but never a changed copy."""
    from navcore.core import kernels

    own = kernels._PACKAGE / "ins" / "mrp.py"
    copy = tmp_path / "unpacked" / kernels._PACKAGE.name / "ins" / "mrp.py"
    copy.parent.mkdir(parents=True)
    copy.write_bytes(own.read_bytes())
    assert kernels._in_package(copy) == Path("ins/mrp.py")
    copy.write_bytes(own.read_bytes() + b"# changed\n")
    assert kernels._in_package(copy) is None
    assert kernels._in_package(tmp_path / "elsewhere" / "mrp.py") is None
