"""The nonlinear kiln-drive plant, declared once as CasADi components.

>>> from kilnctl.model import component_names
>>> component_names("macro")[:3]
('ramp', 'pid', 'voltage_limit')
"""

from __future__ import annotations

import importlib
import pkgutil

from ..errors import ModelError, close_matches_hint, name_list
from . import drive, drivetrain, kiln, effects  # noqa: F401  (register the components)
from . import ramps, smooth  # noqa: F401  (reference profiles and smoothed components for optimization)

#: modules of this package that hold no components
_MACHINERY = ("assembly", "base", "catalogue", "compiled", "stepper")
# every other module is a component file: importing it registers its components (a new effect is one new file)
for _mod in pkgutil.iter_modules(__path__):
    if _mod.name not in _MACHINERY:
        importlib.import_module(f"{__name__}.{_mod.name}")

from .assembly import Plant, get_plant  # noqa: E402  (after the components: the parameter table is complete)
from .base import REGISTRY, Component, Guard, StateVar, register

__all__ = ["MODELS", "ORDER", "component_names", "phase_rank", "Plant", "get_plant", "REGISTRY", "Component", "Guard",
           "StateVar", "register", "describe_components"]

#: phase order of the components: signals flow from the ramp to the stress
ORDER: tuple[str, ...] = (
    "ramp", "speed_sensor_lag", "speed_sensor_filter", "speed_sensor_delay", "pid", "voltage_limit", "dc_motor",
    "current_limit", "second_motor", "gearbox", "drivetrain_compliance", "coupling", "pinion", "mesh",
    "kiln", "kiln_fixed", "bearing_friction", "viscous_drag", "kiln_unbalance", "burden", "bending_stress",
)

_RANK = {nm: i for i, nm in enumerate(ORDER)}

#: the paper's two models as component lists
MODELS: dict[str, tuple[str, ...]] = {
    # macro model (eqs. 1-21): rigid reducer, burden stick-slip, drive limits
    "macro": ("ramp", "pid", "voltage_limit", "dc_motor", "current_limit", "gearbox", "kiln",
              "bearing_friction", "burden", "bending_stress"),
    # micro model (eqs. 26-34): coupling, pinion, mesh with backlash
    "micro": ("ramp", "pid", "voltage_limit", "dc_motor", "current_limit", "coupling", "pinion", "mesh",
              "kiln", "bearing_friction", "burden", "bending_stress"),
}


def component_names(model: str = "macro", add=(), remove=()) -> tuple[str, ...]:
    """Return the component list of a model with effects added or removed.

    Parameters
    ----------
    model : {'macro', 'micro'}
        Base model of the paper.
    add : sequence of str
        Components to add; one that ``replaces`` others removes them.
    remove : sequence of str
        Components to take out.

    Returns
    -------
    tuple of str
        Component names in phase order.

    Raises
    ------
    ModelError
        Unknown model or component name (with close matches).
    """
    if model not in MODELS:
        raise ModelError(f"unknown model {model!r}: {close_matches_hint(model, MODELS)}")
    names = list(MODELS[model])
    add, remove = name_list(add, "effects", ModelError), name_list(remove, "remove", ModelError)
    for nm in list(add) + list(remove):
        if nm not in REGISTRY:
            raise ModelError(f"unknown component {nm!r}: {close_matches_hint(nm, REGISTRY)}")
    for nm in remove:
        if nm not in names:
            raise ModelError(f"component {nm!r} is not in the {model} model, so it cannot be removed")
        names.remove(nm)
    for nm in add:
        for rep in REGISTRY[nm].replaces:
            if rep in names:
                names.remove(rep)
        if nm not in names:
            names.append(nm)
    return tuple(sorted(names, key=phase_rank))


def phase_rank(name: str) -> float:
    """Phase rank of a component: its place in ORDER; reference profiles (``ramp_*``) right after
    ``ramp``, smoothed variants (``*_smooth``) at the place of the component they smooth, a component
    with ``phase_after`` right after that one, others just before ``bending_stress``."""
    rank = _RANK
    if name in rank:
        return rank[name]
    after = getattr(REGISTRY.get(name), "phase_after", None)
    if after in rank:
        return rank[after] + 0.25
    if name.startswith("ramp_"):
        return rank["ramp"] + 0.5
    if name.endswith("_smooth") and name[: -len("_smooth")] in rank:
        return rank[name[: -len("_smooth")]]
    return rank["bending_stress"] - 0.5


def describe_components() -> list[dict]:
    """Return name, summary, parameters and documentation of every component."""
    return [{"name": c.name, "summary": c.summary, "params": list(c.param_names),
             "modes": list(c.modes), "doc": (c.__doc__ or "").strip()} for c in REGISTRY.values()]
