"""A lever arm the run cannot honour: a component given a nonzero GNSS antenna lever arm
(``lever_arm_x/y/z``, :mod:`navcore.ins.lever_arm`) that also has the truth attitude inputs
``truth_roll/pitch/yaw`` (the receiver, which rotates the lever arm into NED with them) but
has them left unconnected.  An unconnected input keeps its start value, attitude 0, so the
antenna is put north-forward whatever the heading, without any error: the master says so
once as ``navfmu: warning: ...`` (the run goes on, as a user may mean it for a test)."""
from __future__ import annotations

from typing import Any, Iterable, List, Mapping

from navcore.ins.lever_arm import LEVER_ARM_PARAMETERS

from ..model.receiver_wiring import ATTITUDE as ATTITUDE_INPUTS
LEVER_ARM_NAMES = tuple(p.name for p in LEVER_ARM_PARAMETERS)


def unconnected_lever_arms(components: Iterable, parameter_values: Mapping[str, Mapping[str, Any]],
                           connections: Iterable) -> List[str]:
    """One message per component (a :class:`~orchestrator.cosim.component_description.Described`)
    whose set lever arm (``parameter_values[name]``) needs attitude inputs no connection feeds."""
    fed = {(c.end_component, c.end_connector) for c in connections}
    messages = []
    for d in components:
        name = d.spec.name
        if not all(d.variables.get(v) is not None and d.variables[v].causality == "input"
                   for v in ATTITUDE_INPUTS):
            continue
        arm = [float(parameter_values.get(name, {}).get(p, 0.0)) for p in LEVER_ARM_NAMES]
        missing = [v for v in ATTITUDE_INPUTS if (name, v) not in fed]
        if any(arm) and missing:
            messages.append(
                f"component '{name}': its lever arm ({', '.join(f'{a:g}' for a in arm)} m) is "
                f"rotated with the attitude inputs {', '.join(missing)}, which are not "
                "connected (they stay 0: the antenna is placed as if the body pointed north "
                "and level); connect them from the truth in the system structure")
    return messages


__all__ = ["ATTITUDE_INPUTS", "unconnected_lever_arms"]
