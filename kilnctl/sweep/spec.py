"""Sweep spec files (TOML): a study written down, for ``kilnctl sweep SPEC.toml``.

The format (every key but ``[parameters]`` is optional)::

    name    = "stress_map"        # shown in the progress bar; default: the file name
    model   = "micro"             # 'macro' or 'micro' (default 'micro')
    t_end   = 30.0                # simulated time of each start-up [s] (default 40)
    method  = "grid"              # 'grid' (default), 'lhs' (Latin hypercube) or 'montecarlo'
    n       = 200                 # number of points (lhs, montecarlo)
    seed    = 1                   # random seed (lhs, montecarlo; default 0)
    outputs = ["peak_stress_Pa"]  # summary values to tabulate (default: peak_stress_Pa)
    config  = "plant.toml"        # base parameter file, relative to this file (default: Table 1)
    effects = ["second_motor"]    # components added to the model
    remove  = []                  # components taken out
    redesign = false              # true: design the PID gains anew at every point (default: once, for the base)

    [base]                        # parameter values on top of config, for every point
    ramp_rate = 74.0

    [parameters.m_v]              # grid: evenly spaced values (scale = "log" for geometric)
    min = 240e3
    max = 974e3
    num = 5

    [parameters.delta_x]          # grid: explicit values
    values = [0.0, 0.008, 0.016]

    [parameters.friction]         # a factor: multiplies mu_c and mu_s of the base together
    factor = ["mu_c", "mu_s"]
    dist = "truncnormal"          # lhs/montecarlo: uniform (min, max), loguniform (min, max),
    mean = 1.0                    #   normal (mean, std), truncnormal (mean, std, min, max),
    std = 0.1                     #   triangular (min, mode, max); min/max alone: uniform
    min = 0.7
    max = 1.3

    [options]                     # simulation options for every point (dt, rtol, atol ...)
    dt = 1e-3

Values are in the parameter's unit (``kilnctl params`` lists them).

Examples
--------
>>> from kilnctl.sweep.spec import study_from_dict
>>> st = study_from_dict({"model": "macro", "parameters": {"m_v": {"min": 290e3, "max": 870e3, "num": 3}}})
>>> st.samples()["m_v"].tolist()
[290000.0, 580000.0, 870000.0]
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Mapping

from ..budget import check_points
from ..files import read_toml
from ..errors import ConfigFileError, KilnctlError, ParameterError, close_matches_hint
from ..params import Parameters
from .space import DISTRIBUTIONS, Grid, LatinHypercube, LogUniform, MonteCarlo, Uniform
from .study import Study

__all__ = ["SpecError", "load_spec", "study_from_dict", "METHODS"]

#: sampling methods of a spec, by name
METHODS = {"grid": Grid, "lhs": LatinHypercube, "montecarlo": MonteCarlo}

_TOP = ("name", "model", "t_end", "method", "n", "seed", "outputs", "config", "effects", "remove", "redesign",
        "base", "parameters", "options")
#: arguments of each distribution in spec keys, in the constructor's order
_DIST_ARGS = {"uniform": ("min", "max"), "loguniform": ("min", "max"), "normal": ("mean", "std"),
              "truncnormal": ("mean", "std", "min", "max"), "triangular": ("min", "mode", "max")}


class SpecError(ConfigFileError):
    """A sweep spec is malformed: names the file and the key, and says how to fix it."""


def _unknown(keys, known, where):
    for k in keys:
        if k not in known:
            raise SpecError(f"{where}: unknown key {k!r}: {close_matches_hint(k, known)}")


def _variable(name: str, entry: Mapping[str, Any], method: str, max_points: int | None = None):
    """Return (grid values or distribution, factor targets or None) of one [parameters.NAME] table."""
    where = f"[parameters.{name}]"
    if not isinstance(entry, Mapping):
        raise SpecError(f"{where}: give a table, e.g. {{ values = [...] }} or {{ min = .., max = .. }}")
    keys = set(entry) - {"factor"}
    factor = entry.get("factor")
    if factor is not None and (isinstance(factor, str) or not isinstance(factor, list) or not factor):
        raise SpecError(f"{where}: factor must be a list of parameter names, e.g. factor = [\"mu_c\", \"mu_s\"]")
    if method == "grid":
        if "dist" in entry:
            raise SpecError(f"{where}: 'dist' is for method = 'lhs' or 'montecarlo'; a grid takes values = [...] "
                            "or min/max/num")
        _unknown(keys, ("values", "min", "max", "num", "scale"), where)
        if "values" in entry:
            if keys & {"min", "max", "num", "scale"}:
                raise SpecError(f"{where}: give either values = [...] or min/max/num, not both")
            vals = entry["values"]
            if not isinstance(vals, list):
                raise SpecError(f"{where}: values must be a list")
            if not vals:
                raise SpecError(f"{where}: values is empty: give at least one value")
            return vals, factor
        missing = [k for k in ("min", "max", "num") if k not in entry]
        if missing:
            raise SpecError(f"{where}: a grid variable needs values = [...] or min, max and num (missing: "
                            + ", ".join(missing) + ")")
        return list(Grid.linspace(entry["min"], entry["max"], entry["num"], entry.get("scale", "linear"),
                                  max_points=max_points)), factor
    dist = entry.get("dist")
    if dist is None:
        _unknown(keys, ("min", "max", "scale", "dist"), where)
        missing = [k for k in ("min", "max") if k not in entry]
        if missing:
            raise SpecError(f"{where}: method '{method}' needs min and max (or dist = ...) for each variable "
                            "(missing: " + ", ".join(missing) + ")")
        scale = entry.get("scale", "linear")
        if scale not in ("linear", "log"):
            raise SpecError(f"{where}: scale = {scale!r}: choose 'linear' or 'log'")
        return (LogUniform if scale == "log" else Uniform)(entry["min"], entry["max"]), factor
    if dist not in DISTRIBUTIONS:
        raise SpecError(f"{where}: unknown dist {dist!r}: {close_matches_hint(str(dist), DISTRIBUTIONS)}")
    args = _DIST_ARGS[dist]
    _unknown(keys, args + ("dist",), where + f" (dist = {dist!r})")
    missing = [a for a in args if a not in entry]
    if missing:
        raise SpecError(f"{where}: dist = {dist!r} needs " + ", ".join(args) + " (missing: " + ", ".join(missing) + ")")
    return DISTRIBUTIONS[dist](*(entry[a] for a in args)), factor


def study_from_dict(spec: Mapping[str, Any], base_dir: str | Path = ".", name: str = "sweep",
                    max_points: int | None = None) -> Study:
    """Build a :class:`Study` from a parsed spec (see the module text for the format).

    Parameters
    ----------
    spec : mapping
        The spec's keys and tables.
    base_dir : path-like, default '.'
        Folder that a relative ``config`` path is taken from.
    name : str, default 'sweep'
        Study name when the spec has none.
    max_points : int, optional
        Largest number of points (checked before any point is built); default
        ``KILNCTL_MAX_POINTS`` or 100 000 (:mod:`kilnctl.budget`).

    Returns
    -------
    Study

    Raises
    ------
    SpecError
        Unknown keys, a bad method, missing or empty ranges (each message names
        the key).
    ParameterError
        More points than ``max_points``.
    ParameterError, ModelError
        Unknown parameters, outputs or components (with close matches).
    """
    _unknown(spec, _TOP, "spec")
    _check_types(spec)
    method = spec.get("method", "grid")
    if method not in METHODS:
        raise SpecError(f"method = {method!r} is not a sampling method: {close_matches_hint(str(method), METHODS)} "
                        "(grid: every combination; lhs: Latin hypercube; montecarlo: independent random points)")
    if method == "grid":
        for k in ("n", "seed"):
            if k in spec:
                raise SpecError(f"{k} is for method = 'lhs' or 'montecarlo': a grid has one point per combination")
    elif "n" not in spec:
        raise SpecError(f"method = {method!r} needs n, the number of points")
    params = spec.get("parameters")
    if not isinstance(params, Mapping) or not params:
        raise SpecError("the spec needs a [parameters] table with at least one variable, e.g. "
                        "[parameters.m_v] min = 240e3, max = 974e3, num = 5")
    base = Parameters()
    if "config" in spec:
        base = Parameters.from_toml(Path(base_dir) / spec["config"])
    if "base" in spec:
        if not isinstance(spec["base"], Mapping):
            raise SpecError("[base] must be a table of parameter values")
        try:
            base = base.replace(**spec["base"])
        except ParameterError as exc:
            raise ParameterError(f"[base]: {exc}") from None
    dims, factors = {}, {}
    for vname, entry in params.items():
        try:
            dims[vname], factor = _variable(vname, entry, method, max_points)
        except ParameterError as exc:
            if isinstance(exc, SpecError):
                raise
            raise SpecError(f"[parameters.{vname}]: {exc}") from None
        if factor is not None:
            factors[vname] = tuple(factor)
    if method == "grid":
        space = Grid(dims)
    else:
        space = METHODS[method](dims, n=spec["n"], seed=spec.get("seed", 0))
    check_points(len(space), max_points, what="the grid (the product of the variables' value counts)"
                 if method == "grid" else f"n = {spec['n']}: the study")
    outputs = spec.get("outputs", ["peak_stress_Pa"])
    if isinstance(outputs, str):
        outputs = [outputs]
    options = spec.get("options", {})
    if not isinstance(options, Mapping):
        raise SpecError("[options] must be a table of simulation options")
    return Study(space, outputs, model=spec.get("model", "micro"), t_end=spec.get("t_end", 40.0), base=base,
                 effects=spec.get("effects", ()), remove=spec.get("remove", ()), factors=factors,
                 options=options, name=str(spec.get("name", name)), redesign=_flag(spec, "redesign"),
                 max_points=max_points)


#: top-level keys that must be text, or lists of text
_TEXT_KEYS = ("name", "model", "method", "config")
_LIST_KEYS = ("outputs", "effects", "remove")


def _check_types(spec: Mapping[str, Any]) -> None:
    for k in _TEXT_KEYS:
        if k in spec and not isinstance(spec[k], str):
            raise SpecError(f"{k} = {spec[k]!r} must be text in quotes, e.g. {k} = \"...\"")
    for k in _LIST_KEYS:
        v = spec.get(k)
        if v is None or (k == "outputs" and isinstance(v, str)):
            continue
        if not isinstance(v, list) or not all(isinstance(x, str) for x in v):
            raise SpecError(f"{k} = {v!r} must be a list of names in quotes, e.g. {k} = [\"...\"]")


def _flag(spec, key: str) -> bool:
    v = spec.get(key, False)
    if not isinstance(v, bool):
        raise SpecError(f"{key} = {v!r} must be true or false")
    return v


def load_spec(path: str | Path, max_points: int | None = None) -> Study:
    """Read a sweep spec file and return its study.

    Parameters
    ----------
    path : path-like
        The TOML file.
    max_points : int, optional
        Largest number of points, see :func:`study_from_dict`.

    Returns
    -------
    Study

    Raises
    ------
    SpecError
        Missing file, invalid TOML or a malformed spec; the message starts with
        the file name.
    ParameterError, ModelError
        Unknown names or impossible values, also prefixed with the file name.
    """
    path = Path(path)
    raw = read_toml(path, "sweep spec", SpecError)
    try:
        return study_from_dict(raw, base_dir=path.parent, name=path.stem, max_points=max_points)
    except KilnctlError as exc:
        if str(exc).startswith(str(path)):
            raise
        raise type(exc)(f"{path}: {exc}") from None
