"""Parameter spaces of a sweep: full grids, Latin hypercubes and Monte Carlo samples.

A space maps *variable* names to values and yields one row per point.  A
variable is a parameter of :class:`kilnctl.Parameters` (``m_v``,
``delta_x`` ...) or a *factor* declared by the study (a multiplier applied to
several parameters at once, see :class:`kilnctl.sweep.Study`).

Sampled spaces draw points on the unit hypercube (stratified for the Latin
hypercube, independent for Monte Carlo) and map each coordinate through the
inverse distribution function of its variable's marginal distribution, so the
same distributions serve both methods.

Examples
--------
>>> from kilnctl.sweep.space import Grid, LatinHypercube, Uniform
>>> g = Grid({"m_v": [290e3, 580e3], "delta_x": [0.0, 0.008, 0.016]})
>>> len(g), g.names
(6, ('m_v', 'delta_x'))
>>> g.samples()["delta_x"].tolist()
[0.0, 0.008, 0.016, 0.0, 0.008, 0.016]
>>> lhs = LatinHypercube({"mu_c": Uniform(0.3, 0.5)}, n=4, seed=1)
>>> sorted(int((v - 0.3) / 0.2 * 4) for v in lhs.samples()["mu_c"])  # one point per stratum
[0, 1, 2, 3]
"""

from __future__ import annotations

import inspect
from abc import ABC, abstractmethod
import itertools
import math
from dataclasses import dataclass
from typing import Mapping, Sequence

import numpy as np

from ..errors import ParameterError

__all__ = ["Distribution", "Uniform", "LogUniform", "Normal", "TruncNormal", "Triangular",
           "Grid", "LatinHypercube", "MonteCarlo", "Space", "DISTRIBUTIONS"]


def _num(name: str, what: str, v) -> float:
    if isinstance(v, bool) or not isinstance(v, (int, float, np.integer, np.floating)) or not math.isfinite(v):
        raise ParameterError(f"{name}: {what} = {v!r} must be a finite number")
    return float(v)


class Distribution(ABC):
    """Marginal distribution of one sampled variable.

    Subclasses define :meth:`ppf`, the inverse cumulative distribution function
    that maps a uniform number in (0, 1) to a value.
    """

    #: name used in sweep spec files (``dist = "..."``)
    kind = ""

    @abstractmethod
    def ppf(self, u: np.ndarray) -> np.ndarray:
        """Return the values at cumulative probabilities ``u`` (each in (0, 1))."""

    def describe(self) -> str:
        """Return a short text such as ``uniform(0.3, 0.5)``."""
        args = ", ".join(f"{v:g}" for v in vars(self).values())
        return f"{self.kind}({args})"


@dataclass(frozen=True)
class Uniform(Distribution):
    """Uniform distribution on [low, high] (units of the variable).

    Parameters
    ----------
    low, high : float
        Bounds, low < high.
    """

    low: float
    high: float
    kind = "uniform"

    def __post_init__(self):
        _check_range(self.kind, self.low, self.high)

    def ppf(self, u):
        """Return ``low + u (high - low)``."""
        return self.low + np.asarray(u) * (self.high - self.low)


@dataclass(frozen=True)
class LogUniform(Distribution):
    """Distribution uniform in the logarithm on [low, high], 0 < low < high.

    Use it for a variable known within a factor, e.g. a ramp constant between
    37 and 740 rpm/s.

    Parameters
    ----------
    low, high : float
        Bounds (same unit as the variable), 0 < low < high.
    """

    low: float
    high: float
    kind = "loguniform"

    def __post_init__(self):
        _check_range(self.kind, self.low, self.high)
        if self.low <= 0:
            raise ParameterError(f"loguniform: low = {self.low!r} must be > 0")

    def ppf(self, u):
        """Return ``low (high/low)^u``."""
        return self.low * (self.high / self.low) ** np.asarray(u)


@dataclass(frozen=True)
class Normal(Distribution):
    """Normal distribution.

    Parameters
    ----------
    mean : float
        Mean (unit of the variable).
    std : float
        Standard deviation (unit of the variable), > 0.
    """

    mean: float
    std: float
    kind = "normal"

    def __post_init__(self):
        _num(self.kind, "mean", self.mean)
        if _num(self.kind, "std", self.std) <= 0:
            raise ParameterError(f"normal: std = {self.std!r} must be > 0")

    def ppf(self, u):
        """Return ``mean + std * Phi^-1(u)``."""
        from scipy.stats import norm

        return norm.ppf(u, loc=self.mean, scale=self.std)


