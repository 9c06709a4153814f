"""``--ssv``: parameter sets (``.ssv`` files) bound to a scenario's components from the
command line, without editing the model.

An item is ``COMPONENT=FILE`` (the file's parameter names are the component's, as in the
``filter.ssv`` that ``navfmu convert kf-gins --config`` writes) or ``FILE`` whose parameter
names carry the component (``filter.r_pos_n``).  Items apply in their order, a later one over
an earlier one, all of them over the model's own bindings; ``--set`` applies over them.  They
become the run's parameter overrides (``{"component.parameter": value}``), so the master
checks every name against the component's FMU like a ``--set``.  A Real given with a
``unit`` is converted here to the unit of the variable in the component's FMU as the model
names it (before a ``--filter`` swap: our filters share one contract), or refused by name
(:mod:`orchestrator.model.units`).
"""
from __future__ import annotations

from pathlib import Path
from typing import Dict, Sequence, Tuple

from ..errors import NavfmuError
from ..model.ssp import SystemModel, read_ssv
from ..model.suggestions import did_you_mean
from ..model.units import convert


def split_item(item: str) -> Tuple[str, Path]:
    """``COMPONENT=FILE`` -> (component, file); ``FILE`` -> ("", file).  A whole item naming
    an existing file is a file even when its name holds a '='."""
    text = str(item)
    component, sep, file = text.partition("=")
    if not text.strip():
        raise NavfmuError("--ssv: empty path; give an .ssv file or COMPONENT=FILE")
    if sep and not Path(text).is_file():
        if not component.strip() or not file.strip():
            raise NavfmuError(f"--ssv {text}: expected COMPONENT=FILE or FILE")
        return component.strip(), Path(file.strip())
    return "", Path(text)


def _read(item: str, path: Path, units=None) -> Dict[str, Tuple[str, object]]:
    if not path.is_file():
        raise NavfmuError(f"--ssv {item}: file not found ({path})")
    return read_ssv(path, units)


def _variable_units(model: SystemModel, component: str) -> Dict[str, str]:
    """variable -> unit of ``component``'s FMU (or, not built, its navcore component)."""
    from ..cosim.component_description import describe_direct, describe_fmu
    from .scenarios import registry

    spec = model.component(component)
    described = (describe_fmu(spec) if spec.source.is_file()
                 else describe_direct(spec, registry()))
    return {name: v.unit for name, v in described.variables.items()}


def _in_variable_units(item: str, model: SystemModel, bound, units: Dict[str, str]):
    """``bound`` with each value given in a unit converted to its variable's unit."""
    targets: Dict[str, Dict[str, str]] = {}
    for key, unit in units.items():
        comp, _, name = key.partition(".")
        if comp not in targets:
            targets[comp] = _variable_units(model, comp)
        if name in targets[comp]:       # an unknown name is refused by the master, by name
            typ, value = bound[key]
            bound[key] = (typ, convert(value, unit, targets[comp][name],
                                       f"--ssv {item}: parameter '{key}' = {value!r} {unit}"))
    return bound


def read_bindings(items: Sequence[str], model: SystemModel) -> Dict[str, Tuple[str, object]]:
    """The ``--ssv`` items as ``{"component.parameter": (type, value)}``, each component one
    of ``model``'s (refused by name otherwise, with the names close to it)."""
    names = [c.name for c in model.components]
    bound: Dict[str, Tuple[str, object]] = {}
    for item in items:
        component, path = split_item(item)
        file_units: Dict[str, str] = {}
        values = _read(item, path, file_units)
        if component and component not in names:
            raise NavfmuError(f"--ssv {item}: {model.path} has no component '{component}' "
                              f"(components: {', '.join(names)}){did_you_mean(component, names)}")
        for key in values:
            if not component:
                comp, dot, _ = key.partition(".")
                if not dot:
                    raise NavfmuError(
                        f"--ssv {item}: parameter '{key}' names no component; bind the file "
                        f"to one with --ssv COMPONENT={item} (components: {', '.join(names)})")
                if comp not in names:
                    raise NavfmuError(
                        f"--ssv {item}: parameter '{key}': {model.path} has no component "
                        f"'{comp}' (components: {', '.join(names)}){did_you_mean(comp, names)}")
        prefix = f"{component}." if component else ""
        typed = {prefix + k: v for k, v in values.items()}
        bound.update(_in_variable_units(item, model, typed,
                                        {prefix + k: u for k, u in file_units.items()}))
    return bound


def read_fmu_bindings(items: Sequence[str]) -> Dict[str, object]:
    """The ``--ssv`` items of one FMU (``navfmu verify``): ``{parameter: value}``; a
    ``COMPONENT=`` prefix is allowed and dropped (there is one component)."""
    values: Dict[str, object] = {}
    for item in items:
        _, path = split_item(item)
        units: Dict[str, str] = {}
        values.update({k: v for k, (_, v) in _read(item, path, units).items()})
        for key, unit in units.items():
            raise NavfmuError(f"--ssv {item}: parameter '{key}' is given in '{unit}'; navfmu "
                              "verify takes the values in the FMU's own units (leave out the "
                              "unit attribute)")
    return values


def overrides(items: Sequence[str], model: SystemModel, sets=None) -> Dict[str, object]:
    """The parameter overrides of a run: the ``--ssv`` items' values, then ``sets``
    (``--set``, ``{"component.parameter": value}``) over them."""
    values = {k: v for k, (_, v) in read_bindings(items, model).items()}
    values.update(sets or {})
    return values


def _ssp_type(value) -> str:
    return ("Boolean" if isinstance(value, bool) else "Integer" if isinstance(value, int)
            else "Real" if isinstance(value, float) else "String")


def bind_overrides(model: SystemModel, values) -> SystemModel:
    """``model`` with ``values`` (``{"component.parameter": value}``) among its components'
    bindings, as if its .ssd bound them last: what a command that reads the bindings (the
    tuner's current values and its tuned set) sees of ``--ssv``."""
    import dataclasses

    by_component: Dict[str, Dict[str, Tuple[str, object]]] = {}
    for key, value in dict(values).items():
        comp, _, name = key.partition(".")
        by_component.setdefault(comp, {})[name] = (_ssp_type(value), value)
    components = [dataclasses.replace(c, parameters={**c.parameters,
                                                     **by_component.get(c.name, {})})
                  for c in model.components]
    return dataclasses.replace(model, components=components)


__all__ = ["split_item", "read_bindings", "read_fmu_bindings", "overrides", "bind_overrides"]
