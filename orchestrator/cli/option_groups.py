"""Options several ``navfmu`` commands share, as click decorators: the options of a run
(``run``, ``compare``), the FMU isolation (``--isolate``, ``--call-timeout``) and its value in
the current command, and the help texts of ``--ssv`` and ``--batch``."""
from __future__ import annotations

import click

from ..cosim.exchange import ALGORITHMS
from ..cosim.isolation import DEFAULT_CALL_TIMEOUT_S, ISOLATE_MODES, Isolation
from .cli_options import nonempty_path

SSV_HELP = ("Bind a parameter set (.ssv) without editing the model: COMPONENT=FILE, or a FILE "
            "whose parameter names carry the component (filter.r_pos_n); repeatable, later "
            "over earlier, --set over all.")

BATCH_HELP = ("Runs of one filter stepped together as one batch on the direct backend "
              "(default: chosen from the runs, the workers and the free memory; 1: one "
              "run at a time). Every run's numbers are those of its single run.")


def common_run_options(f):
    """The options of a run (``run``, ``compare``), the isolation's included."""
    f = click.option("--out", "out", type=click.Path(file_okay=False), callback=nonempty_path,
                     help="Output folder (default: navfmu-results/<scenario>).")(f)
    f = click.option("--stop", "stop", type=float, help="Stop time [s] (default: the SSD's).")(f)
    f = click.option("--backend", type=click.Choice(["fmu", "direct"]), default="fmu",
                     show_default=True, help="Run the FMUs, or the navcore objects directly.")(f)
    f = click.option("--window", help="Metric window t0:t1 [s] (default: the whole run).")(f)
    f = click.option("--set", "sets", multiple=True, metavar="COMP.VAR=VALUE",
                     help="Override a parameter (repeatable).")(f)
    f = click.option("--ssv", "ssv", multiple=True, metavar="[COMPONENT=]FILE",
                     help=SSV_HELP)(f)
    f = click.option("--format", "fmt", type=click.Choice(["csv", "npz", "parquet"]),
                     default="csv", show_default=True,
                     help="Result file format; parquet streams the rows to disk while the run "
                     "goes (memory flat in the flight length).")(f)
    f = click.option("--no-plots", is_flag=True, help="Do not write PNG plots.")(f)
    f = click.option("--replay", "replay", type=click.Path(), callback=nonempty_path,
                     help="Replace the scenario's sensor components (trajectory/IMU, GNSS "
                     "receiver) by ImuGnssReplay playing this sensor-log folder (--stop is "
                     "then in the log's time).")(f)
    f = click.option("--start", "start", type=float, expose_value=False,
                     callback=lambda ctx, _, v: ctx.meta.__setitem__("start_time", v),
                     help="With --replay: start at the first IMU interval beginning at or "
                     "after this time of the log [s].")(f)
    f = click.option("--max-dt-jitter", "max_dt_jitter", type=float, expose_value=False,
                     callback=lambda ctx, _, v: ctx.meta.__setitem__("max_dt_jitter", v),
                     help="With --replay: largest relative deviation of an IMU interval from "
                     "the log's median interval (default 0.75).")(f)
    f = click.option("--algorithm", type=click.Choice(ALGORITHMS), default=ALGORITHMS[0],
                     show_default=True, expose_value=False,
                     callback=lambda ctx, _, v: ctx.meta.__setitem__("algorithm", v),
                     help="Exchange: Gauss-Seidel order, or Jacobi (libcosim's).")(f)
    return isolation_options(f)


def isolation_options(f):
    """``--isolate`` and ``--call-timeout``, kept in the context for :func:`isolation`."""
    f = click.option("--isolate", type=click.Choice(ISOLATE_MODES), default=ISOLATE_MODES[0],
                     show_default=True, expose_value=False,
                     callback=lambda ctx, _, v: ctx.meta.__setitem__("isolate", v),
                     help="Run FMUs in a host process of their own: the foreign ones (not "
                     "this installation's build), always, or never; a crash or hang there "
                     "ends the run with one error line.")(f)
    f = click.option("--call-timeout", type=float, default=DEFAULT_CALL_TIMEOUT_S,
                     show_default=True, expose_value=False,
                     callback=lambda ctx, _, v: ctx.meta.__setitem__("call_timeout", v),
                     help="Longest one FMI call of an FMU in a host process may take [s] "
                     "before it counts as hung and is killed.")(f)
    return f


def isolation():
    """The ``--isolate`` / ``--call-timeout`` of the current command."""
    meta = click.get_current_context().meta
    return Isolation(meta.get("isolate", ISOLATE_MODES[0]),
                     meta.get("call_timeout", DEFAULT_CALL_TIMEOUT_S))
