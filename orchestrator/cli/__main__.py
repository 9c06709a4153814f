"""``python -m orchestrator.cli``: the ``navfmu`` command line."""
from .commands import main

main()
