"""``navfmu package`` and ``navfmu export``: a scenario written as one self-contained SSP
archive or as one co-simulation FMU, its stale FMUs built first and its initialization checked,
by the writers of :mod:`orchestrator.packaging`."""
from __future__ import annotations

import click

from .cli_options import nonempty_path


def write_system(scenario, out, module_name, **options):
    """Build the model's stale FMUs, then write it with ``orchestrator.packaging.<module_name>``
    (``options``: its keyword arguments)."""
    import importlib

    from ..running import scenarios
    from ..results.outputs import check_writable

    from ..running.prechecks import check_initializes

    check_writable(out, "--out")
    model = scenarios.load_scenario(scenario)
    scenarios.ensure_fmus(model, log=lambda m: click.echo(m, err=True))
    check_initializes(model)        # a value its FMU refuses is not packaged
    writer = importlib.import_module(f"..packaging.{module_name}", __package__)
    click.echo(f"wrote {getattr(writer, module_name)(scenario, out, **options)}")


def system_command(name, what, doc, options=()):
    """``navfmu <name> SCENARIO --out FILE``: write the model as ``what``; ``options``: click
    options of this command, passed on to its writer."""
    def command(scenario, out, **kwargs):
        write_system(scenario, out, name, **kwargs)

    command.__doc__ = doc
    for option in options:
        command = option(command)
    command = click.option("--out", required=True, type=click.Path(dir_okay=False),
                           callback=nonempty_path,
                           help=f"The {what} to write.")(command)
    command = click.argument("scenario", type=click.Path(), callback=nonempty_path)(command)
    return click.command(name=name)(command)


package = system_command("package", "SSP archive (.ssp)",
                          "Write SCENARIO as one self-contained SSP archive (FMUs under "
                          "resources/).",
                          options=[click.option(
                              "--step-hints/--no-step-hints", default=True,
                              help="Keep the components' osp:StepSizeHint (default: libcosim "
                                   "and navfmu run honour them) or leave them out, for SSP "
                                   "readers that refuse annotations on a component "
                                   "(OMSimulator); then every component steps at the base "
                                   "step.")])
export = system_command("export", "FMU (.fmu)",
                         "Write SCENARIO as one co-simulation FMU (fmpy's container, Jacobi at "
                         "the base step).")
