"""Loading SystemStructure.ssd: the supported subset and one clear error per problem."""
from __future__ import annotations

import pytest

from conftest import component_xml, connection_xml, ssd_text
from orchestrator.errors import SspError, WiringError
from orchestrator.model.ssp import Connection, load_ssd

SRC = component_xml("src", "fmus/Ramp.fmu",
                    [("y", "output", "Real", "m"), ("n", "output", "Integer"),
                     ("slope", "parameter", "Real", "m/s")],
                    parameters={"slope": ("Real", 2.5), "count": ("Integer", 3),
                                "on": ("Boolean", "true"), "label": ("String", "abc")})
DST = component_xml("dst", "../Gain.fmu",
                    [("u", "input", "Real", "m"), ("k", "parameter", "Real"),
                     ("m", "input", "Integer")],
                    step_hint=0.5)
WIRES = connection_xml("src.y", "dst.u") + "\n" + connection_xml("src.n", "dst.m")


def test_happy_path_inline_and_ssv(write_ssd):
    ssd = write_ssd(ssd_text(SRC + "\n" + DST.replace(
        "</ssd:Connectors>",
        "</ssd:Connectors><ssd:ParameterBindings>"
        "<ssd:ParameterBinding source=\"gain.ssv\"/></ssd:ParameterBindings>"),
        WIRES, base_step=0.125, start=1.0, stop=11.0))
    (ssd.parent / "gain.ssv").write_text(
        '<?xml version="1.0"?>\n<ssv:ParameterSet version="1.0" name="gain" '
        'xmlns:ssv="http://ssp-standard.org/SSP1/SystemStructureParameterValues">'
        '<ssv:Parameters><ssv:Parameter name="k"><ssv:Real value="-4e-1"/></ssv:Parameter>'
        '</ssv:Parameters></ssv:ParameterSet>')
    model = load_ssd(ssd.parent)  # the folder works as well as the file
    assert model.path == ssd.resolve()
    assert (model.name, model.base_step, model.start_time, model.stop_time) == (
        "toy",
        0.125,
        1.0,
        11.0,
    )
    src, dst = model.components
    assert src.name == "src" and src.source == (ssd.parent / "fmus/Ramp.fmu").resolve()
    assert dst.source == (ssd.parent.parent / "Gain.fmu").resolve()
    assert src.connectors == {"y": ("output", "Real"), "n": ("output", "Integer"),
                              "slope": ("parameter", "Real")}
    assert src.units == {"y": "m", "slope": "m/s"}
    assert src.parameters == {"slope": ("Real", 2.5), "count": ("Integer", 3),
                              "on": ("Boolean", True), "label": ("String", "abc")}
    assert dst.parameters == {"k": ("Real", -0.4)}
    assert src.step_hint is None and dst.step_hint == 0.5
    assert model.connections == [
        Connection("src", "y", "dst", "u"),
        Connection("src", "n", "dst", "m"),
    ]


def test_replace_source_returns_a_copy(write_ssd, tmp_path):
    model = load_ssd(write_ssd(ssd_text(SRC + DST, WIRES)))
    swapped = model.replace_source("dst", tmp_path / "Other.fmu")
    assert swapped.components[1].source == (tmp_path / "Other.fmu").resolve()
    assert model.components[1].source.name == "Gain.fmu"
    assert swapped.replaced_sources == {"dst": model.components[1].source}
    with pytest.raises(WiringError, match="no component named 'nope'"):
        model.replace_source("nope", "x.fmu")


def _error(write_ssd, text, *fragments, extra_files=None):
    ssd = write_ssd(text)
    for name, content in (extra_files or {}).items():
        (ssd.parent / name).write_text(content)
    with pytest.raises(SspError) as info:
        load_ssd(ssd)
    message = str(info.value)
    assert message.startswith(str(ssd.resolve())), message
    for f in fragments:
        assert f in message, message
    return message


def test_malformed_xml_names_line_and_column(write_ssd):
    text = ssd_text(SRC + DST, WIRES).replace('<ssd:Elements>', '<ssd:Elements><oops', 1)
    _error(write_ssd, text, "malformed XML", "line 9, column 0")


def test_wrong_prefix_is_rejected(write_ssd):
    text = (
        ssd_text(SRC + DST, WIRES).replace("xmlns:ssc=", "xmlns:common=").replace("ssc:", "common:")
    )
    _error(write_ssd, text, "literal prefix 'ssc:'")


