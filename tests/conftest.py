"""Shared test fixtures (generic; no navigation)."""
from __future__ import annotations

import collections
import struct
import textwrap
from pathlib import Path

import numpy as np

import pytest

SSD_HEAD = """<?xml version="1.0" encoding="UTF-8"?>
<ssd:SystemStructureDescription version="1.0" name="{name}"
    xmlns:ssd="http://ssp-standard.org/SSP1/SystemStructureDescription"
    xmlns:ssc="http://ssp-standard.org/SSP1/SystemStructureCommon"
    xmlns:ssv="http://ssp-standard.org/SSP1/SystemStructureParameterValues"
    xmlns:osp="http://opensimulationplatform.com/SSP/OSPAnnotations">
"""


def ssd_text(elements: str, connections: str = "", base_step: float | str | None = 0.1,
             start: float = 0.0, stop: float = 1.0, name: str = "toy") -> str:
    """A SystemStructure.ssd around the given <ssd:Component> and <ssd:Connection> XML."""
    algorithm = ("" if base_step is None else
                 f'<ssd:Annotations><ssc:Annotation type="com.opensimulationplatform">'
                 f'<osp:Algorithm><osp:FixedStepAlgorithm baseStepSize="{base_step}"/>'
                 f'</osp:Algorithm></ssc:Annotation></ssd:Annotations>')
    return (SSD_HEAD.format(name=name)
            + f'<ssd:System name="{name}">\n<ssd:Elements>\n{textwrap.dedent(elements)}\n'
            + "</ssd:Elements>\n"
            + (f"<ssd:Connections>\n{textwrap.dedent(connections)}\n</ssd:Connections>\n"
               if connections else "")
            + "</ssd:System>\n"
            + f'<ssd:DefaultExperiment startTime="{start}" stopTime="{stop}">{algorithm}'
            + "</ssd:DefaultExperiment>\n</ssd:SystemStructureDescription>\n")


def component_xml(name: str, source: str, connectors=(), parameters=None,
                  step_hint=None) -> str:
    """``connectors``: (name, kind, type[, unit]); ``parameters``: name -> (type, value)."""
    lines = [f'<ssd:Component name="{name}" source="{source}">', "<ssd:Connectors>"]
    for c in connectors:
        cname, kind, typ = c[:3]
        unit = f' unit="{c[3]}"' if len(c) > 3 else ""
        lines.append(
            f'<ssd:Connector name="{cname}" kind="{kind}"><ssc:{typ}{unit}/></ssd:Connector>'
        )
    lines.append("</ssd:Connectors>")
    if parameters:
        lines.append("<ssd:ParameterBindings><ssd:ParameterBinding><ssd:ParameterValues>"
                     "<ssv:ParameterSet version=\"1.0\" name=\"p\"><ssv:Parameters>")
        for pname, (typ, value) in parameters.items():
            lines.append(
                f'<ssv:Parameter name="{pname}"><ssv:{typ} value="{value}"/></ssv:Parameter>'
            )
        lines.append("</ssv:Parameters></ssv:ParameterSet></ssd:ParameterValues>"
                     "</ssd:ParameterBinding></ssd:ParameterBindings>")
    if step_hint is not None:
        lines.append('<ssd:Annotations><ssc:Annotation type="com.opensimulationplatform">'
                     f'<osp:StepSizeHint value="{step_hint}"/></ssc:Annotation></ssd:Annotations>')
    lines.append("</ssd:Component>")
    return "\n".join(lines)


def connection_xml(start: str, end: str) -> str:
    """``start``/``end`` as "component.connector"."""
    sc, sv = start.split(".", 1)
    ec, ev = end.split(".", 1)
    return (f'<ssd:Connection startElement="{sc}" startConnector="{sv}" endElement="{ec}" '
            f'endConnector="{ev}"/>')


@pytest.fixture
def write_ssd(tmp_path):
    """Write an SSD (text) into a fresh folder under tmp_path; return the .ssd path."""
    counter = iter(range(10_000))

    def write(text: str, folder: str | None = None) -> Path:
        d = tmp_path / (folder or f"system{next(counter)}")
        d.mkdir(parents=True, exist_ok=True)
        p = d / "SystemStructure.ssd"
        p.write_text(text)
        return p

    return write


@pytest.fixture
def navfmu_cli(capsys):
    """Run the ``navfmu`` command line in-process: ``(exit status, stdout, stderr)``."""
    from orchestrator.cli.commands import main

    def run(*args):
        with pytest.raises(SystemExit) as exc:
            main([str(a) for a in args])
        out, err = capsys.readouterr()
        return exc.value.code, out, err

    return run


def bits(x: float) -> bytes:
    return struct.pack(">d", x)


def assert_same(a, b, where="component"):
    """Bit-identical object graphs (declared objects by their attributes)."""
    assert type(a) is type(b), where
    if isinstance(a, np.ndarray):
        assert a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes(), where
    elif isinstance(a, float):
        assert bits(a) == bits(b), where
    elif isinstance(a, np.random.Generator):
        assert a.bit_generator.state == b.bit_generator.state, where
    elif isinstance(a, (list, tuple, collections.deque)):
        assert len(a) == len(b) and getattr(a, "maxlen", 0) == getattr(b, "maxlen", 0), where
        for i, (x, y) in enumerate(zip(a, b)):
            assert_same(x, y, f"{where}[{i}]")
    elif isinstance(a, dict):
        assert a.keys() == b.keys(), where
        for k in a:
            assert_same(a[k], b[k], f"{where}.{k}")
    elif hasattr(a, "__dict__"):
        assert vars(a).keys() == vars(b).keys(), where
        for k in vars(a):
            assert_same(getattr(a, k), getattr(b, k), f"{where}.{k}")
    else:
        assert a == b, where
