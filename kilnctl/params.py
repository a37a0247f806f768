"""Parameter sets of the kiln drive, with units and sources.

Every symbol of the paper's Table 1 and nomenclature is a parameter, in SI
units (speeds of the speed loop in r.p.m., as the paper's controller uses
them), each with the place it comes from: ``Table 1``, an equation number, or
``assumed: <why>``.  Every reading the paper leaves open (see
``docs/assumptions.md``) is a named parameter or option, never a constant
buried in a model.

Each parameter is declared once, by the component of :mod:`kilnctl.model`
that owns it (its ``parameters``, made with :func:`param`); :data:`SPECS` is
derived from the registry.  This module validates values against the
declarations and reads and writes parameter files.

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
import numbers
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Iterator, Mapping

import tomli_w

from .errors import ConfigFileError, ParameterError, close_matches_hint
from .files import read_toml, write_atomic

__all__ = ["ParamSpec", "Parameters", "SPECS", "GROUPS", "param", "RegistryView", "Implausible",
           "plausibility", "check_plausible", "HARD_FACTOR", "SLIP_FACTOR", "fold_motors", "MOTORS_KEY",
           "FOLDED_BY_MOTORS"]

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


def param(name: str, default: float | str, unit: str, source: str, description: str, group: str,
          rule: str = "positive", choices=()) -> ParamSpec:
    """Declare a parameter; a component lists what it declares in its ``parameters``.

    Parameters
    ----------
    name : str
        Key, after the paper's nomenclature where it has one.
    default : float or str
        Default value [``unit``]; a string for an option.
    unit : str
        Unit of the value (``-`` when dimensionless).
    source : str
        ``Table 1``, ``eq. N``, or ``assumed: <why>``.
    description : str
        What the parameter is.
    group : str
        TOML section it is saved in (one of :data:`GROUPS`).
    rule : str, default 'positive'
        Bound every value must respect: ``finite``, ``positive``, ``nonnegative`` or ``fraction``.
    choices : sequence of str, optional
        Allowed values of an option.

    Returns
    -------
    ParamSpec
    """
    return ParamSpec(name, default, unit, source, description, group, rule, tuple(choices))


#: returns the component registry (name -> component class).  This module sits below kilnctl.model (whose
#: components import it), so it is handed the registry instead of importing it: the package root
#: (kilnctl/__init__.py, run before any kilnctl module) sets a loader that imports kilnctl.model, which
#: registers every component, and returns kilnctl.model.REGISTRY
_registry_loader = None


def _component_registry() -> dict:
    if _registry_loader is None:
        raise ParameterError("no component registry is set: import kilnctl (its root sets it)")
    return _registry_loader()


class RegistryView(Mapping):
    """A read-only table derived from the component registry, rebuilt when a component is registered.

    Parameters
    ----------
    build : callable
        ``build(registry) -> dict``, from :data:`kilnctl.model.REGISTRY` (name -> component class).
    """

    def __init__(self, build):
        self._build = build
        self._table: dict = {}
        self._key = None

    def _current(self) -> dict:
        REGISTRY = _component_registry()
        # the registry of kilnctl.model counts its changes in ``version``; a plain dict is judged by its size
        key = (id(REGISTRY), getattr(REGISTRY, "version", None), len(REGISTRY))
        if self._key != key:
            # the registry is held, so its id cannot be reused by another object while it is in the key
            self._table, self._key, self._registry = self._build(REGISTRY), key, REGISTRY
        return self._table

    def snapshot(self) -> dict:
        """The current table, a new dict object whenever the registry changed (callers may key a cache on its
        identity); read it, never change it."""
        return self._current()

    def __getitem__(self, key):
        return self._current()[key]

    def __iter__(self):
        return iter(self._current())

    def __len__(self) -> int:
        return len(self._current())

    def __contains__(self, key) -> bool:
        return key in self._current()

    def __repr__(self) -> str:
        return f"RegistryView({self._current()!r})"


def _declarations(registry) -> dict[str, ParamSpec]:
    """Every parameter declared by a registered component (its own ``parameters``, not inherited ones),
    in registration order."""
    out: dict[str, ParamSpec] = {}
    owner: dict[str, str] = {}
    for comp in registry.values():
        for spec in vars(comp).get("parameters", ()):
            if spec.name in out:
                raise ParameterError(f"parameter {spec.name!r} is declared by both component {owner[spec.name]!r} "
                                     f"and {comp.name!r}: declare it once, in the component that owns it, and list "
                                     "it in the other's param_names")
            if spec.group not in GROUPS:
                raise ParameterError(f"parameter {spec.name!r} of component {comp.name!r} is in group "
                                     f"{spec.group!r}: use one of {', '.join(GROUPS)}")
            out[spec.name] = spec
            owner[spec.name] = comp.name
    return out


#: all parameter declarations, by name: derived from the components of kilnctl.model (each declares its own in
#: ``parameters``), in registration order
SPECS: Mapping[str, ParamSpec] = RegistryView(_declarations)
#: the section of an experiment's setup file that holds measurement options, not parameters (docs/measurements.md)
MEASUREMENT_SECTION = "measurement"
#: key of a setup file's ``[motor]`` section: how many identical motors drive the kiln together
#: (:func:`fold_motors`)
MOTORS_KEY = "motors"
#: the parameters of one motor that a drive of several identical motors multiplies (torque per ampere of the
#: logged motor, rotor inertia, viscous friction)
FOLDED_BY_MOTORS = ("k_i", "J_m", "B_m")


def fold_motors(flat: dict, where: str) -> dict:
    """Fold a drive of several identical motors into the model's one motor.

    A large kiln is often driven by two motors, each on its own pinion (or
    both on one shaft), fed alike by one speed controller, and the logger
    records one motor's armature current.  With ``motors = N`` in the
    setup's ``[motor]`` section and one motor's nameplate values there, each
    motor carries the same current i_a: the drive's torque is N k_i i_a, its
    rotor inertia N J_m and its viscous friction N B_m at the motor speed,
    while every motor's armature circuit (R_a, L_a, k_b) and the current
    limit I_max stay those of one motor.  So k_i, J_m and B_m are multiplied
    by N and the model stays the paper's; an effect fitted on the motor side
    (J_m2, T_cm) is then that of all N motors together.

    Parameters
    ----------
    flat : dict
        The setup's keys, sections flattened; ``motors`` is taken out.
    where : str
        The file, for the message.

    Returns
    -------
    dict
        ``flat`` with k_i, J_m and B_m (given or default) multiplied by the number of motors.

    Raises
    ------
    ConfigFileError
        ``motors`` is not a whole number of 1 or more.
    """
    if MOTORS_KEY not in flat:
        return flat
    motors = flat.pop(MOTORS_KEY)
    if isinstance(motors, bool) or not isinstance(motors, int) or motors < 1:
        raise ConfigFileError(f"{where}: [motor] {MOTORS_KEY} = {motors!r} must be a whole number of identical motors "
                              "driving the kiln together, 1 or more (with one motor's R_a, L_a, k_i, k_b, J_m, B_m "
                              "and I_max in [motor] and [drive]; the record logs one motor's current)")
    defaults = Parameters()  # (builds the registry of every component's parameters)
    for k in FOLDED_BY_MOTORS:
        value = flat.get(k, defaults[k])
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            continue  # refused with its own message when the parameters are built
        flat[k] = motors * value
    return flat

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
    for spec in SPECS.values():
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
    # numbers.Real: also numpy's scalars (np.int64 from an index or a sum was refused as "must be a number")
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
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


def _check_into(merged: dict, specs, given: Mapping[str, Any], keys) -> None:
    """Check ``given[key]`` for each of ``keys`` (in that order) against its declaration and put it into
    ``merged``, then check the full set together; the first bad value raises."""
    for key in keys:
        spec = specs.get(key)
        if spec is None:
            raise ParameterError(f"unknown parameter {key!r}: {close_matches_hint(key, specs)}")
        merged[key] = _check_value(spec, given[key])
    _check_together(merged)


def _check_together(merged: dict) -> None:
    """Refuse values that are each valid but impossible together (``merged``: a full set of values)."""
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

    # _specs: the declaration table (SPECS.snapshot()) the values were checked against
    __slots__ = ("_values", "_specs")

    @staticmethod
    def require(value, what: str = "params", hint: str | None = None, error: type = ParameterError) -> "Parameters":
        """Return ``value``, refused with a clear error when it is not a :class:`Parameters` (a dict, a file name).

        Parameters
        ----------
        value : object
            What the caller was given.
        what : str, default 'params'
            The argument's name, for the message (with a prefix naming the file when there is one).
        hint : str, optional
            How to make one, shown in parentheses.
        error : type, default ParameterError
            Exception class raised (a :class:`~kilnctl.errors.KilnctlError` subclass).

        Returns
        -------
        Parameters

        Raises
        ------
        ParameterError
            (or ``error``) ``what must be a kilnctl.Parameters (hint), not TYPE``.
        """
        if not isinstance(value, Parameters):
            raise error(f"{what} must be a kilnctl.Parameters{f' ({hint})' if hint else ''}, not "
                        f"{type(value).__name__}")
        return value

    def __init__(self, values: Mapping[str, Any] | None = None, **overrides: Any):
        if values is not None and not isinstance(values, Mapping):
            hint = (": for a file use Parameters.from_toml(path)" if isinstance(values, (str, os.PathLike))
                    else ", e.g. Parameters({'m_v': 5e5}) or Parameters(m_v=5e5)")
            raise ParameterError(f"Parameters(values): values must be a mapping of parameter names to values, not "
                                 f"{type(values).__name__}{hint}")
        specs = SPECS.snapshot()
        merged = {name: spec.default for name, spec in specs.items()}
        given = dict(values or {})
        given.update(overrides)
        _check_into(merged, specs, given, given)
        object.__setattr__(self, "_values", merged)
        object.__setattr__(self, "_specs", specs)

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
        try:
            return self._values[key]
        except KeyError:
            pass
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
        """Return a copy with some values changed (the changes validated, and all values together).

        Parameters
        ----------
        **changes
            New values by parameter name.

        Returns
        -------
        Parameters
            The new parameter set; ``self`` is unchanged.
        """
        specs = SPECS.snapshot()
        values = dict(self._values)
        if specs is not self._specs:  # a component was registered since: check everything again
            values.update(changes)
            return Parameters(values)
        # the declarations are those self was checked against, so only the changed values need checking
        # (in declaration order, unknown names last: the first error is the one a full check raises)
        order = changes if len(changes) < 2 else (
            [k for k in specs if k in changes] + [k for k in changes if k not in specs])
        _check_into(values, specs, changes, order)
        new = object.__new__(Parameters)
        object.__setattr__(new, "_values", values)
        object.__setattr__(new, "_specs", specs)
        return new

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
            for s in sorted(SPECS.values(), key=lambda s: GROUPS.index(s.group))
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
        for s in SPECS.values():
            doc[s.group][s.name] = self._values[s.name]
        write_atomic(path, tomli_w.dumps(doc))
        return path

    @classmethod
    def from_toml(cls, path: str | os.PathLike) -> "Parameters":
        """Read a parameter set from a TOML file.

        Keys may stand at the top level or inside any of the sections
        ``[motor]``, ``[controller]``, ``[drive]``, ``[kiln]``, ``[gear]``,
        ``[coupling]``, ``[effects]``; missing keys keep their defaults.
        ``motors = N`` in ``[motor]`` folds N identical motors into the
        model's one (:func:`fold_motors`).  The
        ``[measurement]`` section of an experiment's setup file
        (``docs/measurements.md``) is skipped: it is read by the measurement
        tools (:func:`kilnctl.measure.load_setup`), so one setup serves
        ``compare`` and ``diagnose`` as well as ``params``, ``design``,
        ``verify`` and ``simulate``.

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
        return cls.from_sections(read_toml(path, "configuration file"), str(path))

    @classmethod
    def from_sections(cls, raw: Mapping, source: str) -> "Parameters":
        """Build a parameter set from a parsed TOML document (the one reading of every kilnctl parameter file).

        Parameters
        ----------
        raw : mapping
            Keys at the top level or inside the sections of :data:`GROUPS`; a ``[measurement]`` section is
            skipped (the measurement tools read it), ``motors`` in ``[motor]`` is folded (:func:`fold_motors`).
        source : str
            The file, for the messages.

        Returns
        -------
        Parameters

        Raises
        ------
        ConfigFileError
            An unknown section, or a bad ``motors``.
        ParameterError
            A key is unknown or a value impossible; the message names ``source``.
        """
        flat: dict[str, Any] = {}
        for key, value in raw.items():
            if key == MEASUREMENT_SECTION and isinstance(value, dict):
                continue  # the experiment's options, not parameters: checked by kilnctl.measure.load_setup
            if isinstance(value, dict):
                if key not in GROUPS:
                    raise ConfigFileError(f"{source}: unknown section [{key}]: "
                                          f"{close_matches_hint(key, list(GROUPS) + [MEASUREMENT_SECTION])}")
                flat.update(value)
            else:
                flat[key] = value
        try:
            return cls(fold_motors(flat, source))
        except ParameterError as exc:
            raise ParameterError(f"{source}: {exc}") from None
