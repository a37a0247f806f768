"""Catalogue entries: how a component tells the diagnosis what it explains and how to fit it.

A component of :mod:`kilnctl.model` lists in its ``catalogue`` the
:class:`Effect` entries it stands for (``second_motor`` ... ``backlash`` for
``mesh``, ``torque_friction_law`` for ``burden``);
:data:`kilnctl.measure.effects.CATALOGUE` is derived from the registry.  The
fitted parameters are :class:`FreeParameter` declarations (bounds, scaling).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from ..params import SPECS, Parameters

__all__ = ["FreeParameter", "Form", "Effect", "motor_scale", "motor_torque_scale", "kiln_torque_scale", "drag_scale",
           "kiln_inertia_scale"]


@dataclass(frozen=True)
class FreeParameter:
    """A parameter to calibrate, with its bounds and how it is scaled for the optimizer.

    Attributes
    ----------
    name : str
        Model parameter (:data:`kilnctl.params.SPECS`).
    lower, upper : float
        Bounds [unit of the parameter].
    kind : {'lin', 'log', 'polar'}
        ``lin``: the optimizer sees value/typical; ``log``: ln(value/typical)
        (for parameters spanning decades; lower must be > 0); ``polar``:
        an amplitude fitted with its phase ``partner`` as the Cartesian pair
        (a, b) = (A cos phi, A sin phi), which is linear in the torque and
        has no wrap-around.
    typical : float
        Scale [unit] (order of magnitude of the value).
    partner : str, optional
        Phase parameter [rad] of a ``polar`` amplitude.
    """

    name: str
    lower: float
    upper: float
    kind: str = "lin"
    typical: float = 1.0
    partner: str | None = None

    @property
    def unit(self) -> str:
        """Unit of the parameter (from its declaration)."""
        return SPECS[self.name].unit if self.name in SPECS else ""

    def grid(self, n: int) -> list[float]:
        """``n`` values over the parameter's usual span, for a coarse grid of starting points: geometric
        between max(lower, typical/100) and min(upper, 100 typical) for ``log``, even from the lower bound to
        min(upper, 10 typical) for ``lin`` [unit of the parameter]."""
        if self.kind == "log":
            return [float(v) for v in np.geomspace(max(self.lower, self.typical / 100),
                                                   min(self.upper, self.typical * 100), n)]
        return [float(v) for v in np.linspace(self.lower, min(self.upper, 10 * self.typical), n)]


@dataclass(frozen=True)
class Form:
    """Another form of an effect: other components with more parameters, tried when the effect is supported.

    A drive's speed feedback may pass a second-order filter or a transport
    delay rather than a first-order lag: the same effect (the controller
    sees the speed late), another transfer function.  The diagnosis refits
    every candidate in its own form; a supported candidate is then refitted
    in each of its forms, and judged in the best one that gives the evidence
    every candidate must give (see
    :meth:`kilnctl.measure.diagnose.Diagnosis._in_best_form`).

    Attributes
    ----------
    name : str
        Name of the form (``second_order``, ``delay``).
    meaning : str
        What it describes, in a sentence.
    components : tuple of str
        Model components that replace the effect's ``components``.
    parameters : tuple of FreeParameter
        Fitted in addition to the effect's own parameters.
    near : dict
        Values of the added parameters at which the form behaves nearly as
        the effect's own form: the refit starts there (with the effect's
        fitted values), so it ends about as well as the effect's own form at
        worst.  Empty when the added parameters are the model's own (the
        backlash's coupling): their setup values are the effect's own form.
    starts : callable
        ``starts(values) -> list of dict``: further starting points, from
        the effect's fitted values (the model's ``values``) [unit of each].
    ends : dict
        ``{parameter: 'lower' or 'upper'}``: a bound of an added parameter
        that is a physical limit of the form (the backlash's coupling
        rigid at the upper bounds of k_c and c_c), which a fit may reach
        without the form standing in for another difference.  At any other
        bound the diagnosis does not use the form.
    in_rounds : bool
        Tried in each round when the effect is a supported candidate (True),
        or only in the final check, where the form must take the place of
        another selected effect (False: a form the rounds could not tell
        from noise on a usual record).
    unsupported_too : bool
        Tried in a round also when the effect in its own form lowered the
        BIC without being supported: a form for the effect's usual case that
        its own form describes too coarsely to win (a converter's PI current
        limiter, whose overshoot and dip the clamp misses by hundreds of
        amperes).
    local_fits : int
        Local fits of the form's refit, from its best starts (one: from the
        effect's values; more where the form's valley lies away from them,
        as a falling friction's with a heavier burden).
    alike : callable or None
        ``alike(form_values, own_values) -> str or None``: where the form's
        refit tells another story than the effect's own form (a friction
        that falls to nothing at the set speed, not a constant one), that
        story in words; None where they tell the same.  Where the form then
        fits about as well without being supported, the diagnosis cautions
        that the record hardly tells the two apart.
    also : callable or None
        ``also(form_values) -> str or None``: where the form is selected at
        values that a change outside the catalogue imitates on one start-up
        (a friction gone by the set speed, and a current excess that fades
        with the time while the ramp's speed grows with it), that change in
        words; the diagnosis names it in a caution.
    """

    name: str
    meaning: str
    components: tuple
    parameters: tuple
    near: dict
    starts: Callable = field(repr=False, default=lambda values: [])
    ends: dict = field(default_factory=dict)
    in_rounds: bool = True
    unsupported_too: bool = False
    local_fits: int = 1
    alike: Callable | None = field(repr=False, default=None)
    also: Callable | None = field(repr=False, default=None)


def _table1() -> Parameters:
    """The paper's drive (Table 1 and the defaults), against which the usual ranges are written."""
    global _TABLE1
    if _TABLE1 is None:
        _TABLE1 = Parameters()
    return _TABLE1


_TABLE1: Parameters | None = None


def motor_scale(params: Parameters) -> tuple[float, str]:
    """Scale of a motor-side inertia: the motor's own, J_m / J_m of Table 1 [-]."""
    return params.J_m / _table1().J_m, "J_m"


def motor_torque_scale(params: Parameters) -> tuple[float, str]:
    """Scale of a motor-side torque: the motor's torque at its current limit, k_i I_max, over Table 1's [-]."""
    t1 = _table1()
    return params.k_i * params.I_max / (t1.k_i * t1.I_max), "k_i I_max"


def kiln_torque_scale(params: Parameters) -> tuple[float, str]:
    """Scale of a torque on the kiln: the burden's weight times its arm, m_v L, over Table 1's [-] (the kiln's
    running torque is m_v g L sin(psi))."""
    t1 = _table1()
    return params.m_v * params.L / (t1.m_v * t1.L), "m_v L"


def drag_scale(params: Parameters) -> tuple[float, str]:
    """Scale of a viscous drag on the kiln: a torque of the kiln's scale (:func:`kiln_torque_scale`) at the
    kiln's set speed omega_ref / n, over Table 1's [-]."""
    t1 = _table1()
    return (kiln_torque_scale(params)[0] * (t1.omega_ref / t1.n) / (params.omega_ref / params.n),
            "m_v L over the kiln's speed")


def kiln_inertia_scale(params: Parameters) -> tuple[float, str]:
    """Scale of a stiffness or damping at the kiln axis: the kiln's inertia J_o + J_v over Table 1's [-] (the
    same mode frequency and damping ratio)."""
    t1 = _table1()
    return (params.J_o + params.J_v) / (t1.J_o + t1.J_v), "J_o + J_v"


@dataclass(frozen=True)
class Effect:
    """One physical effect of the catalogue.

    Attributes
    ----------
    name : str
        Catalogue name.
    meaning : str
        The physics, in one or two sentences.
    components : tuple of str
        Model components it adds (:data:`kilnctl.model.REGISTRY`).
    options : dict
        Parameter options it sets (e.g. ``friction_law = 'torque'``).
    model : str or None
        Model it needs (``micro`` for backlash), None for any.
    parameters : tuple of FreeParameter
        What is fitted when it is added (on top of the base parameters).
    signature : str
        The residual pattern it explains.
    starts : callable
        ``starts(params, measurement) -> list of dict``: initial guesses
        added to the grid of :func:`grid_starts` (the best of all by cost is
        the starting point of the local fit).
    plausible : dict
        Usual range of each parameter in real drives [unit]: it adds
        starting points, is reported when a fitted value lies outside it
        (:meth:`plausibility`), and draws the magnitudes of synthetic records;
        it is never a fitting bound and never decides which effect is
        selected.
    notes : str
        How it is handled (e.g. the micro model for backlash).
    horizons : tuple of float or 'after_first_failure'
        Growing fitting horizons (fractions of the record) used when it is
        refitted (see :meth:`~kilnctl.measure.calibrate.Calibration.fit`);
        ``after_first_failure``: first up to 1 s after the current model's
        first failing interval, then longer by 10 % of the record at a time.
    grid_points : int
        Points of the coarse start grid per parameter.
    separation : float
        Least scaled distance between the starting points of the local fits
        (small where the cost has narrow parallel valleys).
    smoothing : tuple of float
        Moving-average widths of the residual [s] on which the starting
        points are compared and each local fit begins, widest first (see
        :meth:`~kilnctl.measure.calibrate.Calibration.fit`): for effects whose
        trace is a short event or a jump whose time depends on the
        parameters.  Every refit of a structure with the effect uses them.
    period : callable or None
        ``period(params, omega_ref) -> float``: the period of the effect's
        signature [s] when it is periodic.  In a record shorter than that
        the signature is only part of a cycle, which other causes also
        produce; the diagnosis then adds ``short_record_note`` as a caution.
    short_record_note : str
        What else makes the signature in such a short record.
    relative_plausible : tuple of str
        Parameters whose ``plausible`` range is not in their own unit
        (skipped by :meth:`plausibility`).
    contradicts : callable or None
        ``contradicts(values, params) -> str or None``: why fitted values
        (``values``, with the rest of the model's ``params``) describe
        something other than the effect's signature, or None when they do
        not (a drive train so damped that it cannot ring has no torsional
        mode to show).  A candidate whose refit ends there is not supported:
        it stands in for a difference the catalogue may lack.  Physics, not a
        usual range: it holds for any magnitude.
    scale : callable or None
        ``scale(params) -> (factor, how)``: the :attr:`plausible` ranges
        describe drives like the paper's (Table 1); for another kiln or
        motor they are multiplied by ``factor`` (1 for Table 1), ``how``
        saying with what they scale (``"J_m"``).  None: absolute ranges (a
        sensor's lag, a backlash gap).
    forms : tuple of Form
        Other forms of the effect, each tried when the effect is a supported
        candidate (a second-order speed filter or a delay for the
        first-order lag).
    spread : str or None
        A parameter whose starting points are spread over its decades for
        the local fits (:class:`~kilnctl.measure.calibrate.Starts`): where it
        sets a mode's frequency, a start a few per cent off ranks below no
        mode at all, and the base values may have made up for the effect.
    steady_load : bool
        The effect loads the drive at the set speed (a viscous drag, a
        friction): a model without it makes up for it by a heavier burden,
        and a refit under stick-slip is also started with the burden moved
        to keep the current at the set speed (see
        :meth:`~kilnctl.measure.diagnose.Diagnosis._restart_at_load`).
    offset_in_motion : callable or None
        ``offset_in_motion(values, params) -> float``: the constant current
        [A] the effect adds as soon as the motor turns and not at rest (a
        motor friction's T_cm/k_i), which a current-sensor offset adds at
        rest too.  The final check then weighs the record's current at rest
        (:meth:`~kilnctl.measure.checks.SelectionChecks._offset_at_rest`).
        None: the effect's current is not such a constant.
    null : dict or None
        Values of its parameters at which the effect vanishes (or nearly:
        a lag of 0.1 ms), so that the structure with it contains the one
        without it; a refit starts there too and is then never worse than
        the current model.  None when there is no such point in the bounds
        (a rigid drive train is the limit of infinite stiffness).
    """

    name: str
    meaning: str
    components: tuple
    options: dict
    model: str | None
    parameters: tuple
    signature: str
    starts: Callable = field(repr=False, default=lambda params, m: [{}])
    plausible: dict = field(default_factory=dict)
    notes: str = ""
    horizons: tuple = (1.0,)
    grid_points: int = 24
    separation: float = 1.0
    smoothing: tuple = (0.0,)
    period: Callable | None = field(repr=False, default=None)
    short_record_note: str = ""
    null: dict | None = None
    relative_plausible: tuple = ()
    contradicts: Callable | None = field(repr=False, default=None)
    spread: str | None = None
    forms: tuple = ()
    scale: Callable | None = field(repr=False, default=None)
    steady_load: bool = False
    offset_in_motion: Callable | None = field(repr=False, default=None)

    def usual(self, name: str, params: Parameters | None = None) -> tuple[float, float]:
        """The usual range of parameter ``name`` [its unit] for the drive of ``params`` (Table 1's without).

        Parameters
        ----------
        name : str
            A parameter of :attr:`plausible`.
        params : Parameters, optional
            The setup; the range is scaled by :attr:`scale` (phases and relative ranges are not).

        Returns
        -------
        (float, float)
        """
        lo, hi = self.plausible[name]
        if params is None or self.scale is None or name.startswith("phi") or name in self.relative_plausible:
            return lo, hi
        try:
            factor = float(self.scale(params)[0])
        except (ArithmeticError, KeyError, AttributeError):
            return lo, hi  # a setup the scale cannot be read from (a zero set speed): the written range
        if not (math.isfinite(factor) and factor > 0):
            return lo, hi
        return lo * factor, hi * factor

    def form(self, name: str | None) -> Form | None:
        """The other form called ``name`` (:attr:`forms`), or None when the effect has none of that name (or
        ``name`` is None: the effect's own form)."""
        return next((f for f in self.forms if f.name == name), None)

    def applicable(self, params: Parameters, model: str) -> str | None:
        """Return None if the effect can be added to this base, else the reason it cannot.

        Parameters
        ----------
        params : Parameters
            Base parameters (options).
        model : str
            Base model.

        Returns
        -------
        str or None
        """
        for k, v in self.options.items():
            if params[k] == v:
                return f"the base already has {k} = {v!r}"
        return None

    def plausibility(self, values: dict, params: Parameters | None = None) -> list[str]:
        """Say in words which fitted values lie outside the usual range of real drives.

        The ranges (:attr:`plausible`) only describe typical kilns: a value
        outside one is reported, never refused, and never decides which
        effect is selected.  Ranges that are not in the parameter's own unit
        (``I_max`` as a fraction of the peak current) and phases are skipped.

        Parameters
        ----------
        values : dict of str to float
            Fitted values [unit of each parameter].
        params : Parameters, optional
            The setup: the ranges are scaled to its drive (:meth:`usual`); without it, Table 1's.

        Returns
        -------
        list of str
            E.g. ``"J_m2 = 8 kg*m^2, below the usual 10-45 kg*m^2"``; a scaled range says from what
            (``"... the usual 1.6-7.3 kg*m^2 (the paper's 10-45 scaled with J_m)"``).
        """
        out = []
        for name, (lo0, hi0) in self.plausible.items():
            if name not in values or name.startswith("phi") or name in self.relative_plausible:
                continue
            lo, hi = self.usual(name, params)
            v = float(values[name])
            unit = SPECS[name].unit if name in SPECS else ""
            unit = "" if unit in ("-", "") else " " + unit
            how = ""
            if (lo, hi) != (lo0, hi0):
                how = f" (the paper's {lo0:g}-{hi0:g} scaled with {self.scale(params)[1]})"
            if v < lo:
                out.append(f"{name} = {v:.3g}{unit}, below the usual {lo:.2g}-{hi:.2g}{unit}{how}")
            elif v > hi:
                out.append(f"{name} = {v:.3g}{unit}, above the usual {lo:.2g}-{hi:.2g}{unit}{how}")
        return out

    def usual_starts(self, params: Parameters | None = None) -> list[dict]:
        """Starting points from the usual ranges: each end, their middle, 0.3 x the lower and 3 x the upper end.

        The usual range guides the search; the bounds stay wide, so a value outside it is found too.

        Parameters
        ----------
        params : Parameters, optional
            The setup: the ranges are scaled to its drive (:meth:`usual`); without it, Table 1's.

        Returns
        -------
        list of dict
            One parameter varied at a time [unit of each]; ranges not in the parameter's own unit, and
            phases, are skipped.
        """
        out = []
        for name in self.plausible:
            if name.startswith("phi") or name in self.relative_plausible:
                continue
            lo, hi = self.usual(name, params)
            mid = math.sqrt(lo * hi) if lo > 0 else 0.5 * (lo + hi)
            fp = next((f for f in self.parameters if f.name == name), None)
            for v in (0.3 * lo, lo, mid, hi, 3.0 * hi):
                if fp is None or fp.lower <= v <= fp.upper:
                    out.append({name: float(v)})
        return out

    def to_dict(self) -> dict:
        """Return the entry as a JSON-ready dictionary."""
        return {"name": self.name, "meaning": self.meaning, "components": list(self.components),
                "options": dict(self.options), "model": self.model, "signature": self.signature,
                "parameters": [{"name": p.name, "unit": p.unit, "lower": p.lower, "upper": p.upper,
                                "scale": p.kind} for p in self.parameters],
                "plausible": {k: list(v) for k, v in self.plausible.items()}, "notes": self.notes,
                "forms": [{"name": f.name, "meaning": f.meaning, "components": list(f.components),
                           "parameters": [p.name for p in f.parameters]} for f in self.forms]}
