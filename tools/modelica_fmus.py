"""Build the Rumoca Modelica compiler from its PyPI source and regenerate the Modelica FMUs.

Usage::

    python tools/modelica_fmus.py [--build-dir DIR] [--jobs 2]

regenerates ``examples/modelica/fmus/fmi2/<Model>.fmu`` and ``fmi3/<Model>.fmu`` (source FMUs:
C code, no binary) from ``examples/modelica/NavVehicles.mo``.

Rumoca (https://github.com/CogniPilot/rumoca, Apache-2.0) is pinned to 0.10.2.  The registry's
wheel lacks FMU export, so the compiler is built from the source distribution on PyPI
(checked against its SHA-256) with cargo into ``--build-dir`` (default
``~/.cache/navfmu/rumoca-build``; nothing of it enters this repository):

* the ``[patch.crates-io] diffsol`` entry is dropped (it points to ``vendor/diffsol``, which the
  source distribution does not ship; diffsol then comes from crates.io);
* a 30-line driver crate (``rumoca-fmu-driver``, written here) is added to the workspace: it
  compiles one model through the library API (``rumoca::Compiler`` and
  ``rumoca::compile_packaged_target``, feature ``fmu-packaging``, no default features), which
  avoids the command line's network features (transports, web viewer);
* ``cargo build -j2 --release -p rumoca-fmu-driver``: 313 crates (the workspace's included)
  from crates.io (so the first build needs the network), measured 1441 s of CPU
  (24 CPU-minutes, 1.1 GB peak memory) and 60 min wall clock at nice 10 on two cores shared
  with other work, Rust 1.95; a 47 MB binary.  Later runs reuse the build (about 1 s), and
  each model compiles in 0.2-0.3 s.

Rumoca gives every compiled FMU a new random GUID (FMI 3.0: instantiation token), which is
also its model identifier (``Rumoca_<uuid>``, the library's name); this script makes the
output deterministic: the UUID is replaced by a UUID-5 of the compiler version, the target,
the model and the Modelica source, and the archive is written with sorted members and fixed
dates.  The same source then gives the same FMU bytes (checked: two runs, equal SHA-256).
"""
from __future__ import annotations

import argparse
import hashlib
import re
import shutil
import subprocess
import sys
import tarfile
import tempfile
import time
import urllib.request
import uuid
import zipfile
from pathlib import Path

VERSION = "0.10.2"
SDIST_URL = ("https://files.pythonhosted.org/packages/c1/30/"
             "465fffc12f61dbe18c6fb80c72712eed2ba898c535ce9b94ae2e8067360b/"
             f"rumoca-{VERSION}.tar.gz")
SDIST_SHA256 = "54e0c1b9527df87f6542f1b4755732792bd59394cc5217c12a540d83ca538205"
ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "examples" / "modelica"
SOURCE = EXAMPLES / "NavVehicles.mo"
MODELS = ("FixedWingAircraft", "GroundVehicle")
TARGETS = ("fmi2", "fmi3")
#: the date of every archive member (a fixed one keeps the bytes reproducible)
ZIP_DATE = (2026, 1, 1, 0, 0, 0)
DRIVER = "rumoca-fmu-driver"
DRIVER_TOML = f"""[package]
name = "{DRIVER}"
version = "{VERSION}"
edition = "2024"
publish = false

[dependencies]
rumoca = {{ path = "../rumoca", default-features = false, features = ["fmu-packaging"] }}
"""
DRIVER_MAIN = r'''//! Compile one Modelica model to a packaged FMU target (fmi2 or fmi3)
//! through the library API only (no network-capable command line).
//! Usage: rumoca-fmu-driver <model.mo> <ModelName> <fmi2|fmi3> <out_dir>
use std::path::PathBuf;
use std::process::ExitCode;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().collect();
    if args.len() != 5 {
        eprintln!("usage: {} <model.mo> <ModelName> <fmi2|fmi3> <out_dir>", args[0]);
        return ExitCode::from(2);
    }
    let (file, model, target, out) = (&args[1], &args[2], &args[3], PathBuf::from(&args[4]));
    let result = match rumoca::Compiler::new().model(model).compile_file(file) {
        Ok(result) => result,
        Err(error) => {
            eprintln!("{file}: {error}");
            return ExitCode::from(1);
        }
    };
    if let Err(error) = std::fs::create_dir_all(&out) {
        eprintln!("{}: {error}", out.display());
        return ExitCode::from(1);
    }
    match rumoca::compile_packaged_target(&result, model, target, out) {
        Ok(()) => ExitCode::SUCCESS,
        Err(error) => {
            eprintln!("{file}: {model} -> {target}: {error:#}");
            ExitCode::from(1)
        }
    }
}
'''


def fail(message: str) -> None:
    print(f"modelica_fmus: error: {message}", file=sys.stderr)
    raise SystemExit(1)


