"""The verification's files: ``verify.md`` (one table of check, criterion, measured value and
verdict, then a paragraph, and a figure where there is one, per check), ``verify.json`` and,
when asked, JUnit XML for a CI (one testcase per check: a fail is a ``failure``, a skip is
``skipped``, a warn passes with its reason in ``system-out``)."""
from __future__ import annotations

import json
import shutil
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any, Dict, List, Optional

from ..results import outputs
from ..results.jsonsafe import jsonable
from ..results.run_results import atomic_write
from .roles import ROLE_TITLES
from .verdicts import FAILING, VERDICTS, Check

FORMAT = "navfmu-verify-1"


def counts(checks: List[Check]) -> Dict[str, int]:
    return {v: sum(c.verdict == v for c in checks) for v in VERDICTS}


def failing(checks: List[Check]) -> bool:
    """Whether a check failed or crashed (the exit status is then 1)."""
    return any(c.verdict in FAILING for c in checks)


def _cell(text: str) -> str:
    return str(text).replace("|", "\\|").replace("\n", " ")


def _build_line(build: Dict[str, Any]) -> str:
    """Which code was verified: the FMU's content hash, its tool and its navfmu build."""
    line = (f"sha256 `{build.get('fmu_sha256', '?')}`, GUID `{build.get('guid', '?')}`, "
            f"made by {build.get('generation_tool') or 'an unnamed tool'}")
    if "navfmu_build" in build:
        line += (f"; navfmu {build['navfmu_version']} build `{build['navfmu_build'][:16]}`"
                 + (", its code changed after that build" if build["changed_after_build"]
                    else ""))
    return line


def markdown(summary: Dict[str, Any], checks: List[Check]) -> str:
    n = counts(checks)
    lines = [f"# navfmu verify: {summary['model_name']}", "",
             f"- FMU: `{summary['fmu']}`",
             f"- build: {_build_line(summary.get('build') or {})}",
             f"- role: {ROLE_TITLES[summary['role']]} (`{summary['role']}`"
             + (", forced with --role)" if summary.get("role_forced") else ", detected)"),
             f"- scenario(s): {', '.join(summary['scenarios'])}; seeds per case: "
             f"{summary['runs']}",
             f"- verdict: **{'FAIL' if failing(checks) else 'PASS'}** ({n['pass']} pass, "
             f"{n['fail']} fail, {n['warn']} warn, {n['skip']} skip"
             + (f", {n['crash']} crash" if n["crash"] else "") + ")", "",
             "| check | criterion | measured | verdict |", "|---|---|---|---|"]
    for c in checks:
        lines.append(f"| {c.id} | {_cell(c.criterion)} | {_cell(c.measured)} | "
                     f"{c.verdict} |")
    lines.append("")
    for c in checks:
        lines += [f"## {c.id}: {c.title}", "",
                  f"Criterion: {c.criterion}. Measured: {c.measured}. Verdict: "
                  f"**{c.verdict}**" + (f": {c.reason}." if c.reason else "."), ""]
        if c.details.get("failure_text"):
            lines += ["```", c.details["failure_text"], "```", ""]
        if c.figure:
            lines += [f"![{c.id}]({c.figure})", ""]
    return "\n".join(lines)


def junit_xml(summary: Dict[str, Any], checks: List[Check]) -> bytes:
    n = counts(checks)
    suite = ET.Element("testsuite", name=f"navfmu verify {summary['model_name']}",
                       tests=str(len(checks)), failures=str(n["fail"]),
                       errors=str(n["crash"]),
                       skipped=str(n["skip"]))
    for c in checks:
        case = ET.SubElement(suite, "testcase", classname=f"navfmu.verify.{summary['model_name']}",
                             name=c.id)
        text = f"{c.criterion}; measured: {c.measured}"
        if c.details.get("failure_text"):
            text += "\n" + c.details["failure_text"]
        if c.verdict == "fail":
            ET.SubElement(case, "failure", message=c.reason or "failed").text = text
        elif c.verdict == "crash":
            ET.SubElement(case, "error", message=c.reason or "crashed").text = text
        elif c.verdict == "skip":
            ET.SubElement(case, "skipped", message=c.reason or "skipped")
        elif c.verdict == "warn":
            ET.SubElement(case, "system-out").text = f"warn: {c.reason}; {text}"
    return ET.tostring(suite, encoding="utf-8", xml_declaration=True)


def write_report(out, summary: Dict[str, Any], checks: List[Check],
                 figures: Optional[Dict[str, Path]] = None, junit=None) -> Path:
    """Write the folder ``out`` whole (staged, :mod:`orchestrator.outputs`) and the JUnit
    file ``junit`` if given; returns the path of verify.md."""
    figures = figures or {}
    with outputs.staged(out) as stage:
        for name, path in figures.items():
            shutil.copyfile(path, stage / name)
        (stage / "verify.md").write_text(markdown(summary, checks) + "\n", encoding="utf-8")
        document = {"format": FORMAT, **summary, "counts": counts(checks),
                    "checks": [c.as_dict() for c in checks]}
        (stage / "verify.json").write_text(json.dumps(jsonable(document), indent=1) + "\n",
                                           encoding="utf-8")
    if junit:
        data = junit_xml(summary, checks)
        atomic_write(Path(junit), lambda f: f.write(data), binary=True)
    return Path(out) / "verify.md"


__all__ = ["write_report", "markdown", "junit_xml", "counts", "failing"]
