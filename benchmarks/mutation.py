"""Mutation testing of chosen navcore and orchestrator modules with mutmut (docs/mutation.md).

For each module named (default: all of ``MODULES``), in its own scratch folder
``build/mutation/<module>/``:

* the packages are laid out as they are imported (``navcore/`` from ``fmus/navcore``,
  ``orchestrator/``), with ``tests/``, ``models/``, ``docs/``, ``README.md`` and the slave
  scripts of ``fmus/`` beside them, and a
  ``pyproject.toml`` that is this checkout's plus a ``[tool.mutmut]`` section mutating only that
  module and running only the test files listed for it in ``MODULES``;
* ``mutmut run`` (at most ``--workers`` processes, default 2) makes every mutant and runs, for
  each, the listed tests that reach the mutated function;
* the outcome of every mutant is read back (``mutmut results --all true``) and counted as killed,
  survived, timeout, no tests or equivalent; a survivor listed in ``EQUIVALENT`` with the line it
  makes is counted equivalent, with its reason.

One line per module is printed, then the diff of every non-equivalent survivor, so a survivor
can be killed by a test or named equivalent (``--markdown``: the table and a list of the
survivors in markdown, for docs/mutation.md)::

    nice -n 10 python benchmarks/mutation.py navcore.filters.latency
    nice -n 10 python benchmarks/mutation.py --markdown            # every module of MODULES
    python benchmarks/mutation.py --report navcore.filters.latency   # re-read a finished run
    nice -n 10 python benchmarks/mutation.py --again navcore.filters.latency  # after new tests

A run is slow (one test selection per mutant: minutes to an hour a module); it is not part of
the test suite. ``--report`` reprints a finished run without running anything; ``--again``
re-runs only its survivors (and untested mutants) with the tests as they are now, which is
what a run from scratch would find when only tests were added since.

Error-message text is not mutated: lines that raise or warn are excluded
(``do_not_mutate_patterns``), because the wording of a message is not a behaviour; that a
message names its file, component or parameter is checked by the tests of the CLI's errors.
"""
from __future__ import annotations

import argparse
import json
import os
import re
import shutil
import subprocess
import sys
from dataclasses import dataclass, field
from pathlib import Path

from mutation_equivalents import EQUIVALENT   # the tables beside this script
from mutation_modules import MODULES

ROOT = Path(__file__).resolve().parents[1]
SCRATCH = ROOT / "build" / "mutation"

# lines whose mutants are not run: raising or warning with a message (see the docstring)
NOT_MUTATED_PATTERNS = [r"^\s*raise\s", r"\bwarn(ings\.warn)?\(", r"navfmu: (error|warning)"]

KILLED, SURVIVED, TIMEOUT, NO_TESTS, EQUIV = "killed", "survived", "timeout", "no tests", "equiv"
NOT_CHECKED = "not checked"
EARLIER = "earlier.json"   # verdicts kept from before a run_again


@dataclass
class ModuleResult:
    module: str
    counts: dict[str, int] = field(default_factory=dict)
    survivors: list[str] = field(default_factory=list)
    stale_equivalents: list[str] = field(default_factory=list)

    @property
    def mutants(self) -> int:
        return sum(self.counts.values())

    @property
    def survivor_percent(self) -> float:
        """Surviving and untested mutants per non-equivalent mutant checked."""
        bad = self.counts.get(SURVIVED, 0) + self.counts.get(NO_TESTS, 0)
        checked = self.mutants - self.counts.get(EQUIV, 0) - self.counts.get(NOT_CHECKED, 0)
        return 100.0 * bad / max(checked, 1)


def module_file(module: str) -> Path:
    return Path(*module.split(".")).with_suffix(".py")


def mutmut_section(module: str, tests: list[str]) -> str:
    def toml_list(items):
        return "[" + ", ".join(repr(i).replace("'", '"') for i in items) + "]"
    patterns = toml_list(NOT_MUTATED_PATTERNS)
    return (f"\n[tool.mutmut]\nsource_paths = [\"navcore\", \"orchestrator\"]\n"
            f"also_copy = [\"fmus\", \"models\", \"docs\", \"README.md\"]\n"
            f"only_mutate = {toml_list([str(module_file(module))])}\n"
            f"pytest_add_cli_args_test_selection = {toml_list(tests)}\n"
            f"pytest_add_cli_args = [\"-p\", \"no:cacheprovider\", \"-q\"]\n"
            # an endless loop is given 3 times the tests' time (mutmut's default: 15 times)
            f"timeout_multiplier = 3.0\n"
            f"do_not_mutate_patterns = {patterns}\n")


def write_config(module: str, folder: Path) -> None:
    pyproject = (ROOT / "pyproject.toml").read_text() + mutmut_section(module, MODULES[module])
    (folder / "pyproject.toml").write_text(pyproject)


def lay_out(module: str, folder: Path) -> None:
    """The scratch folder of one module, afresh (a previous run's mutants are removed)."""
    shutil.rmtree(folder, ignore_errors=True)
    folder.mkdir(parents=True)
    ignore = shutil.ignore_patterns("__pycache__", "dist", "*.egg-info")
    shutil.copytree(ROOT / "fmus" / "navcore", folder / "navcore", ignore=ignore)
    for name in ("orchestrator", "tests", "models", "docs"):
        shutil.copytree(ROOT / name, folder / name, ignore=ignore)
    # the slave scripts, which the direct backend imports (their navcore is the mutated one)
    shutil.copytree(ROOT / "fmus", folder / "fmus",
                    ignore=shutil.ignore_patterns("navcore", "__pycache__", "dist"))
    shutil.copy2(ROOT / "README.md", folder / "README.md")
    write_config(module, folder)


