"""Errors a user of the master can act on.

Every error the master raises on purpose derives from :class:`NavfmuError`, the root of the
one hierarchy, defined in :mod:`navcore.errors` (navcore ships inside the FMUs and must not
import the master); the command line prints its message (no traceback) and exits with a
non-zero status.  Any other exception is a bug and keeps its traceback.
"""
from __future__ import annotations

from navcore.errors import NavfmuError


class SspError(NavfmuError):
    """A system structure file (.ssd/.ssv) is malformed or uses something unsupported.

    The message names the file and the element or attribute.
    """


class WiringError(NavfmuError):
    """A connection or parameter names a component or variable that does not exist (or has the
    wrong causality/type), e.g. after swapping a component's FMU."""


class SimulationError(NavfmuError):
    """A component failed while running (FMU status Error/Discard/Fatal, or a component raised).

    The message names the component and the simulation time and includes the component's log.
    ``component``, ``time`` and ``log`` keep the details for programs.
    """

    def __init__(self, message: str, component: str = "", time: float | None = None,
                 log: tuple[str, ...] = ()):
        super().__init__(message)
        self.component = component
        self.time = time
        self.log = tuple(log)


class SimulationTerminated(SimulationError):
    """A component asked to end the simulation (FMI 3.0 ``terminateSimulation``): the master
    stops there and keeps what it recorded (rule 9 of :mod:`orchestrator.cosim.master`)."""


class NavfmuWarning(UserWarning):
    """Something the user should know and can act on, though the command goes on (e.g. a
    scenario parameter the swapped-in filter does not have).  The command line prints each
    as one ``navfmu: warning: ...`` line (:mod:`orchestrator.cli.user_warnings`)."""


class SkippedParametersWarning(NavfmuWarning):
    """The system structure sets parameters a swapped-in component does not have (skipped);
    commands that swap every filter into every scenario on their own (``report``) expect it."""


__all__ = ["NavfmuError", "SspError", "WiringError", "SimulationError", "SimulationTerminated",
           "NavfmuWarning",
           "SkippedParametersWarning"]
