"""Warnings in the command line's own voice: each :class:`~orchestrator.errors.NavfmuWarning`
prints once as one line ``navfmu: warning: <message>`` (no source line, no category), however
often and from wherever in this process it is raised; warnings of the libraries (matplotlib's
legend notes, pandas' and Dask's deprecations) are not the user's to act on and are not shown
(``--debug`` shows them as Python prints them).  Worker processes of a campaign or a tuning
run raise the same warnings as the driver does before it starts them, so the workers keep
theirs to themselves (:mod:`orchestrator.campaigns.executor`)."""
from __future__ import annotations

import contextlib
import warnings
from typing import Callable, Iterator

from ..errors import NavfmuWarning

PREFIX = "navfmu: warning: "


@contextlib.contextmanager
def in_cli_voice(echo: Callable[[str], None], debug: bool = False) -> Iterator[None]:
    """Within the block every NavfmuWarning is ``echo``-ed once as ``navfmu: warning: ...``;
    other warnings are dropped (shown as Python shows them when ``debug``)."""
    shown = set()
    python_show = warnings.showwarning

    def show(message, category, filename, lineno, file=None, line=None):
        if issubclass(category, NavfmuWarning):
            text = str(message)
            if text not in shown:
                shown.add(text)
                echo(PREFIX + text)
        elif debug:
            python_show(message, category, filename, lineno, file, line)

    with warnings.catch_warnings():
        warnings.simplefilter("always")     # repeats are dropped by message text above
        warnings.showwarning = show
        yield


__all__ = ["in_cli_voice", "PREFIX"]