def run_again(module: str, folder: Path, workers: int) -> None:
    """Run, with this checkout's tests as they are now, the mutants of an earlier run that
    survived or were not reached (an interrupted run's unchecked ones too).  A new test
    selection makes mutmut forget every verdict, so those that stand are kept in
    ``earlier.json``: a mutant killed stays killed when only tests were added."""
    statuses = mutant_statuses(folder)
    pending = [n for n, s in statuses.items() if s in (SURVIVED, NO_TESTS, NOT_CHECKED)]
    decided = {n: s for n, s in statuses.items() if n not in pending}
    (folder / EARLIER).write_text(json.dumps(decided, indent=0, sort_keys=True))
    shutil.copytree(ROOT / "tests", folder / "tests", dirs_exist_ok=True,
                    ignore=shutil.ignore_patterns("__pycache__"))
    write_config(module, folder)
    # mutmut maps tests to functions again only for new test names: an edited test could
    # reach a function it did not before and not be run for its mutants
    (folder / "mutants" / "mutmut-stats.json").unlink(missing_ok=True)
    if pending:
        mutmut(folder, "run", "--max-children", str(workers), *pending, capture=False)


def mutmut(folder: Path, *args: str, capture: bool = True) -> str:
    # the scratch folder's copies are imported, not this checkout's
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    done = subprocess.run([sys.executable, "-m", "mutmut", *args], cwd=folder, env=env,
                          capture_output=capture, text=True)
    return done.stdout if capture else ""


def changed_lines(folder: Path, name: str, sign: str = "+") -> list[str]:
    """The lines the mutant ``name`` adds (``sign`` "+") or removes ("-"), stripped."""
    diff = mutmut(folder, "show", name)
    return [line[1:].strip() for line in diff.splitlines()
            if line.startswith(sign) and not line.startswith(sign * 3)]


def survivor_item(folder: Path, name: str) -> str:
    """One markdown list item: the mutant and the change it makes."""
    removed = " ".join(changed_lines(folder, name, "-"))
    added = " ".join(changed_lines(folder, name, "+"))
    return f"* `{name.split('.')[-1]}`: `{removed}` -> `{added}`"


def mutant_statuses(folder: Path) -> dict[str, str]:
    """mutant name -> status of the last run, or of an earlier one (run_again) where the last
    did not check it."""
    earlier_path = folder / EARLIER
    earlier = json.loads(earlier_path.read_text()) if earlier_path.exists() else {}
    statuses = {}
    for line in mutmut(folder, "results", "--all", "true").splitlines():
        match = re.match(r"\s*(\S+__mutmut_\d+): (.+)$", line)
        if match:
            name, status = match.groups()
            status = {"suspicious": TIMEOUT, "segfault": KILLED}.get(status, status)
            statuses[name] = earlier.get(name, status) if status == NOT_CHECKED else status
    return statuses


def read_results(module: str, folder: Path) -> ModuleResult:
    result = ModuleResult(module)
    for name, status in mutant_statuses(folder).items():
        # an equivalent mutant runs the same code: a timeout of one is the machine's load
        if status in (SURVIVED, TIMEOUT) and name in EQUIVALENT:
            if EQUIVALENT[name][0] in changed_lines(folder, name):
                status = EQUIV
            else:
                result.stale_equivalents.append(name)
        if status in (SURVIVED, NO_TESTS):
            result.survivors.append(name)
        result.counts[status] = result.counts.get(status, 0) + 1
    return result


COLUMNS = (KILLED, SURVIVED, TIMEOUT, NO_TESTS, EQUIV, NOT_CHECKED)


def table(results: list[ModuleResult], markdown: bool) -> str:
    head = ["module", "mutants", *COLUMNS, "survivor %"]
    rows = [[r.module, str(r.mutants), *(str(r.counts.get(c, 0)) for c in COLUMNS),
             f"{r.survivor_percent:.1f}"] for r in results]
    if markdown:
        lines = ["| " + " | ".join(head) + " |", "|" + " --- |" * len(head)]
        return "\n".join(lines + ["| " + " | ".join(row) + " |" for row in rows])
    return "\n".join(f"{row[0]:36s}" + "".join(f"{c:>12s}" for c in row[1:])
                     for row in [head] + rows)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("modules", nargs="*", help="dotted module names (default: all)")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--report", action="store_true", help="only re-read finished runs")
    parser.add_argument("--again", action="store_true",
                        help="re-run only the survivors of finished runs, with the current tests")
    parser.add_argument("--markdown", action="store_true")
    args = parser.parse_args(argv)
    modules = args.modules or list(MODULES)
    unknown = [m for m in modules if m not in MODULES]
    if unknown:
        parser.error(f"not in MODULES: {', '.join(unknown)}")
    if args.report or args.again:
        missing = [m for m in modules if not (SCRATCH / m / "mutants").is_dir()]
        if missing:
            parser.error(f"no finished run of {', '.join(missing)} in {SCRATCH} (run it first)")
    results = []
    for module in modules:
        folder = SCRATCH / module
        if args.again:
            run_again(module, folder, args.workers)
        elif not args.report:
            lay_out(module, folder)
            mutmut(folder, "run", "--max-children", str(args.workers), capture=False)
        results.append(read_results(module, folder))
    print(table(results, args.markdown))
    for result in results:
        for name in result.stale_equivalents:
            print(f"\nEQUIVALENT entry no longer matches its mutant: {name}")
        if args.markdown and result.survivors:
            print(f"\n{result.module}:\n")
        for name in result.survivors:
            folder = SCRATCH / result.module
            print(survivor_item(folder, name) if args.markdown
                  else f"\n{mutmut(folder, 'show', name).rstrip()}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
