"""``navfmu report``: the papers' tables, orderings and figures over every scenario and filter,
from one resumable campaign per scenario (``report``).

Wing order: imports ``campaigns`` and the wings below it; imported by ``cli`` only.
"""
