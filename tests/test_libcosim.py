"""libcosim (an independent master) against our master's Jacobi exchange on every model."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from orchestrator.building import build as fmu_build
from orchestrator.running import scenarios
from orchestrator.cosim.master import Simulation

pytest.importorskip("libcosimpy", reason="libcosimpy (the test extra) is not installed")
from orchestrator.cosim.libcosim_run import run_libcosim  # noqa: E402

MODELS = sorted(p for p in (Path(__file__).resolve().parents[1] / "models").iterdir()
                if (p / "SystemStructure.ssd").is_file())
PAPER_MODELS = [p for p in MODELS if (p / "paper.json").is_file()]
#: the stated window of the default run: 12 receiver periods, 600-1200 base steps
WINDOW_S = 12.0


@pytest.fixture(scope="module")
def built():
    fmu_build.build(log=None)


def assert_same_recording(a, b):
    """Every recorded output equal bit for bit (libcosim's unobservable row-0 Booleans aside)."""
    assert a.components == b.components
    np.testing.assert_array_equal(a.time, b.time)
    unobserved = set(a.metadata.get("unobserved_at_start", ()))
    for c in a.components:
        assert a.columns[c] == b.columns[c] and a.units[c] == b.units[c]
        for j, v in enumerate(a.columns[c]):
            first = 1 if f"{c}.{v}" in unobserved else 0
            np.testing.assert_array_equal(a.data[c][first:, j], b.data[c][first:, j],
                                          err_msg=f"{c}.{v}")


@pytest.mark.parametrize("model_dir", MODELS, ids=[p.name for p in MODELS])
def test_libcosim_equals_our_jacobi_master_bit_for_bit(built, model_dir, capfd):
    ours = Simulation(scenarios.load_scenario(model_dir), algorithm="jacobi").run(WINDOW_S)
    capfd.readouterr()
    theirs = run_libcosim(model_dir, WINDOW_S)
    out, err = capfd.readouterr()
    assert out == "" and err == "", "libcosim logged at WARNING level or above"
    assert_same_recording(theirs, ours)
    # the comparison has teeth: fixes are published (an attitude filter updates), the
    # filter moves
    source = next((c for c in theirs.components if theirs.has(c, "gnss_epoch")), None)
    if source is not None:
        assert theirs.column(source, "gnss_epoch")[-1] >= WINDOW_S - 2
        assert np.ptp(theirs.column("filter", "nav_lat")) > 0
    else:
        assert np.nansum(theirs.column("filter", "updated")) >= WINDOW_S
        assert np.ptp(theirs.column("filter", "nav_pitch")) > 0


def test_gauss_seidel_differs_from_libcosim_where_the_rules_differ(built):
    """Sanity of the test above: the default order gives other numbers (the filter sees this
    step's IMU increments instead of the previous step's)."""
    model = scenarios.load_scenario(PAPER_MODELS[0])
    gs = Simulation(model).run(2.0)
    jac = Simulation(model, algorithm="jacobi").run(2.0)
    assert not np.array_equal(gs.column("filter", "nav_time"), jac.column("filter", "nav_time"))
    np.testing.assert_allclose(jac.column("filter", "nav_time")[2:],
                               gs.column("filter", "nav_time")[1:-1])


@pytest.mark.parametrize("model_dir", [PAPER_MODELS[0]] + [p for p in MODELS
                                                         if (p / "log").is_dir()][:1],
                         ids=lambda p: p.name)
def test_a_packaged_archive_runs_in_libcosim_with_the_folders_numbers(built, model_dir,
                                                                      tmp_path):
    from orchestrator.packaging.package import package

    archive = package(model_dir, tmp_path / "scenario.ssp")
    folder = run_libcosim(model_dir, 3.0)
    assert_same_recording(run_libcosim(archive, 3.0), folder)
    assert_same_recording(folder, Simulation(scenarios.load_scenario(archive),
                                             algorithm="jacobi").run(3.0))


@pytest.mark.slow
@pytest.mark.parametrize("model_dir", PAPER_MODELS, ids=[p.name for p in PAPER_MODELS])
def test_paper_scenarios_full_length_in_libcosim(built, model_dir):
    """Full length: libcosim's RMS per axis within 5 % of our default master's, every fix
    applied (needs filters that apply a fix at gnss_time within a latency bound)."""
    from orchestrator.results import metrics

    theirs = run_libcosim(model_dir)
    ours = Simulation(scenarios.load_scenario(model_dir)).run()
    m_theirs = metrics.filter_metrics(theirs, "filter")
    m_ours = metrics.filter_metrics(ours, "filter")
    for key in ("position_rms_m", "velocity_rms_mps", "attitude_rms_deg"):
        for axis, value in m_ours.get(key, {}).items():
            assert m_theirs[key][axis] == pytest.approx(value, rel=0.05), (key, axis)
    if "gnss" not in theirs.components:     # an attitude-only model: no fixes to count
        return
    # the valid fixes that reached the filter before its last step (a fix published at the
    # stop time has no step left to be applied in)
    epoch = theirs.column("gnss", "gnss_epoch")[:-1]
    valid = theirs.column("gnss", "gnss_valid")[:-1] > 0.5
    reached = int(np.sum(np.r_[False, np.diff(epoch) > 0] & valid))
    applied = int(np.nansum(theirs.column("filter", "updated")))
    assert reached > 0.9 * (theirs.time[-1] - theirs.time[0])
    assert applied == reached


def test_a_packaged_replay_runs_in_libcosim_from_any_working_directory(built, tmp_path):
    """The replay's log travels inside its FMU copy in the archive and is found through the
    FMU's resource location: libcosim started in an empty folder elsewhere records the model
    folder's numbers bit for bit (before, the relative ``log`` was looked up in the process's
    working directory and the run failed unless started in the model folder)."""
    import subprocess
    import sys
    import textwrap

    from orchestrator.packaging.package import package

    model_dir = next(p for p in MODELS if (p / "log").is_dir())
    archive = package(model_dir, tmp_path / "packed" / "replay.ssp")
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    out = tmp_path / "recording.npz"
    code = textwrap.dedent(f"""
        import numpy as np
        from orchestrator.cosim.libcosim_run import run_libcosim
        r = run_libcosim({str(archive)!r}, 3.0)
        np.savez({str(out)!r}, time=r.time, **{{c: r.data[c] for c in r.components}})
    """)
    proc = subprocess.run([sys.executable, "-c", code], cwd=elsewhere, capture_output=True,
                          text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert list(elsewhere.iterdir()) == []
    folder = run_libcosim(model_dir, 3.0)
    got = np.load(out)
    np.testing.assert_array_equal(got["time"], folder.time)
    for c in folder.components:
        np.testing.assert_array_equal(got[c], folder.data[c], err_msg=c)
    assert np.ptp(folder.column("filter", "nav_lat")) > 0
