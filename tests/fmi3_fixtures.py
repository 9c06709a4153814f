"""FMI 3.0 co-simulation FMUs for the tests, independent of navfmu's own code: C models written
after the FMI 3.0 standard (``tests/fmi3c``: the interface ``fmi3_shell.h``, the models
``dahlquist3.c`` and ``passthrough3.c``), compiled with the system's C compiler against the
standard's headers as fmpy ships them, and packed with a model description into an FMU.

``Dahlquist3.xml`` is the Dahlquist model's description; :func:`variant` rewrites it into the
FMUs the master must refuse (a Float32 output, an array, a clock...); :func:`passthrough_xml`
writes the pass-through's description for the given channels."""
from __future__ import annotations

import shutil
import subprocess
import zipfile
from pathlib import Path
from typing import Iterable, Tuple

import fmpy

HERE = Path(__file__).resolve().parent / "fmi3c"
HEADERS = Path(fmpy.__file__).parent / "c-code"
#: where FMI 3.0 puts the binary for this platform
PLATFORM = fmpy.platform_tuple
DAHLQUIST_XML = (HERE / "Dahlquist3.xml").read_text()
PASSTHROUGH_TOKEN = "{8c4e0a37-3d0b-4c59-9b7e-5f1d2a6c3e02}"


def compiler() -> str | None:
    """The C compiler, or None (with the FMI 3 headers missing too)."""
    cc = shutil.which("cc") or shutil.which("gcc")
    return cc if cc and (HEADERS / "fmi3Functions.h").is_file() else None


def compile_model(source: str, folder: Path) -> Path:
    """``tests/fmi3c/<source>.c`` as ``folder/<source>.so``."""
    lib = folder / f"{source}.so"
    r = subprocess.run([compiler(), "-O1", "-Wall", "-Wextra", "-Werror", "-shared", "-fPIC",
                        "-I", str(HEADERS), "-I", str(HERE), "-o", str(lib),
                        str(HERE / f"{source}.c"), "-lm"], capture_output=True, text=True)
    if r.returncode != 0:
        raise RuntimeError(f"compiling {source}.c failed:\n{r.stderr}")
    return lib


def pack(xml: str, library: Path, out: Path) -> Path:
    """An FMU ``out`` of the model description ``xml`` and the shared ``library``."""
    with zipfile.ZipFile(out, "w") as z:
        z.writestr("modelDescription.xml", xml)
        z.write(library, f"binaries/{PLATFORM}/{library.name}")
    return out


def variant(old: str, new: str, xml: str = DAHLQUIST_XML) -> str:
    """``xml`` with ``old`` (which must occur) replaced by ``new``."""
    assert old in xml, old
    return xml.replace(old, new)


def passthrough_xml(channels: Iterable[Tuple[str, str]]) -> str:
    """The pass-through's description: for each (name, unit) an input ``in_<name>`` (value
    reference i) and an output ``<name>`` (1000 + i) that repeats it."""
    channels = list(channels)
    units = sorted({u for _, u in channels if u})
    unit_xml = "".join(f'<Unit name="{u}"/>' for u in units)
    variables, outputs = [], []
    for i, (name, unit) in enumerate(channels, start=1):
        attr = f' unit="{unit}"' if unit else ""
        variables.append(f'<Float64 name="in_{name}" valueReference="{i}" causality="input" '
                         f'variability="continuous" start="0"{attr}/>')
        variables.append(f'<Float64 name="{name}" valueReference="{1000 + i}" '
                         f'causality="output" variability="continuous"{attr}/>')
        outputs.append(f'<Output valueReference="{1000 + i}" dependencies="{i}"/>')
    return f"""<?xml version="1.0" encoding="UTF-8"?>
<fmiModelDescription fmiVersion="3.0" modelName="Passthrough3"
    instantiationToken="{PASSTHROUGH_TOKEN}" generationTool="hand-written">
  <CoSimulation modelIdentifier="passthrough3" canGetAndSetFMUState="true"/>
  <UnitDefinitions>{unit_xml}</UnitDefinitions>
  <ModelVariables>
    <Float64 name="time" valueReference="0" causality="independent" variability="continuous"/>
    {chr(10).join(variables)}
  </ModelVariables>
  <ModelStructure>{"".join(outputs)}</ModelStructure>
</fmiModelDescription>
"""
