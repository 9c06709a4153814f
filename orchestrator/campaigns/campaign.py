"""Monte Carlo campaigns: N seeds x the filters of a scenario, resumable, one file per run.

A campaign runs scenario ``S`` once per (filter, run index ``i``), ``i = 0 .. N-1``, on an
:class:`~orchestrator.campaigns.executor.Executor` (serial, process pool or Dask).  Run ``i`` of
every filter uses the same seeds, so the filters see the same truth, IMU and GNSS noise and their
per-run numbers are paired (:mod:`orchestrator.campaigns.statistics`).

Seeds.  Every component with an Integer parameter ``seed`` (the random sources) gets, in
run ``i`` of a campaign with seed ``s``: ``seed = s + i + offset``, where ``offset`` is
the component's entry of ``seed_offsets`` or, by default, ``1000 * j`` for the ``j``-th
random component in declaration order (distinct streams for up to 1000 runs).  With
``seed_offsets={"trajectory": 0, "gnss": 0}`` and ``s = 1``, run ``i`` is the
``seed = i + 1`` of both sources (the loop of the earlier slow tests of paper 001/004).

Files in the campaign folder (every file written atomically):

* ``campaign.json`` -- the manifest: the campaign's identity (scenario and the hash of its
  .ssd/.ssv/paper.json files, filters, campaign seed and seed rule, backend, stop time,
  window, samples, overrides, series format, hash of the code that decides the numbers,
  :data:`NUMERIC_CODE`) and the largest run count asked.
  Starting a campaign in a folder whose manifest has another identity is an error; the same
  identity resumes (a larger ``--runs`` adds runs).
* ``runs/<filter>/run-<iiii>.json`` -- one run: its seeds, the git commit it ran on, metrics
  (:func:`~orchestrator.results.metrics.filter_metrics`, accumulated while the run streams), wall
  time. The worker writes it as soon as the run ends (when it sees the folder; otherwise the driver
  does), so a killed campaign loses only the runs in flight; a restart runs only the
  missing files.
* ``series/<filter>/run-<iiii>.parquet`` (or ``.csv``) -- the time series, only when asked.
* ``summary.json`` -- the statistics of :func:`summarize` over runs ``0 .. N-1``.

This module is the campaign's identity and its driver; the seeds are
:mod:`orchestrator.campaigns.seeds`, one run and its files
:mod:`orchestrator.campaigns.campaign_runs`.
"""
from __future__ import annotations

import contextlib
import hashlib
import json
import shutil
import subprocess
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Dict, List, Optional, Tuple

from ..building import build as fmu_build
from ..cosim import interrupts
from ..cosim.isolation import Isolation
from ..results import metrics as nav_metrics
from ..errors import NavfmuError
from . import batching
from .campaign_runs import read_run, run_batch, run_one, write_run
from .executor import Executor, Task
from .seeds import (check_no_seed_override, check_seed_range, random_components, run_seeds,
                    seed_offsets)
from ..results.jsonsafe import jsonable
from ..results.run_results import atomic_write
from .defaults import DEFAULT_SEED, DEFAULT_WORKERS

MANIFEST = "campaign.json"
FORMAT = "navfmu-campaign-1"
SERIES_FORMATS = ("parquet", "csv")


@dataclass(frozen=True)
class CampaignSpec:
    """What a campaign runs (the command's options)."""

    scenario: str
    filters: Tuple[str, ...]
    runs: int
    seed: int = DEFAULT_SEED
    backend: str = "direct"
    stop_time: Optional[float] = None
    window: Optional[Tuple[float, float]] = None
    samples: str = "all"
    seed_offsets: Tuple[Tuple[str, int], ...] = ()
    parameters: Tuple[Tuple[str, Any], ...] = ()
    series: Optional[str] = None
    #: runs per batch on the direct backend (None: chosen, :mod:`.batching`); not part of
    #: the campaign's identity: a batch's runs are its single runs, bit for bit
    batch: Optional[int] = None
    #: which FMUs run in a host process of their own (``--isolate``, ``--call-timeout``);
    #: not part of the identity either: a hosted FMU's numbers are its in-process ones
    isolation: Isolation = Isolation()

    def __post_init__(self):
        if isinstance(self.runs, bool) or not isinstance(self.runs, int) or self.runs < 1:
            raise NavfmuError(f"--runs: expected a whole number >= 1, got {self.runs!r}")
        if not self.filters:
            raise NavfmuError("--filters: give at least one filter")
        if len(set(self.filters)) != len(self.filters):
            raise NavfmuError(f"--filters: a filter is listed twice: {', '.join(self.filters)}")
        if self.backend not in ("direct", "fmu"):
            raise NavfmuError(f"--backend: expected direct or fmu, got {self.backend!r}")
        if self.series is not None and self.series not in SERIES_FORMATS:
            raise NavfmuError(f"--series: expected one of {', '.join(SERIES_FORMATS)}, got "
                              f"{self.series!r}")
        batching.check_batch(self.batch, self.backend)
        if self.samples not in nav_metrics.SAMPLES:
            raise NavfmuError(f"--samples: expected one of {', '.join(nav_metrics.SAMPLES)}, "
                              f"got {self.samples!r}")


