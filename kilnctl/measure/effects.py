"""The effect catalogue: physical effects a user can add to the model, and what each explains.

Each :class:`Effect` says what physics it stands for, which components or
options of :mod:`kilnctl.model` it adds, which parameters it brings (with
bounds and initial guesses for calibration) and the **residual signature**
it explains: the pattern a comparison shows when the effect is in the kiln
but not in the model.  :class:`~kilnctl.measure.diagnose.Diagnosis` tries
them one by one.

The entries are declared by the components themselves (their ``catalogue``,
next to their equations and parameters); :data:`CATALOGUE` is derived from
the registry, so a new component file brings its entry with it.

>>> from kilnctl.measure.effects import CATALOGUE
>>> sorted(CATALOGUE)[:3]
['backlash', 'current_limit', 'drivetrain_compliance']
>>> CATALOGUE["second_motor"].components
('second_motor',)
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import ModelError, close_matches_hint
from ..model.catalogue import Effect, FreeParameter
from ..params import SPECS, Parameters, RegistryView

__all__ = ["FreeParameter", "Effect", "CATALOGUE", "BASE_PARAMETERS", "DEFAULT_CALIBRATE", "free_parameter",
           "effect_components", "grid_starts"]


#: bounds and scales of the base parameters a user may calibrate (others get a default, see free_parameter)
BASE_PARAMETERS: dict[str, FreeParameter] = {
    "mu_c": FreeParameter("mu_c", 0.02, 1.5, "lin", 0.4),
    "mu_s": FreeParameter("mu_s", 0.02, 2.0, "lin", 0.5),
    "m_v": FreeParameter("m_v", 1e4, 1e7, "log", 5.8e5),
    "J_v": FreeParameter("J_v", 1e4, 1e8, "log", 1.7e6),
    "J_o": FreeParameter("J_o", 1e5, 1e9, "log", 7e6),
    "J_m": FreeParameter("J_m", 1.0, 500.0, "log", 21.5),
    "L": FreeParameter("L", 0.05, 5.0, "lin", 1.35),
    "R": FreeParameter("R", 0.2, 6.0, "lin", 2.2),
    "k_i": FreeParameter("k_i", 0.5, 50.0, "log", 4.6),
    "k_b": FreeParameter("k_b", 0.5, 50.0, "log", 4.6),
    "psi_0": FreeParameter("psi_0", -1.5, 1.5, "lin", 0.5),
    "mu_brg": FreeParameter("mu_brg", 0.0, 0.1, "lin", 0.001),
}


#: base parameters calibrated by default (Calibration, Diagnosis, the example, ``kilnctl diagnose``): the paper's
#: friction study (Fig. 4) plus the burden mass and inertia (the paper blames both for its mismatch of the
#: oscillation frequency)
DEFAULT_CALIBRATE = ("mu_c", "mu_s", "m_v", "J_v")


def free_parameter(name: str, params: Parameters | None = None) -> FreeParameter:
    """Return the calibration declaration of a parameter.

    Known ones come from :data:`BASE_PARAMETERS` or the catalogue; any other
    numeric parameter gets log bounds [value/10, value*10] (positive) or a
    linear range of +-(|value| + 1).

    Parameters
    ----------
    name : str
        Parameter name.
    params : Parameters, optional
        Current values (for the default bounds).

    Returns
    -------
    FreeParameter

    Raises
    ------
    ModelError
        Unknown or non-numeric parameter (with close matches).
    """
    if name in BASE_PARAMETERS:
        return BASE_PARAMETERS[name]
    for eff in CATALOGUE.values():
        for fp in eff.parameters:
            if fp.name == name:
                return fp
    numeric = [k for k, s in SPECS.items() if not s.is_option]
    if name not in numeric:
        raise ModelError(f"cannot calibrate {name!r}: {close_matches_hint(name, numeric)}")
    v = float((params or Parameters())[name])
    spec = SPECS[name]
    if v > 0 and spec.rule == "positive":
        return FreeParameter(name, v / 10, v * 10, "log", v)
    return FreeParameter(name, v - abs(v) - 1, v + abs(v) + 1, "lin", abs(v) or 1.0)


def grid_starts(parameters, n: int = 24) -> list[dict]:
    """A coarse grid over an effect's parameters, for the global phase of a refit.

    ``log`` parameters: geometric between max(lower, typical/100) and
    min(upper, 100 typical); ``lin``: from the lower bound to
    min(upper, 10 typical); ``polar``: amplitudes typical/10 ... 10 typical at
    eight phases.  Two parameters are crossed on a coarser grid.

    Parameters
    ----------
    parameters : sequence of FreeParameter
        The effect's parameters.
    n : int, default 24
        Points per parameter for one parameter (about sqrt(4n) each for two).

    Returns
    -------
    list of dict
        Parameter values [units of each].
    """
    if not parameters or n <= 0:
        return []
    axes = []
    per = n if len(parameters) == 1 else max(4, int(round(math.sqrt(4 * n))))
    for fp in parameters:
        if fp.kind == "polar":
            amps = np.geomspace(fp.typical / 10, min(fp.upper, 10 * fp.typical), 6)
            axes.append([{fp.name: float(a), fp.partner: float(ph)} for a in amps
                         for ph in np.arange(8) * (2 * math.pi / 8)])
        else:
            axes.append([{fp.name: v} for v in fp.grid(per)])
    out = [{}]
    for ax in axes:
        out = [dict(a, **b) for a in out for b in ax]
    return out


def _catalogue(registry) -> dict[str, Effect]:
    """The entries every registered component declares (its own ``catalogue``, not inherited ones)."""
    out: dict[str, Effect] = {}
    for comp in registry.values():
        for eff in vars(comp).get("catalogue", ()):
            if eff.name in out:
                raise ModelError(f"catalogue entry {eff.name!r} is declared twice (component {comp.name!r})")
            out[eff.name] = eff
    return out


#: the effect catalogue, by name: derived from the components of kilnctl.model, in registration order
CATALOGUE: RegistryView = RegistryView(_catalogue)


def effect_components(names, params: Parameters, model: str = "macro") -> tuple[tuple[str, ...], Parameters]:
    """Translate catalogue or component names into components and parameter options.

    Parameters
    ----------
    names : sequence of str
        Catalogue names (``torque_friction_law`` ...) or component names of
        :mod:`kilnctl.model`.
    params : Parameters
        Base parameters.
    model : str
        Model they are added to.

    Returns
    -------
    components : tuple of str
        Components to add.
    params : Parameters
        With the effects' options set.

    Raises
    ------
    ModelError
        Unknown name, or an effect the model cannot carry (backlash on the
        macro model).
    """
    from ..model import REGISTRY

    comps: list[str] = []
    for nm in names:
        if nm in CATALOGUE:
            eff = CATALOGUE[nm]
            if eff.model is not None and eff.model != model:
                raise ModelError(f"effect {nm!r} needs the {eff.model} model (the {model} model cannot carry it); "
                                 f"use --model {eff.model}")
            if eff.options:
                params = params.replace(**eff.options)
            comps += [c for c in eff.components if c not in comps and not _in_base(c, model)]
        elif nm in REGISTRY:
            if nm not in comps and not _in_base(nm, model):
                comps.append(nm)
        else:
            raise ModelError(f"unknown effect {nm!r}: {close_matches_hint(nm, list(CATALOGUE) + list(REGISTRY))}")
    return tuple(comps), params


def _in_base(component: str, model: str) -> bool:
    from ..model import MODELS

    return component in MODELS.get(model, ())
