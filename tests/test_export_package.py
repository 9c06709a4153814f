"""navfmu export (one FMU) and package (.ssp), the SSD component type and the FMU search path."""
from __future__ import annotations

import shutil
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

import numpy as np
import pytest
from fmpy import read_model_description, simulate_fmu
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


def export_equals_jacobi(model, tmp_path, stop, step):
    """Export ``model`` as one FMU, check it validates, simulate it with fmpy and assert every
    output bit for bit equal to our master's Jacobi run of the model without step hints;
    returns fmpy's result."""
    fmu = export(model, tmp_path / "system.fmu")
    assert validate_fmu(str(fmu)) == []
    got = simulate_fmu(str(fmu), stop_time=stop, step_size=step, output_interval=step)
    ours = Simulation(without_step_hints(load_model(model)), algorithm="jacobi").run(stop)
    assert len(got) == len(ours.time)
    for c in ours.components:
        for j, v in enumerate(ours.columns[c]):
            np.testing.assert_array_equal(got[f"{c}.{v}"].astype(float), ours.data[c][:, j],
                                          err_msg=f"{c}.{v}")
    return got


@pytest.fixture(scope="module")
def built():
    fmu_build.build(log=None)


def test_exported_fmu_validates_and_reproduces_the_jacobi_master_bit_for_bit(built, tmp_path):
    """The container steps every component at the base step, Jacobi: our master's jacobi
    run of the model without step hints (an independent implementation of the rule)."""
    got = export_equals_jacobi(MODEL, tmp_path, stop=3.0, step=0.01)
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


def test_packaged_fmu_copies_start_with_the_scenarios_values(built, tmp_path):
    """Every bound parameter (the .ssd's and the .ssv's, Strings included) is the start value
    of the component's FMU copy in the archive, and the FMU starts from it with no parameter
    set by the host (as in OMSimulator, which applies no .ssv String, or fmpy's SSP runner,
    which applies no binding)."""
    import zipfile

    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave

    from orchestrator.packaging.package import package

    archive = package(MODEL, tmp_path / "aircraft_500s.ssp")
    model = load_model(MODEL)
    packed = load_model(archive)
    strings_checked = 0
    for spec in model.components:
        fmu = packed.component(spec.name).source
        assert validate_fmu(str(fmu)) == [], spec.name
        md = read_model_description(str(fmu))
        step = spec.step_hint if spec.step_hint is not None else model.base_step
        assert [float(x) for x in (md.defaultExperiment.startTime, md.defaultExperiment.stopTime,
                                   md.defaultExperiment.stepSize)] == [0.0, 500.0, step]
        starts = {v.name: v for v in md.modelVariables if v.causality == "parameter"}
        assert spec.parameters, spec.name
        for name, (type_name, value) in spec.parameters.items():
            text = starts[name].start
            parsed = {"Real": float, "Integer": int, "String": str,
                      "Boolean": lambda t: t == "true"}[type_name](text)
            assert parsed == value and type(parsed) is type(value), (spec.name, name)
        strings = [(n, v) for n, (t, v) in spec.parameters.items() if t == "String"]
        if not strings:
            continue
        slave = FMU2Slave(guid=md.guid, unzipDirectory=extract(str(fmu)),
                          modelIdentifier=md.coSimulation.modelIdentifier, instanceName="bare")
        slave.instantiate()
        slave.setupExperiment(startTime=0.0)
        slave.enterInitializationMode()
        slave.exitInitializationMode()
        got = slave.getString([starts[n].valueReference for n, _ in strings])
        assert [g.decode() if isinstance(g, bytes) else g for g in got] == \
            [v for _, v in strings], spec.name
        strings_checked += len(strings)
        slave.terminate()
        slave.freeInstance()
    assert strings_checked >= 2   # the receiver's noise steps and outlier patches
    with zipfile.ZipFile(fmu_build.DIST / "GnssReceiver.fmu") as z:
        original = z.read("modelDescription.xml")
    assert b'name="noise_steps"' in original and b'<String start=""' in original