def _scenario_files(model) -> List[Path]:
    folder = Path(model.path).parent
    return sorted(p for p in folder.iterdir()
                  if p.suffix in (".ssd", ".ssv") or p.name == "paper.json")


def scenario_hash(model) -> str:
    """sha256 of the scenario folder's .ssd, .ssv and paper.json files (names and bytes)."""
    h = hashlib.sha256()
    for p in _scenario_files(model):
        h.update(p.name.encode() + b"\0" + p.read_bytes())
    return h.hexdigest()


#: the files whose code decides a run's numbers (a change in any refuses a resume)
NUMERIC_CODE = ("fmus/*.py", "fmus/navcore/**/*.py", "orchestrator/cosim/backends.py",
                "orchestrator/cosim/fmu_instance.py", "orchestrator/cosim/direct_instance.py",
                "orchestrator/cosim/component_description.py", "orchestrator/cosim/exchange.py",
                "orchestrator/cosim/master.py", "orchestrator/cosim/model_checks.py",
                "orchestrator/cosim/macro_loop.py", "orchestrator/cosim/result_assembly.py",
                "orchestrator/cosim/batch.py",
                "orchestrator/cosim/batch_instance.py", "orchestrator/results/batch_recording.py",
                "orchestrator/results/metrics.py",
                "orchestrator/results/recorder.py", "orchestrator/model/ssp.py",
                "orchestrator/model/ssp_xml.py", "orchestrator/campaigns/campaign.py",
                "orchestrator/campaigns/campaign_runs.py", "orchestrator/campaigns/seeds.py",
                "orchestrator/results/run_results.py")


def code_hash() -> str:
    """sha256 over the names and bytes of the :data:`NUMERIC_CODE` files."""
    root = fmu_build.ROOT
    h = hashlib.sha256()
    for pattern in NUMERIC_CODE:
        for p in sorted(root.glob(pattern)):
            h.update(p.relative_to(root).as_posix().encode() + b"\0" + p.read_bytes())
    return h.hexdigest()


def code_commit() -> str:
    """The git commit of the code (``+dirty`` when fmus/, orchestrator/ or models/ have
    uncommitted changes); ``unknown`` outside a git checkout."""
    root = fmu_build.ROOT
    try:
        head = subprocess.run(["git", "-C", str(root), "rev-parse", "HEAD"], check=True,
                              capture_output=True, text=True, timeout=30).stdout.strip()
        dirty = subprocess.run(["git", "-C", str(root), "status", "--porcelain",
                                "--untracked-files=no", "--", "fmus", "orchestrator", "models"],
                               check=True, capture_output=True, text=True, timeout=30).stdout
    except (OSError, subprocess.SubprocessError):
        return "unknown"
    return head + ("+dirty" if dirty.strip() else "")


