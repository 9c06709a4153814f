"""A system model handed on whole: one self-contained SSP archive (``package``) or one
co-simulation FMU (``export``).

Wing order: imports ``model`` and ``results``; imported by ``cli`` only.
"""