def test_exported_fmu_claims_only_its_platforms_and_reports_errors_with_logging_off(built,
                                                                                    tmp_path):
    """No binaries/darwin64 (its components carry no macOS binary), no stray Container.zip,
    and a refused parameter reaches the host's logger with loggingOn false."""
    import zipfile

    fmu = export(MODEL, tmp_path / "system.fmu")
    with zipfile.ZipFile(fmu) as z:
        names = z.namelist()
    platforms = {n.split("/")[1] for n in names if n.startswith("binaries/") and n.count("/") > 1
                 and not n.endswith("/")}
    assert "Container.zip" not in names
    assert platforms == {"linux64", "win64"}
    for component in ("trajectory", "gnss", "filter"):
        assert any(n.startswith(f"resources/{component}/binaries/win64/") for n in names)
    messages = []
    with pytest.raises(Exception, match="fmi2ExitInitializationMode"):
        simulate_fmu(str(fmu), stop_time=0.1, step_size=0.01, debug_logging=False,
                     start_values={"gnss.fix_interval": -1.0},
                     logger=lambda c, name, status, cat, msg: messages.append((status, msg)))
    assert [s for s, m in messages if b"'fix_interval' = -1.0" in m] == [3]


@pytest.mark.parametrize("step_hints", [True, False])
def test_archive_holds_no_string_value_and_step_hints_only_when_asked(built, tmp_path,
                                                                      step_hints):
    from orchestrator.model.ssp_archive import load_model
    from orchestrator.packaging.package import package

    folder = Path(__file__).parents[1] / "models" / "aircraft_500s"
    archive = package(folder, tmp_path / "a.ssp", step_hints=step_hints)
    with zipfile.ZipFile(archive) as z:
        texts = {n: z.read(n).decode() for n in z.namelist() if n.endswith((".ssd", ".ssv"))}
    for name, text in texts.items():
        root = ET.fromstring(text)   # still well-formed
        assert not [e for e in root.iter() if e.tag.endswith("}String")], name
    ssd = ET.fromstring(texts["SystemStructure.ssd"])
    hints = [e for e in ssd.iter() if e.tag.endswith("}StepSizeHint")]
    assert len(hints) == (1 if step_hints else 0)
    model, original = load_model(archive), load_model(folder)
    assert {c.name: c.step_hint for c in model.components} == (
        {c.name: c.step_hint for c in original.components} if step_hints
        else {c.name: None for c in original.components})
    # the Strings the folder binds are the FMU copies' start values
    strings = {(c.name, n): v for c in original.components
               for n, (t, v) in c.parameters.items() if t == "String"}
    assert strings
    for (component, name), value in strings.items():
        spec = next(c for c in model.components if c.name == component)
        start = {v.name: v.start for v in read_model_description(str(spec.source)).modelVariables}
        assert start[name] == value


def _oms_master(text):
    """The System's Annotations children and OMSimulator's FixedStepMaster element."""
    from orchestrator.packaging.oms_annotation import OMS_ANNOTATION_TYPE, OMS_NS

    ssd_ns = "http://ssp-standard.org/SSP1/SystemStructureDescription"
    system = ET.fromstring(text).find(f"{{{ssd_ns}}}System")
    annotations = list(system)[-1]
    assert annotations.tag.endswith("}Annotations")
    first = list(annotations)[0]
    assert first.get("type") == OMS_ANNOTATION_TYPE
    master = first.find(f"{{{OMS_NS}}}Annotations/{{{OMS_NS}}}SimulationInformation/"
                        f"{{{OMS_NS}}}FixedStepMaster")
    return list(annotations), master


def test_archive_system_names_omsimulators_fixed_step_master(built, tmp_path):
    """OMSimulator takes a System's kind from this annotation and imports no System without."""
    from orchestrator.packaging.package import package

    folder = Path(__file__).parents[1] / "models" / "uav_mission"
    archive = package(folder, tmp_path / "a.ssp", step_hints=False)
    with zipfile.ZipFile(archive) as z:
        text = z.read("SystemStructure.ssd").decode()
    children, master = _oms_master(text)
    assert len(children) == 1
    assert master.get("description") == "oms-ma"
    assert float(master.get("stepSize")) == load_model(folder).base_step == 0.02
    # other readers skip it: our loader reads the archive as the folder
    assert load_model(archive).base_step == load_model(folder).base_step


def test_oms_annotation_goes_first_into_a_systems_own_annotations_once():
    from orchestrator.packaging.oms_annotation import with_oms_system_annotation

    text = ssd_text(component_xml("a", "../../fmus/dist/Kf.fmu")).replace(
        "</ssd:System>", '<ssd:Annotations><ssc:Annotation type="com.example"/>'
                         "</ssd:Annotations></ssd:System>", 1)
    once = with_oms_system_annotation(text, 0.05)
    children, master = _oms_master(once)
    assert [c.get("type") for c in children] == ["org.openmodelica", "com.example"]
    assert float(master.get("stepSize")) == 0.05
    assert with_oms_system_annotation(once, 0.05) == once
    assert once.count("xmlns:oms=") == 1