# ----------------------------------------------------------------------------------------
# the campaign (driver)
# ----------------------------------------------------------------------------------------
@dataclass
class Campaign:
    """A campaign in folder ``out``: :meth:`prepare` checks and writes the manifest,
    :meth:`run` runs the missing runs, :meth:`records` reads them all."""

    spec: CampaignSpec
    out: Path
    log: Callable[[str], None] = print
    model: Any = field(default=None, init=False)
    offsets: Dict[str, int] = field(default_factory=dict, init=False)
    identity: Dict[str, Any] = field(default_factory=dict, init=False)
    commit: str = field(default="", init=False)
    runs: int = field(default=0, init=False)

    def prepare(self) -> None:
        """Check everything and write the manifest (:meth:`check`, :meth:`write_manifest`)."""
        self.check()
        self.write_manifest()

    def check(self) -> None:
        """Load the scenario and the filters, compute the identity and compare it with the
        folder's manifest; writes nothing."""
        from ..running.prechecks import check_connected, check_stop_time
        from ..running.scenarios import ensure_fmus, load_scenario, paper_reference, swap_filter

        spec = self.spec
        self.model = load_scenario(spec.scenario)
        paper_reference(self.model)     # a malformed paper.json is refused before any run
        check_connected(self.model)
        check_stop_time(spec.stop_time, self.model.start_time)
        models = [swap_filter(self.model, f) for f in spec.filters]   # unknown filter: error
        if spec.backend == "fmu":      # build once here, never in the workers
            for m in models:
                ensure_fmus(m, log=self.log)
        # every filter's wiring and overrides, checked before any run (mixed roles refused)
        randoms = [random_components(m, spec.backend, spec.parameters) for m in models]
        check_no_seed_override(spec, randoms[0])
        self.offsets = seed_offsets(spec, randoms[0])
        self.identity = {
            "scenario": self.model.name, "ssd": str(Path(self.model.path).resolve()),
            "scenario_sha256": scenario_hash(self.model), "filters": list(spec.filters),
            "seed": spec.seed, "seed_offsets": self.offsets, "backend": spec.backend,
            "stop_time": spec.stop_time, "window": list(spec.window) if spec.window else None,
            "samples": spec.samples, "parameters": [list(p) for p in spec.parameters],
            "series": spec.series, "code_sha256": code_hash()}
        self.commit = code_commit()
        self.runs = self._check_manifest()
        check_seed_range(spec, self.offsets, self.runs)

    def _check_manifest(self) -> int:
        """The run count of the campaign: the larger of ``--runs`` and the manifest's (a
        smaller ``--runs`` than a campaign has finished keeps and summarizes them all)."""
        path = self.out / MANIFEST
        runs = self.spec.runs
        if self.out.exists() and not self.out.is_dir():
            raise NavfmuError(f"--out {self.out}: exists and is not a folder")
        if path.is_file():
            try:
                old = json.loads(path.read_text(encoding="utf-8"))
            except (OSError, json.JSONDecodeError) as exc:
                raise NavfmuError(f"{path}: unreadable campaign manifest: {exc}") from None
            mine = jsonable(self.identity)
            theirs = old.get("identity", {})
            differ = [k for k in mine if k != "ssd" and theirs.get(k) != mine[k]]
            if old.get("format") != FORMAT or differ:
                what = "; ".join(f"{k}: {theirs.get(k)!r} there, {mine[k]!r} here"
                                 for k in differ) or f"format {old.get('format')!r}"
                raise NavfmuError(f"{self.out}: holds another campaign ({what}); resume it "
                                  "with its own options or choose another --out")
            runs = max(runs, int(old.get("runs", 0)))
        elif self.out.is_dir() and any(self.out.iterdir()):
            raise NavfmuError(f"--out {self.out}: the folder holds files but no {MANIFEST}; "
                              "choose a new or empty folder")
        return runs

    def write_manifest(self) -> None:
        """Write ``campaign.json`` (creating the folder)."""
        try:
            self.out.mkdir(parents=True, exist_ok=True)
            atomic_write(self.out / MANIFEST, lambda f: f.write(json.dumps(
                {"format": FORMAT, "identity": jsonable(self.identity), "runs": self.runs},
                indent=2)))
        except OSError as exc:
            raise NavfmuError(f"--out {self.out}: cannot write the campaign there: "
                              f"{exc.strerror or exc}") from None

    def job(self, filter_name: str, index: int) -> Dict[str, Any]:
        s = self.spec
        return {"ssd": str(Path(self.model.path).resolve()), "filter": filter_name,
                "index": index, "seeds": run_seeds(s, self.offsets, index),
                "parameters": list(s.parameters), "backend": s.backend,
                "stop_time": s.stop_time, "window": s.window, "samples": s.samples,
                "series": s.series, "out": str(self.out.resolve()), "commit": self.commit,
                "isolation": {"mode": s.isolation.mode,
                              "call_timeout": s.isolation.call_timeout}}

    def missing(self) -> List[Tuple[str, int]]:
        return [(f, i) for i in range(self.runs) for f in self.spec.filters
                if read_run(self.out, f, i) is None]

    def run(self, executor: Executor, progress=None) -> Dict[str, int]:
        """Run the missing runs; returns counts ``done_before`` and ``ran``.  ``progress(runs
        done, runs to do)`` counts runs (a batch's runs count when the batch ends)."""
        _remove_stale_temporaries(self.out)
        interrupts.safe_point("campaign-started")
        todo = self.missing()
        total = self.runs * len(self.spec.filters)
        ran = 0
        workers = getattr(executor, "workers", 1)
        if progress is not None:
            progress(0, len(todo))
        for _, result in executor.run(self.tasks(todo, workers)):
            for record in (result if isinstance(result, list) else [result]):
                if read_run(self.out, record["filter"], record["index"]) is None:
                    write_run(self.out, record)      # a worker that cannot see the folder
                ran += 1
                interrupts.safe_point(f"campaign-ran-{ran}")
            if progress is not None:
                progress(ran, len(todo))
        return {"done_before": total - len(todo), "ran": ran, "total": total}

    def tasks(self, todo: List[Tuple[str, int]], workers: int) -> List[Task]:
        """One task per run, or per batch of one filter's runs on the direct backend
        (:mod:`.batching`); a batch's key is (filter, first index, last index)."""
        tasks = []
        for name, indices in batching.batches(todo, self.spec.batch, self.spec.backend,
                                              workers):
            if len(indices) == 1:
                tasks.append(Task(key=(name, indices[0]), func=run_one,
                                  args=(self.job(name, indices[0]),)))
            else:
                tasks.append(Task(key=(name, indices[0], indices[-1]), func=run_batch,
                                  args=([self.job(name, i) for i in indices],)))
        return tasks

    def records(self) -> Dict[str, List[Dict[str, Any]]]:
        """filter -> the records of runs 0 .. N-1 (all must exist)."""
        out = {}
        for f in self.spec.filters:
            rows = [read_run(self.out, f, i) for i in range(self.runs)]
            lost = [i for i, r in enumerate(rows) if r is None]
            if lost:
                raise NavfmuError(f"{self.out}: runs {lost} of {f} are missing")
            out[f] = rows
        return out


