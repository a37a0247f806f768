"""The effect catalogue: physical effects a user can add to the model, and what each explains.

Each :class:`Effect` says what physics it stands for, which components or
options of :mod:`kilnctl.model` it adds, which parameters it brings (with
bounds and initial guesses for calibration) and the **residual signature**
it explains: the pattern a comparison shows when the effect is in the kiln
but not in the model.  :class:`~kilnctl.measure.diagnose.Diagnosis` tries
them one by one.

>>> from kilnctl.measure.effects import CATALOGUE
>>> sorted(CATALOGUE)[:3]
['backlash', 'current_limit', 'drivetrain_compliance']
>>> CATALOGUE["second_motor"].components
('second_motor',)
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from ..errors import ModelError, close_matches_hint
from ..params import SPECS, Parameters

__all__ = ["FreeParameter", "Effect", "CATALOGUE", "BASE_PARAMETERS", "DEFAULT_CALIBRATE", "free_parameter",
           "effect_components", "grid_starts"]


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

    def plausibility(self, values: dict) -> list[str]:
        """Say in words which fitted values lie outside the usual range of real drives.

        The ranges (:attr:`plausible`) only describe typical kilns: a value
        outside one is reported, never refused, and never decides which
        effect is selected.  Ranges that are not in the parameter's own unit
        (``I_max`` as a fraction of the peak current) and phases are skipped.

        Parameters
        ----------
        values : dict of str to float
            Fitted values [unit of each parameter].

        Returns
        -------
        list of str
            E.g. ``"J_m2 = 8 kg*m^2, below the usual 10-45 kg*m^2"``.
        """
        out = []
        for name, (lo, hi) in self.plausible.items():
            if name not in values or name.startswith("phi") or name in self.relative_plausible:
                continue
            v = float(values[name])
            unit = SPECS[name].unit if name in SPECS else ""
            unit = "" if unit in ("-", "") else " " + unit
            if v < lo:
                out.append(f"{name} = {v:.3g}{unit}, below the usual {lo:g}-{hi:g}{unit}")
            elif v > hi:
                out.append(f"{name} = {v:.3g}{unit}, above the usual {lo:g}-{hi:g}{unit}")
        return out

    def usual_starts(self) -> list[dict]:
        """Starting points from the usual ranges: each end, their middle, 0.3 x the lower and 3 x the upper end.

        The usual range guides the search; the bounds stay wide, so a value outside it is found too.

        Returns
        -------
        list of dict
            One parameter varied at a time [unit of each]; ranges not in the parameter's own unit, and
            phases, are skipped.
        """
        out = []
        for name, (lo, hi) in self.plausible.items():
            if name.startswith("phi") or name in self.relative_plausible:
                continue
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
                "plausible": {k: list(v) for k, v in self.plausible.items()}, "notes": self.notes}


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
        elif fp.kind == "log":
            lo, hi = max(fp.lower, fp.typical / 100), min(fp.upper, fp.typical * 100)
            axes.append([{fp.name: float(v)} for v in np.geomspace(lo, hi, per)])
        else:
            hi = min(fp.upper, 10 * fp.typical)
            axes.append([{fp.name: float(v)} for v in np.linspace(fp.lower, hi, per)])
    out = [{}]
    for ax in axes:
        out = [dict(a, **b) for a in out for b in ax]
    return out


def _compliance_starts(params) -> list[dict]:
    """k_po on a fine geometric grid (40 points over 5 decades: the mode frequency within 8 %), C_po from
    damping ratios 0.03, 0.15, 0.6 of the torsional mode."""
    j_motor = (params.J_m + params.J_m2) * params.n ** 2  # motor side referred to the kiln (upper bound)
    j_kiln = params.J_e_eff
    j_eff = j_motor * j_kiln / (j_motor + j_kiln)
    out = []
    for k in np.geomspace(1e6, 1e11, 40):
        for zeta in (0.03, 0.15, 0.6):
            out.append({"k_po": float(k), "C_po": float(min(1e10, max(1e3, 2 * zeta * math.sqrt(k * j_eff))))})
    return out


def _peak_current(m) -> float:
    """A robust peak of the measured current [A] (99.5th percentile of |i|)."""
    return float(np.percentile(np.abs(m.current), 99.5)) if m is not None else 1000.0


CATALOGUE: dict[str, Effect] = {e.name: e for e in [
    Effect(
        "second_motor",
        "A second drive motor, electrically isolated but still coupled to the shaft: its rotor inertia "
        "must be accelerated with the first motor (the paper's experiment, Fig. 5).",
        ("second_motor",), {}, None,
        (FreeParameter("J_m2", 0.0, 2000.0, "lin", 21.5),),
        "current above the model while the drive accelerates (the ramp), by J_m2 x acceleration / k_i, "
        "and a step down when the ramp ends; no error at constant speed",
        starts=lambda params, m: [{"J_m2": params.J_m}, {"J_m2": 0.3 * params.J_m}, {"J_m2": 3 * params.J_m}],
        plausible={"J_m2": (10.0, 45.0)}, null={"J_m2": 0.0}),
    Effect(
        "current_limit",
        "The drive limits the armature current lower than the setup says: the current is held flat at "
        "I_max and the speed falls behind its reference while it is.",
        ("current_limit",), {}, None,
        (FreeParameter("I_max", 10.0, 20000.0, "log", 1000.0),),
        "the measured current flat-topped at a plateau the model exceeds, while the speed lags the reference; "
        "the model's current peak is above the measured one",
        starts=lambda params, m: [{"I_max": f * _peak_current(m)} for f in (0.9, 0.95, 0.98, 1.0, 1.02, 1.05, 1.1)]
        + [{"I_max": params.I_max}],
        plausible={"I_max": (0.9, 0.98)}, separation=0.02, null={}, relative_plausible=("I_max",),
        notes="current_limit is in both base models with the setup's I_max; as a candidate, I_max is freed. "
              "Synthetic records draw I_max as a fraction of the plant's peak current without the limit."),
    Effect(
        "drivetrain_compliance",
        "Torsional flexibility of shafts, gearbox and coupling lumped as a spring-damper between the "
        "gearbox and the kiln (k_po, C_po of Table 1) instead of a rigid reducer.",
        ("drivetrain_compliance",), {}, None,
        (FreeParameter("k_po", 1e6, 1e12, "log", 7.012e8), FreeParameter("C_po", 1e3, 1e10, "log", 19.9e6)),
        "a damped oscillation of the current at the torsional mode (about 1.5 Hz with Table 1) after each "
        "change of torque: ramp start, ramp end, burden breakaway",
        starts=lambda params, m: _compliance_starts(params),
        plausible={"k_po": (5e7, 5e8), "C_po": (2e6, 2e7)}, grid_points=0,
        notes="started from a grid in stiffness (fine: the mode frequency must match) times damping ratios "
              "0.03-0.6 of the mode between the motor side and the kiln."),
    Effect(
        "backlash",
        "Play between girth gear and pinion: at start-up the motor turns freely until the teeth meet, "
        "then they engage with an impact.",
        (), {}, "micro",
        (FreeParameter("delta_x", 0.0, 0.06, "lin", 0.008),),
        "in the first second or so: current below the model while the motor turns free, then a spike "
        "when the teeth meet; nothing at steady state",
        starts=lambda params, m: [{"delta_x": 0.004}, {"delta_x": 0.008}, {"delta_x": 0.016}],
        plausible={"delta_x": (0.004, 0.016)}, grid_points=80, smoothing=(0.4, 0.1), null={"delta_x": 0.0},
        notes="needs the micro model (coupling, pinion, mesh), which has backlash; the macro model has none. "
              "The candidate runs the micro model with the base's calibrated values and fits delta_x; the "
              "evidence is against the macro base (the micro model with delta_x = 0 is close to it). Only the "
              "free travel gap_0 * delta_x shows in a start-up: gap_0 is kept at the setup's value. The impact "
              "is a spike one or two samples long whose time moves with the gap, so the cost has a valley a "
              "fraction of a millimetre wide: starts are compared, and fits begin, on a residual smoothed over "
              "0.4 s, then 0.1 s, then none."),
    Effect(
        "torque_friction_law",
        "The burden breaks away when the friction torque needed to hold it exceeds mu_s N R (torque-"
        "consistent), instead of the paper's force comparison (eq. 3): large stick-slip cycles.",
        (), {"friction_law": "torque"}, None, (),
        "a saw-tooth in the current at steady speed: rising while the burden sticks, dropping at each "
        "breakaway, with a period of seconds; the paper's law gives small sliding oscillations",
        notes="an option of the burden model, not a component: no new parameter; mu_c and mu_s are refitted "
              "(their meaning changes with the law), first on the record up to the end of the current model's "
              "first failing interval, then on all of it: the cost of a long run of stick-slip cycles is rugged. "
              "A breakaway misplaced in time costs in proportion to the shift (a cusp at the right friction): "
              "each fit runs on a residual smoothed over 0.4 s, then 0.1 s, then none.",
        horizons="after_first_failure", separation=0.04, smoothing=(0.4, 0.1)),
    Effect(
        "speed_sensor_lag",
        "The controller sees the motor speed through a first-order lag (tacho filter, encoder averaging).",
        ("speed_sensor_lag",), {}, None,
        (FreeParameter("tau_s", 1e-4, 2.0, "log", 0.005),),
        "a less damped speed loop: current oscillation at the loop's crossover after the ramp starts and "
        "ends, larger overshoot of the speed; residual correlated with the speed error",
        starts=lambda params, m: [{"tau_s": 0.001}, {"tau_s": 0.003}, {"tau_s": 0.01}],
        plausible={"tau_s": (0.002, 0.006)}, null={"tau_s": 1e-4},
        notes="the record's speed_rpm is read as the true motor speed; only the controller's copy lags. "
              "Large lags can destabilise the loop: such trial runs are cut short and count as a poor fit."),
    Effect(
        "kiln_unbalance",
        "A once-per-revolution torque on the kiln from an eccentric mass (coating, accretion) or a "
        "cranked shell: T_unb sin(theta_o + phi_unb).",
        ("kiln_unbalance",), {}, None,
        (FreeParameter("T_unb", 0.0, 2e7, "polar", 2e5, partner="phi_unb"),),
        "a slow sinusoidal drift of the current with the kiln angle (one period per kiln revolution, "
        "about 130 s at 500 rpm): in a short record, a slowly rising or falling offset",
        starts=lambda params, m: [{"T_unb": 1e4, "phi_unb": 0.0}],
        plausible={"T_unb": (1e5, 4e5), "phi_unb": (0.0, 2 * math.pi)}, null={"T_unb": 0.0, "phi_unb": 0.0},
        period=lambda params, omega_ref: 60.0 * params.n / omega_ref,  # one kiln revolution at the set speed
        short_record_note="a slow drift, which a current-sensor offset or gain error, or slowly correlated "
                          "noise, also produce",
        notes="fitted as the pair (T cos phi, T sin phi), which is linear in the torque; T_unb and phi_unb "
              "and their standard errors follow."),
    Effect(
        "viscous_drag",
        "A torque proportional to the kiln speed (seals, tyre and roller slip, lubricant drag): "
        "-B_o omega_o.",
        ("viscous_drag",), {}, None,
        (FreeParameter("B_o", 0.0, 1e9, "lin", 1e6),),
        "current above the model in proportion to the speed: growing along the ramp, then a constant "
        "offset at steady speed (which alone a burden mass or friction change could also explain)",
        starts=lambda params, m: [{"B_o": 1e5}, {"B_o": 3e6}],
        plausible={"B_o": (2e6, 1e7)}, null={"B_o": 0.0}),
]}


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
