"""What the benchmark scripts share: running Python on a checkout's own sources, and the
alternating order of the pairs.  Standard library only: the scripts also run this file's
folder inside another checkout (``ab_speed.py``, ``step_cpu.py``)."""
from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from pathlib import Path


def checkout_env(checkout: Path) -> dict:
    """The environment of a child on ``checkout``'s sources (plots without a display)."""
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(checkout / "fmus"), str(checkout)])
    env.setdefault("MPLBACKEND", "Agg")
    return env


def run_python(checkout: Path, args, what: str, script: str = "benchmark"):
    """``(wall time [s], stdout)`` of ``python ARGS`` run in ``checkout`` on its own sources;
    a failure ends the benchmark with the tail of its stderr."""
    t0 = time.perf_counter()
    done = subprocess.run([sys.executable, *args], cwd=checkout, env=checkout_env(checkout),
                          capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if done.returncode:
        raise SystemExit(f"{script}: {what} failed in {checkout}:\n{done.stderr[-2000:]}")
    return wall, done.stdout


def last_json(stdout: str):
    """The JSON a child printed as its last line."""
    return json.loads(stdout.strip().splitlines()[-1])


def build_fmus(checkout: Path, script: str = "benchmark") -> None:
    """Build ``checkout``'s FMUs (untimed, before the first pair)."""
    run_python(checkout, ["-m", "orchestrator.cli", "build"], "the FMU build", script)


def alternating(pairs: int, items):
    """``(i, order)`` for ``i`` in ``range(pairs)``: ``items`` in order, then reversed, and so on,
    so that neither side always runs first."""
    items = tuple(items)
    for i in range(pairs):
        yield i, (items if i % 2 == 0 else items[::-1])


def argument_parser(doc: str, pairs: int, other: bool = False):
    """The command line of a benchmark script: its docstring's first paragraph as the
    description and the number of alternating pairs (``--pairs``, default ``pairs``);
    ``other``: also the required ``--other`` checkout (:func:`other_checkout` checks it)."""
    import argparse

    parser = argparse.ArgumentParser(description=doc.split("\n\n")[0])
    parser.add_argument("--pairs", type=int, default=pairs,
                        help=f"alternating pairs (default {pairs})")
    if other:
        parser.add_argument("--other", type=Path, required=True,
                            help="the other checkout (its root folder)")
    return parser


def other_checkout(parser, args) -> Path:
    """``--other`` resolved, or the parser's error when it is no navfmu checkout."""
    if not (args.other / "orchestrator").is_dir():
        parser.error("--other: give the root folder of another navfmu checkout")
    return args.other.resolve()


#: modules renamed when the packages were grouped into wings (new last name -> old name)
_FLAT_NAMES = {"run_results": "results", "commands": "cli", "registry": "components"}


def layout_module(name: str):
    """The module ``name`` as the wing layout calls it (``orchestrator.running.scenarios``), or,
    in a checkout from before the wings, the flat module it was (``orchestrator.scenarios``),
    so that a script can measure this checkout against an older one."""
    import importlib

    try:
        return importlib.import_module(name)
    except ModuleNotFoundError:
        package, last = name.split(".")[0], name.rsplit(".", 1)[1]
        return importlib.import_module(f"{package}.{_FLAT_NAMES.get(last, last)}")