def run_campaign(spec: CampaignSpec, out, workers: int = DEFAULT_WORKERS,
                 scheduler: Optional[str] = None, local_cluster: bool = False, progress=None,
                 log=print) -> Dict[str, Any]:
    """Prepare, run the missing runs, summarize (written to ``summary.json``); returns the
    summary with ``counts`` (runs done before, run now, total)."""
    from .campaign_summary import summarize
    from ..running.scenarios import paper_reference

    campaign = Campaign(spec, Path(out), log=log)
    with Executor(workers=workers, scheduler=scheduler, local_cluster=local_cluster) as ex:
        campaign.check()
        ex.connect()
        with _undone_if_nothing_ran(campaign):
            campaign.write_manifest()
            counts = campaign.run(ex, progress=progress)
    records = campaign.records()
    summary = summarize(records, paper_reference(campaign.model),
                        {**provenance(campaign, records), "mode": ex.mode})
    atomic_write(campaign.out / "summary.json",
                 lambda f: f.write(json.dumps(jsonable(summary), indent=1)))
    summary["counts"] = counts
    return summary


@contextlib.contextmanager
def _undone_if_nothing_ran(campaign: Campaign):
    """A campaign that fails (or is stopped) before its first run file exists leaves the
    folder as it found it: the manifest written for it, the folders made for it go."""
    out = campaign.out.absolute()
    created = None          # the outermost folder this campaign will create
    for folder in (out, *out.parents):
        if folder.exists():
            break
        created = folder
    had_manifest = (out / MANIFEST).exists()
    try:
        yield
    except BaseException:
        if not had_manifest and not any((out / "runs").glob("*/run-*.json")):
            if created is None:
                (out / MANIFEST).unlink(missing_ok=True)
                for folder in ("runs", "series"):
                    shutil.rmtree(out / folder, ignore_errors=True)
            else:
                shutil.rmtree(created, ignore_errors=True)
        raise


def provenance(campaign: Campaign, records: Dict[str, List[Dict[str, Any]]]) -> Dict[str, Any]:
    """How the numbers of ``records`` were made: the campaign's identity, runs, the commits
    the runs ran on, the seed ranges."""
    spec = campaign.spec
    first = run_seeds(spec, campaign.offsets, 0)
    last = run_seeds(spec, campaign.offsets, campaign.runs - 1)
    commits = sorted({r.get("commit", "") for rows in records.values() for r in rows})
    return {**campaign.identity, "runs": campaign.runs, "commit": ", ".join(commits),
            "seeds": ", ".join(f"{c}.seed {first[c]}..{last[c]}" for c in first)
            or "no random component"}


def _remove_stale_temporaries(out: Path) -> None:
    """Temporary files of runs killed while writing (never a result: names start with '.')."""
    for folder in ("runs", "series"):
        for p in (Path(out) / folder).glob("*/.run-*.tmp"):
            try:
                p.unlink()
            except FileNotFoundError:
                pass


__all__ = [
    "CampaignSpec",
    "Campaign",
    "run_campaign",
    "scenario_hash",
    "code_commit",
    "MANIFEST",
]
