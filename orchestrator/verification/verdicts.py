"""A check's verdict, and the child processes the checks that load the FMU run in
(:func:`run_child`, shared with the master's FMU host: :mod:`orchestrator.cosim.host_process`).

Verdicts: ``pass``, ``fail``, ``warn`` (worth a look, does not fail the verification) and
``skip`` (the FMU lacks what the check needs, e.g. an optional output; never a fail) and
``crash`` (the process hosting the FMU died, twice: retried once; not a judgement of the
check's criterion, though the verification fails).  A fail or crash from a run that did not
finish says where (simulated time, FMI call), why (the FMU's message and exception) and what
to try (:mod:`.run_failures`).
"""
from __future__ import annotations

from dataclasses import asdict, dataclass, field
from typing import Any, Dict, Optional

from ..cosim.host_process import run_child

VERDICTS = ("pass", "fail", "warn", "skip", "crash")
#: verdicts that make the verification's exit status 1
FAILING = ("fail", "crash")


@dataclass
class Check:
    """One check: what it measures, its criterion, what it measured and the verdict with the
    reason (every fail, warn and skip says why)."""

    id: str
    title: str
    criterion: str
    measured: str
    verdict: str
    reason: str = ""
    details: Dict[str, Any] = field(default_factory=dict)
    figure: Optional[str] = None

    def __post_init__(self):
        if self.verdict not in VERDICTS:
            raise ValueError(f"verdict {self.verdict!r} is not one of {VERDICTS}")

    def as_dict(self):
        return asdict(self)


__all__ = ["Check", "VERDICTS", "FAILING", "run_child"]