def fetch_sources(build_dir: Path) -> Path:
    """Download (once) and unpack the source distribution; returns the workspace folder."""
    archive = build_dir / f"rumoca-{VERSION}.tar.gz"
    if not archive.is_file():
        print(f"downloading {SDIST_URL}")
        with urllib.request.urlopen(SDIST_URL) as response, open(archive, "wb") as out:
            shutil.copyfileobj(response, out)
    digest = hashlib.sha256(archive.read_bytes()).hexdigest()
    if digest != SDIST_SHA256:
        fail(f"{archive}: SHA-256 {digest}, expected {SDIST_SHA256}")
    workspace = build_dir / f"rumoca-{VERSION}"
    if not workspace.is_dir():
        with tarfile.open(archive) as tar:
            tar.extractall(build_dir, filter="data")
    return workspace


def patch_workspace(workspace: Path) -> None:
    """Drop the diffsol patch entry and add the driver crate (idempotent)."""
    manifest = workspace / "Cargo.toml"
    text = manifest.read_text()
    text = re.sub(r'\n\[patch\.crates-io\]\n(?:#.*\n)*diffsol = \{ path = "vendor/diffsol" \}\n',
                  "\n", text)
    if f'"crates/{DRIVER}"' not in text:
        text = text.replace('members = [', f'members = ["crates/{DRIVER}", ', 1)
    manifest.write_text(text)
    crate = workspace / "crates" / DRIVER
    (crate / "src").mkdir(parents=True, exist_ok=True)
    for path, content in ((crate / "Cargo.toml", DRIVER_TOML),
                          (crate / "src" / "main.rs", DRIVER_MAIN)):
        if not path.is_file() or path.read_text() != content:
            path.write_text(content)


def build_driver(workspace: Path, jobs: int) -> Path:
    started = time.monotonic()
    command = ["cargo", "build", f"-j{jobs}", "--release", "-p", DRIVER]
    print(" ".join(command))
    if subprocess.run(command, cwd=workspace).returncode != 0:
        fail(f"cargo build failed in {workspace}")
    print(f"compiler built (or up to date) in {time.monotonic() - started:.0f} s")
    return workspace / "target" / "release" / DRIVER


UUID = re.compile(r"[0-9a-f]{8}([-_])[0-9a-f]{4}\1[0-9a-f]{4}\1[0-9a-f]{4}\1[0-9a-f]{12}")


def deterministic(fmu: Path, out: Path, model: str, target: str) -> None:
    """Write ``fmu`` to ``out`` with its random UUIDs (the GUID or instantiation token, and
    in the model identifier, spelt with underscores) replaced by UUID-5s of its inputs,
    sorted members and fixed dates (see the module docstring)."""
    with zipfile.ZipFile(fmu) as z:
        members = {name: z.read(name) for name in z.namelist() if not name.endswith("/")}
    found = []
    for match in UUID.finditer(members["modelDescription.xml"].decode()):
        key = match.group(0).replace("_", "-")
        if key not in found:
            found.append(key)
    if not found:
        fail(f"{fmu}: no GUID found in its model description")
    seed = f"rumoca {VERSION} {target} {model} {hashlib.sha256(SOURCE.read_bytes()).hexdigest()}"
    new = {old: str(uuid.uuid5(uuid.NAMESPACE_URL, f"{seed} {i}")) for i, old in enumerate(found)}
    tmp = out.with_suffix(".tmp")
    with zipfile.ZipFile(tmp, "w", zipfile.ZIP_DEFLATED) as z:
        for name in sorted(members):
            data = members[name]
            try:
                text = data.decode()
            except UnicodeDecodeError:
                pass
            else:
                for old, replacement in new.items():
                    text = text.replace(old, replacement).replace(
                        old.replace("-", "_"), replacement.replace("-", "_"))
                data = text.encode()
            if UUID.search(name):
                fail(f"{fmu}: a UUID in the member name {name}")
            info = zipfile.ZipInfo(name, ZIP_DATE)
            info.compress_type = zipfile.ZIP_DEFLATED
            info.external_attr = 0o644 << 16
            z.writestr(info, data)
    tmp.replace(out)


def generate(driver: Path) -> None:
    for target in TARGETS:
        folder = EXAMPLES / "fmus" / target
        folder.mkdir(parents=True, exist_ok=True)
        for model in MODELS:
            qualified = f"NavVehicles.{model}"
            with tempfile.TemporaryDirectory() as tmp:
                started = time.monotonic()
                done = subprocess.run([str(driver), str(SOURCE), qualified, target, tmp])
                if done.returncode != 0:
                    fail(f"{qualified} -> {target} failed")
                made = sorted(Path(tmp).rglob("*.fmu"))
                if len(made) != 1:
                    fail(f"{qualified} -> {target}: expected one .fmu, found {made}")
                deterministic(made[0], folder / f"{model}.fmu", model, target)
            print(f"{folder / f'{model}.fmu'} ({time.monotonic() - started:.1f} s)")


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--build-dir", type=Path,
                        default=Path.home() / ".cache" / "navfmu" / "rumoca-build",
                        help="where the compiler is downloaded and built (outside the repository)")
    parser.add_argument("--jobs", type=int, default=2, help="cargo's parallel jobs")
    args = parser.parse_args(argv)
    if shutil.which("cargo") is None:
        fail("cargo not found on PATH (install Rust: https://rustup.rs)")
    args.build_dir.mkdir(parents=True, exist_ok=True)
    workspace = fetch_sources(args.build_dir)
    patch_workspace(workspace)
    generate(build_driver(workspace, args.jobs))


if __name__ == "__main__":
    main()
