"""Progress bars of the command line: one tqdm bar per label, on a terminal only, each
update a safe point for a deferred Ctrl-C (:mod:`orchestrator.cosim.interrupts`), named
``UNIT-P%`` (``step-50%``: the update at half the run's steps) for the test hook."""
from __future__ import annotations

import contextlib
import sys

from ..cosim import interrupts


@contextlib.contextmanager
def progress_bars():
    """A factory of tqdm progress callbacks (one bar per label, shown on a terminal only);
    every bar is closed (its line cleared) when the block ends, also on an error, so a
    message starts on its own line.  Each callback is a safe point for a deferred Ctrl-C."""
    from tqdm import tqdm

    bars = []

    def factory(label, unit="step"):
        bar = {}

        def progress(done, total):
            interrupts.safe_point(f"{unit}-{100 * done // max(total, 1)}%")
            if "bar" not in bar:
                bar["bar"] = tqdm(total=total, desc=label, unit=unit, leave=False,
                                  mininterval=0.5, file=sys.stderr, disable=None)
                bars.append(bar["bar"])
            bar["bar"].update(done - bar["bar"].n)
            if done >= total:
                bar["bar"].close()

        return progress

    try:
        yield factory
    finally:
        for b in bars:
            b.close()


__all__ = ["progress_bars"]