@pytest.mark.parametrize("mutate, fragments", [
    (lambda t: t.replace('name="src" source="fmus/Ramp.fmu"', 'name="src"'),
     ['<ssd:Component name="src">', "'source'"]),
    (lambda t: t.replace('startElement="src" startConnector="y"', 'startElement="src"'),
     ["<ssd:Connection>", "'startConnector'"]),
    (lambda t: t.replace('<ssd:Connector name="u" kind="input">', '<ssd:Connector name="u">'),
     ['<ssd:Connector name="u">', "'kind'"]),
])
def test_missing_required_attribute(write_ssd, mutate, fragments):
    _error(write_ssd, mutate(ssd_text(SRC + DST, WIRES)), *fragments)


def test_unknown_component_in_connection(write_ssd):
    _error(write_ssd, ssd_text(SRC + DST, connection_xml("src.y", "gain.u")),
           'endElement "gain" is not a component')


def test_undeclared_connector(write_ssd):
    _error(write_ssd, ssd_text(SRC + DST, connection_xml("src.z", "dst.u")),
           'startConnector "z" is not declared', 'component "src"')


def test_duplicate_component(write_ssd):
    _error(write_ssd, ssd_text(SRC + SRC + DST), '<ssd:Component name="src"> is declared twice')


def test_input_connected_twice(write_ssd):
    src2 = SRC.replace('name="src"', 'name="src2"')
    _error(write_ssd, ssd_text(SRC + src2 + DST, connection_xml("src.y", "dst.u") +
                               connection_xml("src2.y", "dst.u")),
           "input dst.u is already connected", "src.y -> dst.u")


def test_type_mismatch(write_ssd):
    _error(write_ssd, ssd_text(SRC + DST, connection_xml("src.n", "dst.u")),
           "type mismatch, Integer output connected to Real input")


def test_output_to_output_is_rejected(write_ssd):
    _error(write_ssd, ssd_text(SRC + DST, connection_xml("dst.u", "src.y")),
           'start connector has kind "input"')


def test_transformation_not_supported(write_ssd):
    conn = connection_xml("src.y", "dst.u").replace(
        "/>", '><ssc:LinearTransformation factor="2"/></ssd:Connection>')
    _error(write_ssd, ssd_text(SRC + DST, conn), "<ssc:LinearTransformation>", "not supported")


def test_connection_to_system_not_supported(write_ssd):
    conn = '<ssd:Connection startConnector="y_sys" endElement="dst" endConnector="u"/>'
    _error(
        write_ssd, ssd_text(SRC + DST, conn), "connections to the system itself are not supported"
    )


@pytest.mark.parametrize("base_step, fragment", [
    (None, "has no base step"),
    (0.0, "baseStepSize=0.0 must be > 0"),
    (-0.1, "must be > 0"),
    ("abc", 'baseStepSize'),
])
def test_bad_base_step(write_ssd, base_step, fragment):
    _error(write_ssd, ssd_text(SRC + DST, WIRES, base_step=base_step), fragment)


def test_stop_not_after_start(write_ssd):
    _error(write_ssd, ssd_text(SRC + DST, WIRES, start=2.0, stop=2.0),
           "stopTime=2.0 must be greater than startTime=2.0")


@pytest.mark.parametrize("hint, fragment", [
    (0.0, "the step must be > 0"),
    (-1.0, "the step must be > 0"),
    (0.25, "integer multiple of the base step 0.1"),
    (0.05, "integer multiple of the base step 0.1"),
])
def test_bad_step_hint(write_ssd, hint, fragment):
    dst = DST.replace('value="0.5"', f'value="{hint}"')
    _error(write_ssd, ssd_text(SRC + dst, WIRES), '<ssd:Component name="dst">', fragment)


def test_step_hint_multiple_within_tolerance(write_ssd):
    # 0.3 / 0.1 = 2.9999999999999996 in binary floating point: accepted as 3
    model = load_ssd(write_ssd(ssd_text(SRC + DST.replace('value="0.5"', 'value="0.3"'), WIRES)))
    assert model.components[1].step_hint == 0.3


def test_missing_ssv_file(write_ssd):
    dst = DST.replace("</ssd:Connectors>", "</ssd:Connectors><ssd:ParameterBindings>"
                      "<ssd:ParameterBinding source=\"missing.ssv\"/></ssd:ParameterBindings>")
    _error(write_ssd, ssd_text(SRC + dst, WIRES), 'source="missing.ssv": file not found')


def test_bad_parameter_value(write_ssd):
    src = SRC.replace('<ssv:Integer value="3"/>', '<ssv:Integer value="3.5"/>')
    _error(write_ssd, ssd_text(src + DST, WIRES), '<ssv:Parameter name="count">',
           'not a valid Integer')


def test_missing_file(tmp_path):
    with pytest.raises(SspError, match="file not found"):
        load_ssd(tmp_path)
