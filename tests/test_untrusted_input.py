"""Files and blobs from elsewhere are data: SSP files without DTDs or entities and within a
size bound, motion profiles within a size bound, and no code-running loader anywhere in
the product's source."""
from __future__ import annotations

import ast
from pathlib import Path

import pytest

from navcore.ins import motion_profiles
from navcore.core.component import ParameterError
from orchestrator.model import ssp, ssp_xml
from orchestrator.errors import SspError

ROOT = Path(__file__).resolve().parents[1]
PRODUCT = [p for folder in ("fmus", "orchestrator") for p in (ROOT / folder).rglob("*.py")
           if "dist" not in p.relative_to(ROOT).parts]

LAUGHS = """<?xml version="1.0"?>
<!DOCTYPE lolz [<!ENTITY lol "lol"><!ENTITY lol2 "&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;">]>
<ssd:SystemStructureDescription version="1.0" name="&lol2;"
    xmlns:ssd="http://ssp-standard.org/SSP1/SystemStructureDescription"/>
"""
EXTERNAL = """<?xml version="1.0"?>
<!DOCTYPE x [<!ENTITY secret SYSTEM "file:///etc/passwd">]>
<ssd:SystemStructureDescription version="1.0" name="&secret;"
    xmlns:ssd="http://ssp-standard.org/SSP1/SystemStructureDescription"/>
"""


@pytest.mark.parametrize("text", [LAUGHS, EXTERNAL], ids=["entity expansion", "external entity"])
def test_ssd_with_a_dtd_is_refused(write_ssd, text):
    path = write_ssd(text)
    with pytest.raises(SspError, match="DTD or entity is not allowed") as info:
        ssp.load_ssd(path)
    assert str(path) in str(info.value) and "root:" not in str(info.value)


def test_oversized_ssd_is_refused_before_parsing(write_ssd, monkeypatch):
    path = write_ssd("<not even xml" + " " * 200)
    monkeypatch.setattr(ssp_xml, "MAX_FILE_BYTES", 100)
    with pytest.raises(SspError, match="more than the 100"):
        ssp.load_ssd(path)


def test_oversized_or_deeply_nested_profile_is_refused(tmp_path, monkeypatch):
    deep = tmp_path / "deep.json"
    deep.write_text("[" * 100_000 + "]" * 100_000)
    with pytest.raises(ParameterError, match="deep.json"):
        motion_profiles.load_profile(str(deep))
    monkeypatch.setattr(motion_profiles, "MAX_PROFILE_BYTES", 1000)
    with pytest.raises(ParameterError, match="larger than the 1000 bytes"):
        motion_profiles.load_profile(str(deep))


#: modules whose loaders run code from the data they read
CODE_LOADING_MODULES = {"pickle", "cPickle", "_pickle", "dill", "cloudpickle", "marshal",
                        "shelve", "jsonpickle"}


def _code_loading_uses(tree):
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            yield from (a.name for a in node.names
                        if a.name.split(".")[0] in CODE_LOADING_MODULES)
        elif isinstance(node, ast.ImportFrom) and node.module:
            if node.module.split(".")[0] in CODE_LOADING_MODULES:
                yield node.module
        elif isinstance(node, ast.Call):
            func = node.func
            if isinstance(func, ast.Name) and func.id in ("eval", "exec", "__import__"):
                yield func.id
            if (isinstance(func, ast.Attribute) and func.attr in ("load", "load_all",
                                                                  "unsafe_load", "full_load")
                    and isinstance(func.value, ast.Name) and func.value.id == "yaml"):
                yield f"yaml.{func.attr}"
            for kw in node.keywords:
                if kw.arg == "allow_pickle" and not (isinstance(kw.value, ast.Constant)
                                                     and kw.value.value is False):
                    yield "allow_pickle"


def test_the_scan_finds_what_it_looks_for():
    source = ("import pickle\nfrom marshal import loads\neval('1')\nyaml.load(f)\n"
              "np.load(p, allow_pickle=True)\n")
    assert sorted(_code_loading_uses(ast.parse(source))) == sorted(
        ["pickle", "marshal", "eval", "yaml.load", "allow_pickle"])


def test_no_code_running_loader_in_the_product():
    found = {str(p.relative_to(ROOT)): uses for p in PRODUCT
             if (uses := sorted(set(_code_loading_uses(ast.parse(p.read_text())))))}
    assert len(PRODUCT) > 30
    assert found == {}
