"""The structure of a plant: which model, which physical effects, in one small object.

A :class:`Structure` names a model preset of :data:`kilnctl.model.MODELS`
(the paper's ``macro`` or ``micro`` model) and the effects added to it, by
catalogue name (:data:`kilnctl.measure.effects.CATALOGUE`: ``second_motor``,
``torque_friction_law`` ...) or component name (:data:`kilnctl.model.REGISTRY`).
It gives the component tuple the plant is assembled from
(:meth:`Structure.components`) and the parameter options the effects set
(:meth:`Structure.apply`: ``friction_law = 'torque'`` ...); iterating over
it gives the components too, so it stands where a component tuple stood
(``"mesh" in structure``, ``tuple(structure)``).  It holds no
parameter values: the calibrated values of a diagnosis travel in a
:class:`~kilnctl.params.Parameters` beside it
(:func:`kilnctl.design.learned.learned_structure`).

``simulate``, ``linearize``, ``verify``, ``check_gains`` / ``retune``,
``RampProblem`` and ``Study`` take a Structure where they take a component
tuple (``components=``); the simulator and the linearization sit below this
module and use only its methods.

>>> from kilnctl.structure import Structure
>>> s = Structure("macro").with_effects("second_motor")
>>> str(s)
'macro + second_motor'
>>> s.components()[3:7]
('dc_motor', 'current_limit', 'second_motor', 'gearbox')
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

from .errors import ConfigFileError, ModelError, close_matches_hint
from .measure.effects import CATALOGUE, effect_components
from .model import MODELS, component_names
from .params import Parameters

__all__ = ["Structure", "PRESETS", "diagnosis_dict"]


@dataclass(frozen=True)
class Structure:
    """A plant structure: a model preset plus physical effects, checked when made.

    Parameters
    ----------
    model : {'macro', 'micro'}, default 'macro'
        Model preset (:data:`kilnctl.model.MODELS`).
    effects : sequence of str
        Catalogue effects or component names to add, in order.
    remove : sequence of str
        Components of the preset to take out (``current_limit`` ...).

    Raises
    ------
    ModelError
        Unknown model, effect or component (with close matches), or an effect
        the model cannot carry (backlash on the macro model).
    """

    model: str = "macro"
    effects: tuple[str, ...] = ()
    remove: tuple[str, ...] = ()

    def __post_init__(self):
        for name in ("effects", "remove"):
            value = getattr(self, name)
            if isinstance(value, str):
                raise ModelError(f"Structure {name} = {value!r} must be a sequence of names, e.g. ({value!r},)")
            value = tuple(dict.fromkeys(value))  # duplicates once, order kept
            for v in value:
                if not isinstance(v, str):
                    raise ModelError(f"Structure {name} holds {v!r}: give effect or component names (str)")
            object.__setattr__(self, name, value)
        if self.model not in MODELS:
            raise ModelError(f"unknown model {self.model!r}: {close_matches_hint(self.model, MODELS)}")
        self.components()  # checks every name and the effects' model

    def components(self) -> tuple[str, ...]:
        """Return the component names the plant is assembled from, in phase order.

        Returns
        -------
        tuple of str
        """
        extra, _ = effect_components(self.effects, Parameters(), self.model)
        return component_names(self.model, extra, self.remove)

    def __iter__(self):
        """Iterate over the components, so a Structure stands where a component tuple stood."""
        return iter(self.components())

    def __contains__(self, name) -> bool:
        return name in self.components()

    @property
    def options(self) -> dict[str, str]:
        """Parameter options the effects set (``{"friction_law": "torque"}`` ...)."""
        out = {}
        for nm in self.effects:
            if nm in CATALOGUE:
                out.update(CATALOGUE[nm].options)
        return out

    def apply(self, params: Parameters) -> Parameters:
        """Return ``params`` with the effects' options set.

        Parameters
        ----------
        params : Parameters
            Values of the plant [units of :data:`kilnctl.params.SPECS`].

        Returns
        -------
        Parameters
        """
        options = self.options
        return params.replace(**options) if options else params

    def with_effects(self, *names: str) -> "Structure":
        """Return this structure with more effects added (those already in it are kept once).

        Parameters
        ----------
        *names : str
            Catalogue effects or component names.

        Returns
        -------
        Structure
        """
        return Structure(self.model, self.effects + tuple(names), self.remove)

    @classmethod
    def from_diagnosis(cls, source, model: str | None = None) -> "Structure":
        """Return the structure a diagnosis selected: its model with its selected effects, each in the form it
        was fitted in (the second-order filter's component for a ``speed_sensor_lag`` kept in that form).

        Parameters
        ----------
        source : path-like, dict or Diagnosis
            JSON written by ``kilnctl diagnose --json`` (or ``diagnose.json``
            of its ``--report`` folder), that JSON read into a dict, or a
            fitted :class:`~kilnctl.measure.diagnose.Diagnosis`.
        model : str, optional
            Model preset (default: the one the diagnosis used, else macro).

        Returns
        -------
        Structure

        Raises
        ------
        ConfigFileError
            The file is missing, not JSON, or not a diagnosis.
        """
        d = diagnosis_dict(source)
        forms = d.get("forms") or {}
        effects = []
        for e in d["selected"]:
            form = CATALOGUE[e].form(forms.get(e)) if e in CATALOGUE else None
            effects += list(form.components) if form is not None else [e]
        return cls(model or d.get("settings", {}).get("model") or "macro", tuple(effects))

    def __str__(self) -> str:
        text = " + ".join((self.model,) + self.effects)
        if self.remove:
            text += "".join(f" - {nm}" for nm in self.remove)
        options = self.options
        if options:
            text += " (" + ", ".join(f"{k} = {v!r}" for k, v in options.items()) + ")"
        return text


#: the paper's models as structures (the presets of :data:`kilnctl.model.MODELS`)
PRESETS: dict[str, Structure] = {name: Structure(name) for name in MODELS}


def diagnosis_dict(source) -> dict:
    """Return a diagnosis as the dictionary ``kilnctl diagnose --json`` writes.

    Parameters
    ----------
    source : path-like, dict or Diagnosis
        The JSON file, its content, or a fitted diagnosis (its ``to_dict()``).

    Returns
    -------
    dict
        With at least ``selected`` (list of effect names) and
        ``final_parameters`` (``{name: {"value": v, ...}}``, values in the
        units of :data:`kilnctl.params.SPECS`).

    Raises
    ------
    ConfigFileError
        The file is missing, not JSON, or not a diagnosis.
    """
    where = "the diagnosis"
    if hasattr(source, "to_dict") and not isinstance(source, dict):
        d = source.to_dict()
    elif isinstance(source, dict):
        d = source
    else:
        path = Path(source)
        where = f"--model-from {path}"
        try:
            d = json.loads(path.read_text())
        except (OSError, UnicodeDecodeError) as exc:
            raise ConfigFileError(f"{where}: cannot read it ({exc.__class__.__name__}): give the JSON that "
                                  "'kilnctl diagnose --json' printed, saved to a file") from None
        except ValueError as exc:
            raise ConfigFileError(f"{where}: not JSON ({exc}): give the JSON that 'kilnctl diagnose --json' "
                                  "printed") from None
    if not isinstance(d, dict) or "selected" not in d or "final_parameters" not in d:
        raise ConfigFileError(f"{where}: not a diagnosis (no 'selected' / 'final_parameters'): give the JSON "
                              "that 'kilnctl diagnose --json' printed")
    return d
