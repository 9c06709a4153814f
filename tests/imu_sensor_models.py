"""A scenario rewired through ImuSensor: the trajectory's truth drives an ImuSensor with the
trajectory's error parameters and seed, whose IMU outputs replace the trajectory's at the
filter (tests of ImuSensor against TrajectoryImu)."""
from __future__ import annotations

import shutil
import xml.etree.ElementTree as ET
from pathlib import Path

NS = {"ssd": "http://ssp-standard.org/SSP1/SystemStructureDescription",
      "ssc": "http://ssp-standard.org/SSP1/SystemStructureCommon",
      "ssv": "http://ssp-standard.org/SSP1/SystemStructureParameterValues",
      "osp": "http://opensimulationplatform.com/SSP/OSPAnnotations"}
for prefix, uri in NS.items():
    ET.register_namespace(prefix, uri)

TRUTH = ("truth_time", "truth_lat", "truth_lon", "truth_h", "truth_vn", "truth_ve", "truth_vd",
         "truth_roll", "truth_pitch", "truth_yaw")
#: TrajectoryImu parameters ImuSensor does not have
PROFILE_ONLY = ("profile", "extend_profile")


def _q(tag):
    prefix, name = tag.split(":")
    return f"{{{NS[prefix]}}}{name}"


def _connector(parent, name, kind, unit):
    c = ET.SubElement(parent, _q("ssd:Connector"), name=name, kind=kind)
    ET.SubElement(c, _q("ssc:Real"), unit=unit)


def through_imu_sensor(model_dir: Path, target: Path) -> Path:
    """A copy of ``model_dir`` in ``target`` with component ``imu`` (ImuSensor) between the
    component ``trajectory`` and every consumer of its IMU outputs."""
    shutil.copytree(model_dir, target)
    ssd = target / "SystemStructure.ssd"
    tree = ET.parse(ssd)
    system = tree.getroot().find("ssd:System", NS)
    elements = system.find("ssd:Elements", NS)
    trajectory = next(c for c in elements if c.get("name") == "trajectory")
    source = trajectory.get("source").replace("TrajectoryImu.fmu", "ImuSensor.fmu")
    imu = ET.SubElement(elements, _q("ssd:Component"), name="imu",
                        type="application/x-fmu-sharedlibrary", source=source)
    connectors = ET.SubElement(imu, _q("ssd:Connectors"))
    units = {c.get("name"): c[0].get("unit") for c in trajectory.find("ssd:Connectors", NS)}
    connections = system.find("ssd:Connections", NS)
    moved = []
    for conn in connections:
        if conn.get("startElement") == "trajectory" and conn.get("startConnector").startswith(
                ("imu_", "mag_")):
            conn.set("startElement", "imu")
            moved.append(conn.get("startConnector"))
    t_connectors = trajectory.find("ssd:Connectors", NS)
    present = set(units)
    for name in TRUTH:
        unit = "s" if name == "truth_time" else ("m" if name == "truth_h" else (
            "m/s" if name.startswith("truth_v") else "rad"))
        if name not in present:
            _connector(t_connectors, name, "output", unit)
        _connector(connectors, name, "input", unit)
        ET.SubElement(connections, _q("ssd:Connection"), startElement="trajectory",
                      startConnector=name, endElement="imu", endConnector=name)
    for name in dict.fromkeys(moved):
        _connector(connectors, name, "output", units[name])
    ssv_source = trajectory.find("ssd:ParameterBindings/ssd:ParameterBinding", NS).get("source")
    ssv = ET.parse(target / ssv_source)
    params = ssv.getroot().find("ssv:Parameters", NS)
    for p in list(params):
        if p.get("name") in PROFILE_ONLY:
            params.remove(p)
    ssv.write(target / "imu.ssv", xml_declaration=True, encoding="UTF-8")
    bindings = ET.SubElement(imu, _q("ssd:ParameterBindings"))
    ET.SubElement(bindings, _q("ssd:ParameterBinding"), source="imu.ssv")
    hint = trajectory.find("ssd:Annotations", NS)
    if hint is not None:
        imu.append(hint)
    tree.write(ssd, xml_declaration=True, encoding="UTF-8")
    return target