@dataclass(frozen=True)
class TruncNormal(Distribution):
    """Normal distribution truncated to [low, high].

    The natural choice for a physical coefficient known as "mean +- spread,
    never outside these limits" (a friction coefficient cannot be negative).

    Parameters
    ----------
    mean : float
        Mean of the untruncated normal (unit of the variable).
    std : float
        Standard deviation of the untruncated normal, > 0.
    low, high : float
        Truncation bounds, low < high.
    """

    mean: float
    std: float
    low: float
    high: float
    kind = "truncnormal"

    def __post_init__(self):
        Normal(self.mean, self.std)
        _check_range(self.kind, self.low, self.high)

    def ppf(self, u):
        """Return the truncated-normal quantiles at ``u``."""
        from scipy.stats import truncnorm

        a, b = (self.low - self.mean) / self.std, (self.high - self.mean) / self.std
        return truncnorm.ppf(u, a, b, loc=self.mean, scale=self.std)


@dataclass(frozen=True)
class Triangular(Distribution):
    """Triangular distribution on [low, high] with its peak at ``mode``.

    Parameters
    ----------
    low, mode, high : float
        Lower bound, most likely value, upper bound (unit of the variable).
    """

    low: float
    mode: float
    high: float
    kind = "triangular"

    def __post_init__(self):
        _check_range(self.kind, self.low, self.high)
        if not self.low <= _num(self.kind, "mode", self.mode) <= self.high:
            raise ParameterError(f"triangular: mode = {self.mode!r} must lie in [low, high] = "
                                 f"[{self.low!r}, {self.high!r}]")

    def ppf(self, u):
        """Return the triangular quantiles at ``u``."""
        from scipy.stats import triang

        c = (self.mode - self.low) / (self.high - self.low)
        return triang.ppf(u, c, loc=self.low, scale=self.high - self.low)


def _check_range(kind, low, high):
    lo, hi = _num(kind, "low", low), _num(kind, "high", high)
    if not lo < hi:
        raise ParameterError(f"{kind}: empty range [{low!r}, {high!r}]: low must be below high")


#: distributions by the ``dist`` name used in spec files
DISTRIBUTIONS: dict[str, type[Distribution]] = {
    c.kind: c for c in (Uniform, LogUniform, Normal, TruncNormal, Triangular)}


def _check_names(names: Sequence[str]) -> tuple[str, ...]:
    names = tuple(names)
    if not names:
        raise ParameterError("a sweep needs at least one variable")
    for nm in names:
        if not isinstance(nm, str) or not nm:
            raise ParameterError(f"variable name {nm!r} must be a non-empty string")
    return names


class Space(ABC):
    """Base class of the parameter spaces: ``names``, ``len()`` and :meth:`samples`."""

    names: tuple[str, ...] = ()
    method = ""

    @abstractmethod
    def samples(self) -> dict[str, np.ndarray]:
        """Return one array of values per variable, all of length ``len(self)``."""

    @abstractmethod
    def __len__(self) -> int:
        """Number of points."""

    @abstractmethod
    def describe(self) -> dict[str, str]:
        """Return a short text per variable (its values or its distribution)."""


class Grid(Space):
    """Full factorial grid: every combination of the given values.

    Points are ordered with the first variable varying slowest (as
    ``itertools.product``).

    Parameters
    ----------
    values : mapping of str to sequence
        Values of each variable (numbers in the parameter's unit, or strings
        for an option such as ``friction_law``).  Each needs at least one value
        and no repeats.

    Raises
    ------
    ParameterError
        An empty or repeated value list.
    """

    method = "grid"

    def __init__(self, values: Mapping[str, Sequence]):
        self.names = _check_names(list(values))
        self.values: dict[str, tuple] = {}
        for nm in self.names:
            vals = values[nm]
            if isinstance(vals, (str, bytes)) or not isinstance(vals, Sequence) and not isinstance(vals, np.ndarray):
                raise ParameterError(f"grid variable {nm!r}: give a list of values, not {vals!r}")
            vals = tuple(v.item() if isinstance(v, np.generic) else v for v in vals)
            if not vals:
                raise ParameterError(f"grid variable {nm!r} has no values: give at least one")
            if len(set(vals)) != len(vals):
                raise ParameterError(f"grid variable {nm!r} repeats a value: {list(vals)}")
            self.values[nm] = vals

    @classmethod
    def linspace(cls, low: float, high: float, num: int, scale: str = "linear",
                 max_points: int | None = None) -> tuple[float, ...]:
        """Return ``num`` evenly spaced values from ``low`` to ``high`` (both included).

        Parameters
        ----------
        low, high : float
            End points (unit of the variable), low < high unless num == 1.
        num : int
            Number of values, >= 1.
        scale : {'linear', 'log'}
            Even spacing in the value or in its logarithm (then low > 0).
        max_points : int, optional
            Largest ``num`` accepted (checked before any value is made);
            default: :data:`kilnctl.budget.DEFAULT_MAX_POINTS` or the
            environment variable ``KILNCTL_MAX_POINTS``.

        Returns
        -------
        tuple of float
        """
        from ..budget import check_points

        if isinstance(num, bool) or not isinstance(num, int) or num < 1:
            raise ParameterError(f"num = {num!r} must be an integer >= 1")
        check_points(num, max_points, what=f"num = {num}: the grid variable")
        if num == 1:
            return (_num("grid", "low", low),)
        _check_range("grid", low, high)
        if scale == "log":
            if low <= 0:
                raise ParameterError(f"grid: a log scale needs low > 0, got {low!r}")
            return tuple(float(v) for v in np.geomspace(low, high, num))
        if scale != "linear":
            raise ParameterError(f"scale = {scale!r}: choose 'linear' or 'log'")
        return tuple(float(v) for v in np.linspace(low, high, num))

    def __len__(self) -> int:
        return math.prod(len(v) for v in self.values.values())

    def samples(self) -> dict[str, np.ndarray]:
        """Return the grid points as one array per variable (first variable slowest)."""
        rows = list(itertools.product(*(self.values[nm] for nm in self.names)))
        out = {}
        for j, nm in enumerate(self.names):
            col = [r[j] for r in rows]
            out[nm] = np.array(col, dtype=object if any(isinstance(v, str) for v in col) else float)
        return out

    def describe(self) -> dict[str, str]:
        """Return the values of each variable as text."""
        return {nm: "values " + ", ".join(f"{v:g}" if not isinstance(v, str) else v for v in vals)
                for nm, vals in self.values.items()}


