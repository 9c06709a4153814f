"""The seeds of a campaign's runs (the rule in :mod:`orchestrator.campaigns.campaign`).

Every component with an Integer parameter ``seed`` is a random source; in run ``i`` of a
campaign with seed ``s`` it gets ``seed = s + i + offset``, its offset given by
``--seed-offset COMP=K`` or, by default, :data:`SEED_STRIDE` times its place among the random
components.  ``spec`` below is the campaign's
:class:`~orchestrator.campaigns.campaign.CampaignSpec`.
"""
from __future__ import annotations

from typing import Dict, List, Tuple

from ..errors import NavfmuError

#: default distance between the seeds of two random components of one run
SEED_STRIDE = 1000


def random_components(model, backend: str, parameters=None) -> List[str]:
    """Components with an Integer parameter ``seed``, in declaration order (``parameters``:
    the overrides, checked against the components here)."""
    from ..cosim.master import Simulation
    from ..running.scenarios import registry

    sim = Simulation(model, backend=backend, registry=registry() if backend == "direct" else None,
                     parameters=dict(parameters or {}))
    return [d.spec.name for d in sim.components
            if (v := d.variables.get("seed")) is not None and v.type == "Integer"
            and v.causality == "parameter"]


def check_no_seed_override(spec, components: List[str]) -> None:
    """A campaign gives every random component its seed (module docstring): a ``seed``
    parameter set by ``--set`` or ``--ssv`` would be replaced in every run, so it is
    refused, with the options that choose the seeds."""
    for key, value in spec.parameters:
        comp, _, name = key.partition(".")
        if name == "seed" and comp in components:
            raise NavfmuError(
                f"--set {key}={value}: a campaign gives each random component its seed (run "
                f"i: --seed + i + the component's offset); choose them with --seed and "
                f"--seed-offset {comp}=K instead")


def seed_offsets(spec, components: List[str]) -> Dict[str, int]:
    """Offset of every random component (see the module docstring)."""
    given = dict(spec.seed_offsets)
    unknown = sorted(set(given) - set(components))
    if unknown:
        raise NavfmuError(f"--seed-offset: no random component {', '.join(unknown)} (random "
                          f"components: {', '.join(components) or 'none'})")
    return {c: int(given.get(c, SEED_STRIDE * j)) for j, c in enumerate(components)}


def parse_seed_offsets(items) -> Tuple[Tuple[str, int], ...]:
    """``["gnss=100", ...]`` (``--seed-offset``) as ``(("gnss", 100), ...)``."""
    offsets = []
    for item in items:
        comp, sep, value = item.partition("=")
        try:
            offsets.append((comp, int(value)))
        except ValueError:
            sep = ""
        if not sep or not comp:
            raise NavfmuError(f"--seed-offset: expected COMP=integer, got {item!r}")
    return tuple(offsets)


def check_seed_range(spec, offsets: Dict[str, int], runs: int) -> None:
    """Every run's seeds must fit an FMI Integer (checked before the campaign starts)."""
    from ..cosim.backends import FMI_INTEGER_MAX, FMI_INTEGER_MIN

    for index in (0, runs - 1):
        for comp, value in run_seeds(spec, offsets, index).items():
            if not FMI_INTEGER_MIN <= value <= FMI_INTEGER_MAX:
                raise NavfmuError(
                    f"--seed {spec.seed}: run {index} would give {comp}.seed = {value}, which "
                    f"does not fit an FMI Integer ({FMI_INTEGER_MIN} .. {FMI_INTEGER_MAX})")


def run_seeds(spec, offsets: Dict[str, int], index: int) -> Dict[str, int]:
    return {c: spec.seed + index + off for c, off in offsets.items()}
