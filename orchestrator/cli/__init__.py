"""The ``navfmu`` command line, the master's highest wing: the commands (``commands``), option
values read into what the facades take (``cli_options``), progress bars (``progress``), ``run`` and
``compare`` (``run_command``), ``convert`` (``convert``) and ``bench`` (``bench``).

``main`` is the entry point (``navfmu`` and ``python -m orchestrator.cli``).  It is imported on
first use, so that the Ctrl-C handling is installed before numpy, fmpy and scipy load.

Wing order: imports every other wing; nothing imports it.
"""


def main(argv=None):
    """Run the ``navfmu`` command line on ``argv`` (default ``sys.argv[1:]``)."""
    from .commands import main as _main

    _main(argv)
