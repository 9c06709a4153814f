"""``navfmu verify``: a navigation FMU (ours or not) through the FMI, contract, consistency
and robustness checks of its role, with a verdict per check (``verify``).

Wing order: imports ``campaigns`` and the wings below it; imported by ``cli`` only.
"""
