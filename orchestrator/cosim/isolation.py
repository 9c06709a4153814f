"""Which FMUs the master runs in a host process of their own, and how long it waits for
one FMI call there.

``mode`` (``navfmu run --isolate``):

* ``foreign`` (the default): every foreign FMU (:mod:`orchestrator.model.fmu_origin`: not
  byte for byte this installation's build of its model) in a host process of its own
  (:mod:`orchestrator.cosim.hosted_instance`), ours in the master's process;
* ``always``: every FMU in a host process of its own;
* ``never``: every FMU in the master's process (a crash of one then ends navfmu).

``call_timeout`` (``--call-timeout``): the longest one call into a hosted FMU may take
(instantiation, initialization, one communication step) before the FMU counts as hung and
its host is killed.  The default, :data:`DEFAULT_CALL_TIMEOUT_S`, leaves room for an FMU that
compiles or loads data in its first call, on a loaded machine.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from ..errors import NavfmuError
from ..model.fmu_origin import is_foreign

#: the accepted modes, the default first
ISOLATE_MODES = ("foreign", "always", "never")
#: longest one FMI call into a hosted FMU may take [s]
DEFAULT_CALL_TIMEOUT_S = 120.0


@dataclass(frozen=True)
class Isolation:
    """Where the FMUs run (the module docstring)."""

    mode: str = ISOLATE_MODES[0]
    call_timeout: float = DEFAULT_CALL_TIMEOUT_S

    def __post_init__(self):
        if self.mode not in ISOLATE_MODES:
            raise NavfmuError(f"--isolate: expected {', '.join(ISOLATE_MODES)}, got "
                              f"{self.mode!r}")
        if not (isinstance(self.call_timeout, (int, float)) and math.isfinite(self.call_timeout)
                and self.call_timeout > 0):
            raise NavfmuError(f"--call-timeout: expected a positive finite number of "
                              f"seconds, got {self.call_timeout!r}")

    def hosts(self, path, model_name: str) -> bool:
        """Whether the FMU ``path`` (of model ``model_name``) runs in a host process."""
        if self.mode == "foreign":
            return is_foreign(path, model_name)
        return self.mode == "always"


__all__ = ["Isolation", "ISOLATE_MODES", "DEFAULT_CALL_TIMEOUT_S"]
