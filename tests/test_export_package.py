"""navfmu export (one FMU) and package (.ssp), the SSD component type and the FMU search path."""
from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest
from fmpy import simulate_fmu
from fmpy.validation import validate_fmu

from conftest import component_xml, ssd_text
from orchestrator.building import build as fmu_build
from orchestrator.cli.commands import main
from orchestrator.errors import SspError
from orchestrator.packaging.export import export, without_step_hints
from orchestrator.cosim.master import Simulation
from orchestrator.model.fmu_path import FMU_PATH_VARIABLE
from orchestrator.model.ssp import load_ssd
from orchestrator.model.ssp_archive import load_model

MODEL = Path(__file__).resolve().parents[1] / "models" / "aircraft_500s"


@pytest.fixture(scope="module")
def built():
    fmu_build.build(log=None)


def test_exported_fmu_validates_and_reproduces_the_jacobi_master_bit_for_bit(built, tmp_path):
    """The container steps every component at the base step, Jacobi: our master's jacobi
    run of the model without step hints (an independent implementation of the rule)."""
    fmu = export(MODEL, tmp_path / "system.fmu")
    assert validate_fmu(str(fmu)) == []
    stop = 3.0
    got = simulate_fmu(str(fmu), stop_time=stop, step_size=0.01, output_interval=0.01)
    ours = Simulation(without_step_hints(load_model(MODEL)), algorithm="jacobi").run(stop)
    assert len(got) == len(ours.time)
    for c in ours.components:
        for j, v in enumerate(ours.columns[c]):
            np.testing.assert_array_equal(got[f"{c}.{v}"].astype(float), ours.data[c][:, j],
                                          err_msg=f"{c}.{v}")
    assert got["gnss.gnss_epoch"][-1] == 2 and got["filter.updated"].sum() == 2


def test_copied_model_folder_finds_its_fmus(built, tmp_path, monkeypatch):
    copied = tmp_path / "elsewhere" / "aircraft_500s"
    shutil.copytree(MODEL, copied)
    model = load_model(copied)
    assert all(c.source.parent == fmu_build.DIST.resolve() for c in model.components)
    # NAVFMU_FMU_PATH comes before the installed fmus/dist
    own = tmp_path / "my_fmus"
    own.mkdir()
    shutil.copy(fmu_build.DIST / "Kf.fmu", own / "Kf.fmu")
    monkeypatch.setenv(FMU_PATH_VARIABLE, str(own))
    assert load_model(copied).component("filter").source == (own / "Kf.fmu").resolve()
    res = Simulation(load_model(copied)).run(1.0)
    assert res.column("filter", "nav_time")[-1] == pytest.approx(1.0)


def test_component_type_other_than_fmu_is_refused(write_ssd):
    comp = component_xml("a", "A.fmu", [("y", "output", "Real")]).replace(
        "<ssd:Component ", '<ssd:Component type="application/x-ssp-package" ', 1)
    with pytest.raises(SspError, match='type="application/x-ssp-package" is not supported'):
        load_ssd(write_ssd(ssd_text(comp)))


@pytest.mark.parametrize("command,out", [("package", "x.zip"), ("export", "x.ssp")])
def test_cli_refuses_a_wrong_extension(built, command, out, tmp_path, capsys):
    with pytest.raises(SystemExit) as exit_:
        main([command, str(MODEL), "--out", str(tmp_path / out)])
    assert exit_.value.code == 2
    assert capsys.readouterr().err.startswith("navfmu: error: --out")


def test_archive_beyond_its_bounds_or_escaping_is_refused(tmp_path, monkeypatch):
    import zipfile

    from orchestrator.model import ssp_archive

    big = tmp_path / "big.ssp"
    with zipfile.ZipFile(big, "w") as zf:
        zf.writestr("SystemStructure.ssd", "x" * 2000)
    monkeypatch.setattr(ssp_archive, "MAX_ARCHIVE_BYTES", 1000)
    with pytest.raises(SspError, match="2000 bytes uncompressed, more than the 1000"):
        load_model(big)
    escaping = tmp_path / "escaping.ssp"
    with zipfile.ZipFile(escaping, "w") as zf:
        zf.writestr("../outside.ssd", "x")
    with pytest.raises(SspError, match="lies outside the archive"):
        load_model(escaping)
    assert not (tmp_path / "outside.ssd").exists()