class _Sampled(Space):
    """A space of ``n`` points drawn from marginal distributions with a seed."""

    def __init__(self, distributions: Mapping[str, Distribution], n: int, seed: int | None = 0):
        self.names = _check_names(list(distributions))
        for nm in self.names:
            if not isinstance(distributions[nm], Distribution):
                raise ParameterError(f"variable {nm!r}: {distributions[nm]!r} is not a distribution; use "
                                     + ", ".join(c.__name__ for c in DISTRIBUTIONS.values()))
        if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
            raise ParameterError(f"n = {n!r} must be an integer >= 1 (number of points)")
        if seed is not None and (isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0):
            raise ParameterError(f"seed = {seed!r} must be an integer >= 0")
        self.distributions = dict(distributions)
        self.n = int(n)
        self.seed = None if seed is None else int(seed)

    def __len__(self) -> int:
        return self.n

    @abstractmethod
    def unit_samples(self) -> np.ndarray:
        """Return an (n, d) array of points in the open unit hypercube."""

    def samples(self) -> dict[str, np.ndarray]:
        """Return the points as one array per variable (deterministic for a given seed)."""
        u = self.unit_samples()
        return {nm: np.asarray(self.distributions[nm].ppf(u[:, j]), dtype=float) for j, nm in enumerate(self.names)}

    def describe(self) -> dict[str, str]:
        """Return the distribution of each variable as text."""
        return {nm: d.describe() for nm, d in self.distributions.items()}


class LatinHypercube(_Sampled):
    """Latin hypercube sample (scipy.stats.qmc): each variable's range is cut into
    ``n`` strata of equal probability and each stratum holds exactly one point.

    Parameters
    ----------
    distributions : mapping of str to Distribution
        Marginal distribution of each variable (``Uniform(low, high)`` for a
        plain range).
    n : int
        Number of points, >= 1.
    seed : int, default 0
        Seed of the random permutation and jitter: the same seed gives the same
        points.
    """

    method = "lhs"

    def unit_samples(self) -> np.ndarray:
        """Return the stratified (n, d) sample in the unit hypercube."""
        from scipy.stats import qmc

        d = len(self.names)
        rng = np.random.default_rng(self.seed)
        if "rng" in inspect.signature(qmc.LatinHypercube).parameters:
            sampler = qmc.LatinHypercube(d, rng=rng)
        else:  # scipy < 1.15
            sampler = qmc.LatinHypercube(d, seed=rng)
        return sampler.random(self.n)


class MonteCarlo(_Sampled):
    """Independent random sample (plain Monte Carlo) from the marginal distributions.

    Parameters
    ----------
    distributions : mapping of str to Distribution
        Distribution of each variable; variables are independent.
    n : int
        Number of points, >= 1.
    seed : int, default 0
        Seed of numpy's default generator: the same seed gives the same points.
    """

    method = "montecarlo"

    def unit_samples(self) -> np.ndarray:
        """Return the independent (n, d) uniform sample."""
        rng = np.random.default_rng(self.seed)
        u = rng.random((self.n, len(self.names)))
        return np.clip(u, 1e-12, 1 - 1e-12)  # keep the unbounded quantiles finite
