"""Parameter sets of the kiln drive, with units and sources.

Every symbol of the paper's Table 1 and nomenclature is here, in SI units
(speeds of the speed loop in r.p.m., as the paper's controller uses them), each
with the place it comes from: ``Table 1``, an equation number, or
``assumed: <why>``.  Every reading the paper leaves open (see
``docs/assumptions.md``) is a named parameter or option, never a constant
buried in a model.

Examples
--------
>>> from kilnctl.params import Parameters
>>> p = Parameters()
>>> round(p.J_stick, 2)
28.97
>>> p2 = p.replace(mu_c=0.35, mu_s=0.38)
>>> p2.mu_c
0.35
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Iterator, Mapping

import tomli_w

from .errors import ConfigFileError, ParameterError, close_matches_hint
from .files import read_toml, write_atomic

__all__ = ["ParamSpec", "Parameters", "SPECS", "GROUPS", "Implausible", "plausibility", "check_plausible",
           "HARD_FACTOR", "SLIP_FACTOR"]

#: rules a numeric value may be held to
_RULES = {
    "finite": (lambda v: True, "must be a finite number"),
    "positive": (lambda v: v > 0, "must be > 0"),
    "nonnegative": (lambda v: v >= 0, "must be >= 0"),
    "fraction": (lambda v: 0 <= v <= 1, "must lie in [0, 1]"),
}


@dataclass(frozen=True)
class ParamSpec:
    """Declaration of one parameter.

    Attributes
    ----------
    name : str
        Key, after the paper's nomenclature where it has one.
    default : float or str
        Default value (SI unless ``unit`` says otherwise).
    unit : str
        Unit of the value.
    source : str
        Where the value comes from: ``Table 1``, ``eq. N``, or ``assumed: ...``.
    description : str
        What the parameter is.
    group : str
        Section of the TOML file it is saved in.
    rule : str
        ``finite``, ``positive``, ``nonnegative`` or ``fraction`` for numbers.
    choices : tuple of str, optional
        Allowed values of an option (string parameter).
    """

    name: str
    default: float | str
    unit: str
    source: str
    description: str
    group: str
    rule: str = "finite"
    choices: tuple[str, ...] = ()

    @property
    def is_option(self) -> bool:
        """True for string options, False for numbers."""
        return bool(self.choices)


def _p(name, default, unit, source, description, group, rule="positive", choices=()):
    return ParamSpec(name, default, unit, source, description, group, rule, tuple(choices))


_SPEC_LIST = [
    # --- DC motor (eq. 21) -------------------------------------------------------
    _p("R_a", 0.00961, "ohm", "Table 1", "armature resistance", "motor"),
    _p("L_a", 0.57e-3, "H", "Table 1", "armature inductance", "motor"),
    _p("k_i", 4.6, "N*m/A", "Table 1 (printed as N.m/r.p.m., read in SI)", "torque constant", "motor"),
    _p("k_b", 4.6, "V*s/rad", "assumed: nomenclature line 'k_b k_i' is garbled; read as equal to k_i in SI "
       "(gives 241 V back-emf at 500 rpm)", "back-emf constant", "motor"),
    _p("J_m", 21.5, "kg*m^2", "Table 1", "inertia of motor", "motor"),
    _p("B_m", 0.005, "N*m*s/rad", "Table 1", "viscous friction coefficient of the motor", "motor", "nonnegative"),
    _p("J_m2", 21.5, "kg*m^2", "assumed: the paper's second motor is of the same type as the first",
       "inertia of the second, electrically isolated motor (component 'second_motor')", "motor"),
    # --- speed controller (eq. 21, Fig. 3) --------------------------------------
    _p("K_fb", 60.0 / (2.0 * math.pi), "rpm*s/rad", "eq. 21; NOTES: the unit conversion 60/(2 pi)",
       "speed feedback constant K (called k in eq. 21)", "controller"),
    _p("gains", "design", "-", "assumed: the paper designs the gains by root locus and does not print them",
       "'design': k_p, k_I, k_D come from the root-locus design with default requirements; "
       "'given': use k_p, k_I, k_D below", "controller", choices=("design", "given")),
    _p("k_p", 1.0, "V/rpm", "assumed: placeholder used only when gains = 'given'",
       "proportional constant", "controller", "nonnegative"),
    _p("k_I", 1.0, "V/(rpm*s)", "assumed: placeholder used only when gains = 'given'",
       "integral constant", "controller", "nonnegative"),
    _p("k_D", 0.01, "V*s/rpm", "assumed: placeholder used only when gains = 'given'",
       "derivative constant (realised through L_a, eq. 21 line 2)", "controller", "nonnegative"),
    # --- drive: reference and limits -------------------------------------------
    _p("omega_ref", 500.0, "rpm", "paper: optimum operating speed 500 r.p.m.", "motor speed set point", "drive"),
    _p("ramp_rate", 74.0, "rpm/s", "assumed reading of the paper's ramp constant 74: the speed reference "
       "rises at 74 rpm/s and reaches 500 rpm after 6.76 s", "ramp constant of the speed reference", "drive"),
    _p("V_max", 500.0, "V", "assumed: supply for the paper's 1000 rpm top speed (k_b * 104.7 rad/s = 482 V)",
       "armature voltage limit of the drive (applies to the PI output)", "drive"),
    _p("I_max", 1500.0, "A", "assumed: about 1.8 x the 840 A worked steady-state current, a usual "
       "short-time rating", "armature current limit of the drive", "drive"),
    # --- kiln and burden (eqs. 1-19) --------------------------------------------
    _p("J_o", 6.978e6, "kg*m^2", "Table 1", "inertia of kiln", "kiln"),
    _p("J_v", 1.678e6, "kg*m^2", "Table 1", "inertia of burden", "kiln"),
    _p("J_e", 8.476e6, "kg*m^2", "Table 1 (2 % below J_o + J_v = 8.656e6)",
       "equivalent inertia J_e = J_o + J_v as printed; used only when J_e_mode = 'table'", "kiln"),
    _p("J_e_mode", "sum", "-", "NOTES: Table 1 J_e disagrees with J_o + J_v by 2 %",
       "'sum': J_e = J_o + J_v; 'table': J_e as printed, the kiln shell then has J_e - J_v",
       "kiln", choices=("sum", "table")),
    _p("m_v", 580e3, "kg", "Table 1", "mass of burden", "kiln"),
    _p("L", 1.353, "m", "Table 1", "torque arm of burden (centre of mass from kiln axis)", "kiln"),
    _p("R", 2.17, "m", "Table 1", "radius of kiln (arm of the wall friction force)", "kiln"),
    _p("mu_c", 0.4, "-", "paper, Fig. 4: mu3 fits best", "Coulomb (kinetic) friction coefficient of burden", "kiln", "nonnegative"),
    _p("mu_s", 0.51, "-", "paper, Fig. 4: mu3 fits best", "static friction coefficient of burden", "kiln", "nonnegative"),
    _p("friction_law", "paper", "-", "NOTES: the printed law is not torque-consistent",
       "'paper': breakaway when F_t > F_bf (forces, eq. 3); 'torque': breakaway when the holding torque "
       "exceeds mu_s*N*R. Both use kinetic torque mu_c*N*R opposing the relative velocity and re-stick",
       "kiln", choices=("paper", "torque")),
    _p("psi_0", 0.0, "rad", "assumed: the paper does not give the initial burden angle; burden at rest at "
       "the bottom", "initial burden angle from bottom dead centre", "kiln", "finite"),
    _p("g", 9.81, "m/s^2", "nomenclature", "gravitational constant", "kiln"),
    _p("mu_brg", 0.001, "-", "Le Roux [10], eq. 17", "friction coefficient of support roller bearings",
       "kiln", "nonnegative"),
    _p("P", 16.512e6, "N", "Table 1", "total weight of kiln", "kiln", "nonnegative"),
    _p("l_brg", 0.7155, "m", "Table 1 ('l')", "torque arm of bearing l (eq. 17)", "kiln", "nonnegative"),
    _p("k_brg", 0.5475, "m", "Table 1 ('k'; not the feedback constant K)", "torque arm of bearing k (eq. 17)",
       "kiln", "nonnegative"),
    # --- drive train and gears (eqs. 26-34) -------------------------------------
    _p("n", 1076.5, "-", "Table 1", "total reduction motor to kiln", "gear"),
    _p("R_o", 3.960, "m", "Table 1", "pitch circle radius of girth gear", "gear"),
    _p("R_p", 0.5775, "m", "Table 1", "pitch circle radius of pinion", "gear"),
    _p("k_o", 2.986e10, "N/m", "Table 1", "spring constant of girth gear teeth", "gear"),
    _p("k_pi", 2.986e10, "N/m", "Table 1", "spring constant of pinion gear teeth", "gear"),
    _p("C_e", 8.2e5, "N*s/m", "assumed: 5 % damping ratio of the pinion (J_p) on the mesh stiffness k_e",
       "mesh damping constant", "gear", "nonnegative"),
    _p("delta_x", 8e-3, "m", "paper: normal backlash about 8 mm (studied 0-16 mm)",
       "backlash between girth gear and pinion (Delta x)", "gear", "nonnegative"),
    _p("gap_0", 1.0, "-", "assumed: worst case, the whole backlash must be taken up at start",
       "fraction of the backlash open at t = 0 (1: pinion on the back flank)", "gear", "fraction"),
    _p("J_p", 1500.0, "kg*m^2", "assumed: steel pinion r = 0.5775 m, b = 0.6 m (about 1 100 kg*m^2) plus "
       "gearbox output", "inertia of pinion and gearbox output, pinion axis", "gear"),
    _p("k_po", 7.012e8, "N*m/rad", "Table 1", "equivalent torsional spring constant (component "
       "'drivetrain_compliance', kiln axis)", "gear"),
    _p("C_po", 19.9e6, "N*m*s/rad", "Table 1", "equivalent torsional damping constant (component "
       "'drivetrain_compliance', kiln axis)", "gear", "nonnegative"),
    _p("module", 0.033, "m", "assumed: 33 mm gives integer tooth counts 240/35 for R_o, R_p exactly",
       "module of girth gear and pinion", "gear"),
    _p("face_width", 0.6, "m", "assumed: typical girth gear face width (about 18 modules)",
       "face width of the girth gear", "gear"),
    _p("Y_lewis", 0.468, "-", "assumed: Lewis form factor, 20 deg full depth, 240 teeth (Michalopoulos [11])",
       "Lewis form factor of the girth gear tooth", "gear"),
    _p("dynamic_factor", "none", "-", "assumed: at 0.19 m/s pitch-line speed Barth's factor is only 1.03",
       "'none' or 'barth' ((6.1 + V)/6.1) on the Lewis stress", "gear", choices=("none", "barth")),
    # --- effects a measurement may reveal (components in kilnctl/model/effects.py) ---
    _p("tau_s", 0.05, "s", "assumed: first-order lag of a tacho-generator with filter",
       "speed sensor time constant (component 'speed_sensor_lag')", "effects"),
    _p("T_unb", 2.0e5, "N*m", "assumed: about 5 % of the 4.2 MN*m kiln running torque",
       "amplitude of the once-per-revolution kiln torque (component 'kiln_unbalance')", "effects", "nonnegative"),
    _p("phi_unb", 0.0, "rad", "assumed: phase of the eccentric mass or shell crank at t = 0",
       "phase of the once-per-revolution torque (component 'kiln_unbalance')", "effects", "finite"),
    _p("B_o", 1.0e6, "N*m*s/rad", "assumed: about 1 % of the running torque at 0.46 rpm (seals, tyre slip)",
       "viscous drag on the kiln (component 'viscous_drag')", "effects", "nonnegative"),
    # --- elastomeric coupling (micro model) -------------------------------------
    _p("k_c", 1.0e5, "N*m/rad", "assumed: thesis [9] not available; large elastomeric coupling, "
       "about 2.5 deg twist at the 4 kN*m running torque", "coupling stiffness at zero twist, motor side",
       "coupling"),
    _p("phi_c_ref", 0.05, "rad", "assumed: progressive rubber; stiffness doubles at 0.05 rad twist",
       "twist scale of the progressive term: T = k_c*phi*(1 + (phi/phi_c_ref)^2)", "coupling"),
    _p("coupling_law", "progressive", "-", "assumed: shape of the elastomer curve",
       "'progressive' or 'linear' torque-twist curve", "coupling", choices=("progressive", "linear")),
    _p("c_c", 150.0, "N*m*s/rad", "assumed: about 10 % damping ratio of the coupling mode",
       "coupling damping constant, motor side", "coupling", "nonnegative"),
]

#: all parameter declarations, by name
SPECS: dict[str, ParamSpec] = {s.name: s for s in _SPEC_LIST}
#: TOML section order
GROUPS: tuple[str, ...] = ("motor", "controller", "drive", "kiln", "gear", "coupling", "effects")


# --- plausibility: values that are valid numbers but not a kiln drive ------------------------------
#: a value this many times above or below its default (Table 1 or the documented assumption) is refused:
#: no kiln drive is that far off, and the models' arithmetic overflows (R_a = 1e300 gave non-finite matrices)
HARD_FACTOR = 1e9
#: a mass, inertia, weight or length this many times above or below its default is almost surely a unit
#: slip (tonnes for kg, mm for m): a warning, an error with ``strict``
SLIP_FACTOR = 300.0
#: units whose slips come in factors of 1000 (kg <-> t, m <-> mm, N <-> kN)
_SLIP_UNITS = ("kg", "kg*m^2", "N", "m")
#: coefficients of friction: above 1 is almost surely a percentage
_FRICTION = ("mu_c", "mu_s", "mu_brg")


def _check_magnitude(spec: ParamSpec, v: float) -> None:
    d = spec.default
    if spec.is_option or not isinstance(d, float) or d == 0 or v == 0:
        return
    ratio = abs(v / d)
    if not 1 / HARD_FACTOR <= ratio <= HARD_FACTOR:
        raise ParameterError(
            f"parameter {spec.name!r} = {v!r} {spec.unit} is {ratio:.3g} times its default {d:g} {spec.unit} "
            f"({spec.source}): no kiln drive is that far off (the limit is a factor of {HARD_FACTOR:g}); check "
            f"the value and its unit ({spec.description}, in {spec.unit})")


@dataclass(frozen=True)
class Implausible:
    """A value that is valid but almost surely a slip (a unit, a percentage).

    Attributes
    ----------
    name : str
        Parameter name.
    value : float
        The value given (in the parameter's unit).
    likely : float
        The value probably meant (same unit).
    message : str
        The warning, in words, with the likely value.
    """

    name: str
    value: float
    likely: float
    message: str


def plausibility(params: "Parameters") -> list[Implausible]:
    """Return the values of a parameter set that are valid but almost surely a slip.

    Rules: a coefficient of friction above 1 (a percentage: the likely value
    is a hundredth), and a mass, inertia, weight or length at least
    :data:`SLIP_FACTOR` times above or below its default (Table 1 or the
    documented assumption; the likely value is a thousandth or a thousand
    times), e.g. a backlash of 8 given in metres meant as millimetres.

    Parameters
    ----------
    params : Parameters
        The parameter set.

    Returns
    -------
    list of Implausible
        In declaration order; empty when nothing looks wrong.
    """
    out = []
    for spec in _SPEC_LIST:
        v = params[spec.name]
        if spec.is_option or v == 0:
            continue
        if spec.name in _FRICTION:
            if v > 1:
                likely = v / 100
                out.append(Implausible(spec.name, v, likely, (
                    f"{spec.name} = {v:g} is a coefficient of friction above 1 (a {spec.description}): was it "
                    f"given in percent? {v:g} % is {spec.name} = {likely:g}")))
            continue
        d = spec.default
        if spec.unit not in _SLIP_UNITS or not isinstance(d, float) or d == 0:
            continue
        ratio = v / d
        if ratio >= SLIP_FACTOR or ratio <= 1 / SLIP_FACTOR:
            likely = v / 1000 if ratio > 1 else v * 1000
            thousand = {"kg": "t", "kg*m^2": "t*m^2", "N": "kN"}  # the unit a thousand times larger
            if spec.unit == "m" and ratio > 1:
                slip = "given in mm instead of m"
            elif spec.unit in thousand and ratio < 1:
                slip = f"given in {thousand[spec.unit]} instead of {spec.unit}"
            else:
                slip = "a factor of 1000 too " + ("large" if ratio > 1 else "small")
            out.append(Implausible(spec.name, v, likely, (
                f"{spec.name} = {v:g} {spec.unit} is {ratio:.3g} times its default {d:g} {spec.unit} "
                f"({spec.source}; {spec.description}): {slip}? The likely value is {spec.name} = {likely:g} "
                f"{spec.unit}")))
    return out


def check_plausible(params: "Parameters", strict: bool = False, where: str = "") -> list[str]:
    """Return the plausibility warnings of a parameter set, or raise them with ``strict``.

    Parameters
    ----------
    params : Parameters
        The parameter set.
    strict : bool, default False
        Raise instead of returning warnings.
    where : str, optional
        The file the values come from, put before each message.

    Returns
    -------
    list of str
        One message per implausible value (see :func:`plausibility`).

    Raises
    ------
    ParameterError
        With ``strict``, when any value is implausible (all messages, and how
        to accept them: leave out ``--strict``).
    """
    prefix = f"{where}: " if where else ""
    msgs = [prefix + w.message for w in plausibility(params)]
    if msgs and strict:
        raise ParameterError("; ".join(msgs) + " (refused because of --strict / strict=True; without it these "
                             "are warnings)")
    return msgs


def _check_value(spec: ParamSpec, value: Any) -> float | str:
    if spec.is_option:
        if not isinstance(value, str) or value not in spec.choices:
            raise ParameterError(
                f"parameter {spec.name!r} = {value!r} is not allowed: choose one of "
                + ", ".join(repr(c) for c in spec.choices))
        return value
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ParameterError(
            f"parameter {spec.name!r} = {value!r} must be a number in {spec.unit}")
    v = float(value)
    if not math.isfinite(v):
        raise ParameterError(f"parameter {spec.name!r} = {v!r} must be a finite number ({spec.unit})")
    ok, rule = _RULES[spec.rule]
    if not ok(v):
        raise ParameterError(f"parameter {spec.name!r} = {v!r} {rule} ({spec.description}, {spec.unit})")
    _check_magnitude(spec, v)
    return v


class Parameters(Mapping):
    """A validated, immutable set of kiln-drive parameters.

    Parameters
    ----------
    values : mapping, optional
        Values that replace the defaults, by parameter name.
    **overrides
        More replacements, by keyword.

    Raises
    ------
    ParameterError
        For an unknown name (the message lists close matches) or an impossible
        value (the message names the key, the value and the rule).

    Notes
    -----
    Values are read as attributes (``p.J_m``) or by key (``p["J_m"]``).  Derived
    quantities (``n_p``, ``n_r``, ``k_e``, ``J_stick`` ...) are properties.
    """

    __slots__ = ("_values",)

    def __init__(self, values: Mapping[str, Any] | None = None, **overrides: Any):
        merged = {name: spec.default for name, spec in SPECS.items()}
        given = dict(values or {})
        given.update(overrides)
        for key, value in given.items():
            if key not in SPECS:
                raise ParameterError(f"unknown parameter {key!r}: {close_matches_hint(key, SPECS)}")
            merged[key] = _check_value(SPECS[key], value)
        if merged["mu_c"] > merged["mu_s"]:
            raise ParameterError(
                f"parameter 'mu_c' = {merged['mu_c']} exceeds 'mu_s' = {merged['mu_s']}: the kinetic friction "
                "coefficient must not exceed the static one")
        if merged["J_e_mode"] == "table" and merged["J_e"] <= merged["J_v"]:
            raise ParameterError(
                f"parameter 'J_e' = {merged['J_e']} must exceed 'J_v' = {merged['J_v']} when J_e_mode = 'table' "
                "(the kiln shell inertia is J_e - J_v)")
        if merged["R_o"] <= merged["R_p"]:
            raise ParameterError(
                f"parameter 'R_o' = {merged['R_o']} must exceed 'R_p' = {merged['R_p']}: the girth gear is the "
                "larger wheel")
        if merged["n"] <= merged["R_o"] / merged["R_p"]:
            raise ParameterError(
                f"parameter 'n' = {merged['n']} must exceed the girth-gear ratio R_o/R_p = "
                f"{merged['R_o'] / merged['R_p']:.4g}: the gearbox ratio n/n_p would be below 1")
        pitch = math.pi * merged["module"]
        if merged["delta_x"] >= pitch:
            raise ParameterError(
                f"parameter 'delta_x' = {merged['delta_x']!r} m (backlash) is not below the circular pitch "
                f"pi * module = {pitch:.4g} m: the teeth could not mesh. Backlash is in metres: "
                f"{merged['delta_x']:g} mm is delta_x = {merged['delta_x'] / 1000:g}")
        object.__setattr__(self, "_values", merged)

    # --- mapping protocol ---------------------------------------------------
    def __getitem__(self, key: str):
        try:
            return self._values[key]
        except KeyError:
            raise ParameterError(f"unknown parameter {key!r}: {close_matches_hint(key, SPECS)}") from None

    def __iter__(self) -> Iterator[str]:
        return iter(self._values)

    def __len__(self) -> int:
        return len(self._values)

    def __getattr__(self, key: str):
        if key.startswith("_"):
            raise AttributeError(key)
        if key in SPECS:
            return self._values[key]
        raise AttributeError(f"Parameters has no attribute {key!r}: {close_matches_hint(key, SPECS)}")

    def __setattr__(self, key, value):
        raise AttributeError("Parameters are immutable: use p.replace(name=value)")

    def __reduce__(self):
        # pickled by value (worker processes): rebuilt, and so re-checked, from its values
        return (Parameters, (dict(self._values),))

    def __repr__(self) -> str:
        changed = {k: v for k, v in self._values.items() if v != SPECS[k].default}
        return f"Parameters({changed!r})"

    def __eq__(self, other) -> bool:
        return isinstance(other, Parameters) and self._values == other._values

    def __hash__(self) -> int:
        return hash(tuple(sorted(self._values.items())))

    def replace(self, **changes: Any) -> "Parameters":
        """Return a copy with some values changed (validated again).

        Parameters
        ----------
        **changes
            New values by parameter name.

        Returns
        -------
        Parameters
            The new parameter set; ``self`` is unchanged.
        """
        values = dict(self._values)
        values.update(changes)
        return Parameters(values)

    def as_dict(self) -> dict[str, float | str]:
        """Return the values as a plain dictionary (name -> value)."""
        return dict(self._values)

    # --- derived quantities -------------------------------------------------
    @property
    def n_p(self) -> float:
        """Girth gear to pinion ratio R_o / R_p [-]."""
        return self.R_o / self.R_p

    @property
    def n_r(self) -> float:
        """Gearbox ratio n / n_p [-] (about 157)."""
        return self.n / self.n_p

    @property
    def k_e(self) -> float:
        """Equivalent mesh stiffness of the teeth in series, eq. 26 [N/m]."""
        return self.k_o * self.k_pi / (self.k_o + self.k_pi)

    @property
    def J_kiln(self) -> float:
        """Inertia of the kiln shell used by the models [kg*m^2].

        ``J_o`` when ``J_e_mode == 'sum'``; ``J_e - J_v`` when ``'table'``.
        """
        return self.J_o if self.J_e_mode == "sum" else self.J_e - self.J_v

    @property
    def J_e_eff(self) -> float:
        """Kiln plus burden inertia J_e used by the models [kg*m^2]."""
        return self.J_kiln + self.J_v

    @property
    def J_stick(self) -> float:
        """Inertia at the motor with the burden sticking, eq. 11 [kg*m^2]."""
        return self.J_m + self.J_e_eff / self.n ** 2

    @property
    def J_slip(self) -> float:
        """Inertia at the motor with the burden slipping, eq. 15 [kg*m^2]."""
        return self.J_m + self.J_kiln / self.n ** 2

    @property
    def T_brg(self) -> float:
        """Support-roller bearing friction torque at the kiln, eq. 17 [N*m]."""
        return 2.0 * self.mu_brg * self.P / 2.0 * math.cos(math.radians(30.0)) * (self.l_brg + self.k_brg) / 2.0

    # --- description and files ------------------------------------------------
    def describe(self) -> list[dict[str, Any]]:
        """Return one row per parameter: name, value, unit, source, description, group.

        Returns
        -------
        list of dict
            Rows in declaration order, ready for printing or JSON.
        """
        return [
            {"name": s.name, "value": self._values[s.name], "unit": s.unit, "source": s.source,
             "description": s.description, "group": s.group, "default": s.default}
            for s in _SPEC_LIST
        ]

    def to_toml(self, path: str | os.PathLike, *, overwrite: bool = False) -> Path:
        """Write the full parameter set to a TOML file, grouped by section.

        The file is written whole or not at all (a temporary file is renamed).

        Parameters
        ----------
        path : path-like
            Destination file.
        overwrite : bool, default False
            Replace an existing file.  Without it, an existing file is an error:
            kilnctl never overwrites what the user gave.

        Returns
        -------
        Path
            The path written.
        """
        path = Path(path)
        if path.exists() and not overwrite:
            raise ConfigFileError(f"{path}: file exists; choose another name or pass overwrite=True")
        doc: dict[str, dict[str, Any]] = {g: {} for g in GROUPS}
        for s in _SPEC_LIST:
            doc[s.group][s.name] = self._values[s.name]
        write_atomic(path, tomli_w.dumps(doc))
        return path

    @classmethod
    def from_toml(cls, path: str | os.PathLike) -> "Parameters":
        """Read a parameter set from a TOML file.

        Keys may stand at the top level or inside any of the sections
        ``[motor]``, ``[controller]``, ``[drive]``, ``[kiln]``, ``[gear]``,
        ``[coupling]``, ``[effects]``; missing keys keep their defaults.

        Parameters
        ----------
        path : path-like
            The TOML file.

        Returns
        -------
        Parameters

        Raises
        ------
        ConfigFileError
            The file is missing, a folder, not UTF-8 TOML (a byte-order mark
            is named as such), or has an unknown section.
        ParameterError
            A key is unknown or a value impossible; the message names the file.
        """
        path = Path(path)
        raw = read_toml(path, "configuration file")
        flat: dict[str, Any] = {}
        for key, value in raw.items():
            if isinstance(value, dict):
                if key not in GROUPS:
                    raise ConfigFileError(
                        f"{path}: unknown section [{key}]: {close_matches_hint(key, GROUPS)}")
                for k, v in value.items():
                    flat[k] = v
            else:
                flat[key] = value
        try:
            return cls(flat)
        except ParameterError as exc:
            raise ParameterError(f"{path}: {exc}") from None
