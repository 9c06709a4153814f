"""The checks a system model passes before it runs (rule 8 of :mod:`orchestrator.cosim.master`).

:class:`ModelChecks` is the part of :class:`~orchestrator.cosim.master.Simulation` that looks
at the model and the components' descriptions only, nothing run: every component's decimation
(rule 2), every connection's variables, causalities, types and units, the SSD parameters and the
user's overrides (bound, converted, skipped after a swap, or refused), and the selection of the
recorded outputs.  Each refusal is a :class:`~orchestrator.errors.WiringError` or
:class:`~orchestrator.errors.NavfmuError` naming the component, the variable and the FMU file.
"""
from __future__ import annotations

import warnings
from typing import Any, Dict, Iterable, List, Mapping, Optional, Tuple

from navcore.core.timing import TIME_TOLERANCE

from .backends import NUMERIC_TYPES
from ..errors import NavfmuError, SkippedParametersWarning, WiringError
from ..model.ssp import ComponentSpec, Connection
from ..model import units
from ..model.suggestions import did_you_mean

#: the types a parameter value can be set to
SETTABLE_TYPES = ("Real", "Integer", "Enumeration", "Boolean", "String")


def _parameter_hint(d, name: str) -> str:
    """The component's parameters close to the unknown ``name``, or all of them."""
    names = sorted(v.name for v in d.variables.values() if v.causality == "parameter")
    return did_you_mean(name, names) or f" (its parameters: {', '.join(names)})"


def _check_settable(d, var) -> None:
    """Refuse setting a parameter of a type no parameter value maps onto (an FMI 3.0
    Float32, UInt8, array...: :mod:`orchestrator.cosim.fmi3_variables`)."""
    if var.type not in SETTABLE_TYPES:
        raise WiringError(f"component '{d.spec.name}' ({d.source}): parameter '{var.name}' has "
                          f"type {var.type}, which cannot be set (settable: "
                          f"{', '.join(SETTABLE_TYPES)})")


class ModelChecks:
    """The model's checks, as methods of the simulation that runs it: they read its
    ``model``, ``base_step``, ``components``, ``names`` and ``_index``."""

    def _decimation(self, spec: ComponentSpec) -> int:
        if spec.step_hint is None:
            return 1
        ratio = spec.step_hint / self.base_step
        n = int(round(ratio))
        if n < 1 or abs(ratio - n) > TIME_TOLERANCE * ratio:
            raise NavfmuError(f"component '{spec.name}': its step {spec.step_hint} s is not an "
                              f"integer multiple of the base step {self.base_step} s")
        return n

    def _check_wiring(self) -> None:
        for conn in self.model.connections:
            for comp_name, var_name, causality in (
                    (conn.start_component, conn.start_connector, "output"),
                    (conn.end_component, conn.end_connector, "input")):
                d = self.components[self._index[comp_name]]
                var = d.variables.get(var_name)
                where = f"component '{comp_name}' ({d.source})"
                if var is None:
                    raise WiringError(f"{where} has no variable '{var_name}', which the connection "
                                      f"{conn} needs")
                if var.causality != causality:
                    raise WiringError(f"{where}: variable '{var_name}' has causality "
                                      f"'{var.causality}', but the connection {conn} needs an "
                                      f"{causality}")
                declared = d.spec.connectors.get(var_name, (None, None))[1]
                if declared is not None and var.type != declared:
                    raise WiringError(f"{where}: variable '{var_name}' is a {var.type}, but the "
                                      f"system structure declares it as {declared} "
                                      f"(connection {conn})")
                if var.type not in NUMERIC_TYPES:
                    raise WiringError(f"{where}: variable '{var_name}' is a {var.type}; only Real, "
                                      f"Integer and Boolean variables can be connected")
                units.check_same(d.spec.units.get(var_name, ""), var.unit,
                                 f"{where}: the system structure's connector '{var_name}' "
                                 "against the FMU's variable")
            self._check_connection_units(conn)

    def _check_connection_units(self, conn: Connection) -> None:
        """Both ends of ``conn`` in one unit (rule 8: the value passes unchanged)."""
        ends = [self.components[self._index[c]].variables[v] for c, v in (
            (conn.start_component, conn.start_connector),
            (conn.end_component, conn.end_connector))]
        units.check_same(ends[0].unit, ends[1].unit, f"connection {conn}")

    def _parameters(self, overrides: Mapping[str, Any]):
        values: Dict[str, Dict[str, Any]] = {n: {} for n in self.names}
        skipped: List[str] = []
        settable = ("parameter", "input")
        for d in self.components:
            swapped = d.spec.name in self.model.replaced_sources
            for pname, (_, value) in d.spec.parameters.items():
                var = d.variables.get(pname)
                if var is None or var.causality not in settable:
                    if swapped and pname not in d.spec.variant_parameters:
                        skipped.append(f"{d.spec.name}.{pname}")
                        continue
                    raise WiringError(
                        f"component '{d.spec.name}' ({d.source}): the system structure sets "
                        f"parameter '{pname}', which "
                        + ("does not exist" if var is None else
                           f"has causality '{var.causality}' (not settable)")
                    )
                _check_settable(d, var)
                unit = d.spec.parameter_units.get(pname)
                if unit:
                    value = units.convert(value, unit, var.unit,
                                          f"component '{d.spec.name}' ({d.source}): parameter "
                                          f"'{pname}' = {value!r} {unit}")
                values[d.spec.name][pname] = value
        if skipped:
            warnings.warn("parameters not present in the swapped-in component(s), skipped: "
                          + ", ".join(skipped), SkippedParametersWarning, stacklevel=3)
        for key, value in overrides.items():
            comp, var_name = self._split(key, "parameter override")
            d = self.components[self._index[comp]]
            var = d.variables.get(var_name)
            if var is None or var.causality not in settable:
                raise WiringError(
                    f"parameter override '{key}': component '{comp}' ({d.source}) has no "
                    f"parameter '{var_name}'" + (_parameter_hint(d, var_name) if var is None
                                                 else f" (it is an {var.causality})")
                )
            _check_settable(d, var)
            values[comp][var_name] = value
        return values, skipped

    def _split(self, key: str, what: str) -> Tuple[str, str]:
        comp, dot, var = key.partition(".")
        if comp not in self._index:
            raise WiringError(f"{what} '{key}': no component named '{comp}' "
                              f"(components: {', '.join(self.names)})"
                              + did_you_mean(comp, self.names))
        return comp, var if dot else ""

    def _recorded(self, record: Optional[Iterable[str]]) -> Dict[str, List[str]]:
        """component -> recorded output names, in the component's variable order."""
        def outputs(d):
            return [v.name for v in d.variables.values()
                    if v.causality == "output" and v.type in NUMERIC_TYPES]

        if record is None:
            return {d.spec.name: outputs(d) for d in self.components}
        wanted: Dict[str, set] = {n: set() for n in self.names}
        for item in ([record] if isinstance(record, str) else record):
            comp, var_name = self._split(item, "record")
            d = self.components[self._index[comp]]
            if not var_name:
                wanted[comp].update(outputs(d))
                continue
            var = d.variables.get(var_name)
            if var is None or var.causality != "output" or var.type not in NUMERIC_TYPES:
                raise WiringError(f"record '{item}': component '{comp}' ({d.source}) has no "
                                  f"Real/Integer/Boolean output '{var_name}'")
            wanted[comp].add(var_name)
        return {d.spec.name: [n for n in outputs(d) if n in wanted[d.spec.name]]
                for d in self.components}
