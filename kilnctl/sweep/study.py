"""A parametric study: a parameter space, the simulation to run at each point, its outputs.

Examples
--------
>>> from kilnctl.sweep import Study, Grid
>>> st = Study(Grid({"m_v": [290e3, 580e3]}), outputs=["final_current_A"], model="macro", t_end=40.0)
>>> [p.m_v for p in st.parameter_sets()]
[290000.0, 580000.0]
>>> Study(Grid({"m_vv": [1.0]}))
Traceback (most recent call last):
...
kilnctl.errors.ParameterError: unknown sweep variable 'm_vv': did you mean 'm_v' or ...?...
"""

from __future__ import annotations

import hashlib
import json
import math
from functools import lru_cache
from pathlib import Path
from typing import Callable, Mapping, Sequence

import numpy as np

from ..errors import ParameterError, close_matches_hint
from ..params import SPECS, Parameters
from ..structure import Structure
from .result import OUTPUTS
from .space import Space

__all__ = ["Study", "OUTPUTS", "SIM_OPTIONS"]

#: keyword options of :func:`kilnctl.simulate.simulate` a study may set for every point
SIM_OPTIONS = ("dt", "rtol", "atol", "event_tol", "max_events", "n_grid", "method", "max_step", "max_samples")

#: source files whose content decides a simulation's result; their hash is part of every cache key
_CODE_PARTS = ("params.py", "gains.py", "structure.py", "measure/effects.py", "simulate.py", "response.py", "linear.py",
               "model", "design")


@lru_cache(maxsize=1)
def code_fingerprint() -> str:
    """Return a hash of the kilnctl sources that decide simulation results.

    A cached sweep point is reused only while this hash is unchanged, so a
    changed model never serves stale results.

    Returns
    -------
    str
        16 hex digits.
    """
    root = Path(__file__).resolve().parents[1]
    h = hashlib.sha256()
    for part in _CODE_PARTS:
        p = root / part
        files = sorted(p.rglob("*")) if p.is_dir() else [p]
        for f in files:
            if f.suffix in (".py", ".c") and f.is_file():
                h.update(str(f.relative_to(root)).encode())
                h.update(f.read_bytes())
    return h.hexdigest()[:16]


class Study:
    """A parametric study of kiln start-ups.

    Parameters
    ----------
    space : Grid, LatinHypercube or MonteCarlo
        The points to simulate.  Each variable is a parameter name (value in
        the parameter's unit) or a factor of ``factors``.
    outputs : sequence of str or mapping of str to callable, default ('peak_stress_Pa',)
        Keys of :data:`OUTPUTS` (summary values of each run), or a mapping from
        a column name to a function ``f(response) -> float`` (module-level, so
        worker processes can import it) for anything else.
    model : {'macro', 'micro'} or Structure, default 'micro'
        Plant of the paper to simulate at each point, or a
        :class:`kilnctl.structure.Structure` (then without ``effects`` and
        ``remove``).
    t_end : float, default 40.0
        Simulated time of each start-up [s].
    base : Parameters, optional
        Parameters the space varies (default: the paper's Table 1).
    effects, remove : sequence of str
        Effects (catalogue or component names) to add to the model, and
        components to take out of it (as in :class:`kilnctl.structure.Structure`).
    factors : mapping of str to sequence of str, optional
        Factor variables: ``{"friction": ("mu_c", "mu_s")}`` makes the variable
        ``friction`` [-] multiply the base values of both coefficients, so they
        vary together (and ``mu_c <= mu_s`` keeps holding).
    options : mapping, optional
        Simulation options for every point, from :data:`SIM_OPTIONS`
        (``dt`` [s], ``rtol``, ``atol`` ...).
    name : str, default 'sweep'
        Name shown in the progress bar and in the result.
    redesign : bool, default False
        With ``base.gains == 'design'``: False designs the PID gains once, for
        the base parameters, and keeps them at every point (a kiln's
        controller is not retuned as its burden or backlash changes, and one
        design is far cheaper than one per point); True designs them anew at
        every point.
    max_points : int, optional
        Largest number of points, checked before any point is built; default:
        the environment variable ``KILNCTL_MAX_POINTS`` or 100 000
        (:mod:`kilnctl.budget`).

    Raises
    ------
    ParameterError
        An unknown variable, output or option (with close matches), a factor
        on a non-numeric parameter, a non-positive ``t_end``, or more points
        than ``max_points``.
    SimulationError
        A start-up whose output would exceed the sample limit (``t_end``,
        ``dt`` and the ``max_samples`` option; see :mod:`kilnctl.budget`).
    ModelError
        An unknown model or component.
    """

    def __init__(self, space: Space, outputs: Sequence[str] | Mapping[str, Callable] = ("peak_stress_Pa",), *,
                 model: str = "micro", t_end: float = 40.0, base: Parameters | None = None,
                 effects: Sequence[str] = (), remove: Sequence[str] = (),
                 factors: Mapping[str, Sequence[str]] | None = None, options: Mapping | None = None,
                 name: str = "sweep", redesign: bool = False, max_points: int | None = None):
        from ..budget import check_points

        if not isinstance(space, Space):
            raise ParameterError(f"space must be a Grid, LatinHypercube or MonteCarlo, not {type(space).__name__}")
        self.space = space
        check_points(len(space), max_points, what="the study")
        self.base = Parameters() if base is None else base
        Parameters.require(self.base, "base")
        if isinstance(model, Structure):
            if effects or remove:
                raise ParameterError("give the effects inside the Structure (Structure.with_effects), not as "
                                     "effects= or remove= beside it")
            self.structure = model
        else:
            self.structure = Structure(model, tuple(effects), tuple(remove))  # checks model and names
        #: the structure's parts, as the cache key and the reproduce command name them
        self.model, self.effects, self.remove = self.structure.model, self.structure.effects, self.structure.remove
        if isinstance(t_end, bool) or not isinstance(t_end, (int, float)) or not math.isfinite(t_end) or t_end <= 0:
            raise ParameterError(f"t_end = {t_end!r} must be a finite number of seconds > 0")
        self.t_end = float(t_end)
        self.name = str(name)
        self.redesign = bool(redesign)
        self._controlled: Parameters | None = None
        self.factors = {k: tuple(v) for k, v in (factors or {}).items()}
        self._check_factors()
        self._check_variables()
        self.outputs, self.custom_outputs = self._check_outputs(outputs)
        self.options = dict(options or {})
        for k in self.options:
            if k not in SIM_OPTIONS:
                raise ParameterError(f"unknown simulation option {k!r}: {close_matches_hint(k, SIM_OPTIONS)}")
        self._check_run_size()

    # --- validation -------------------------------------------------------------------------
    def _check_factors(self):
        for fname, targets in self.factors.items():
            if fname in SPECS:
                raise ParameterError(f"factor {fname!r} has the name of a parameter: choose another name")
            if not targets:
                raise ParameterError(f"factor {fname!r} names no parameter to multiply")
            for t in targets:
                if t not in SPECS:
                    raise ParameterError(f"factor {fname!r}: unknown parameter {t!r}: {close_matches_hint(t, SPECS)}")
                if SPECS[t].is_option:
                    raise ParameterError(f"factor {fname!r}: parameter {t!r} is an option, not a number")

    def _check_variables(self):
        known = list(SPECS) + list(self.factors)
        for nm in self.space.names:
            if nm not in known:
                raise ParameterError(f"unknown sweep variable {nm!r}: {close_matches_hint(nm, known)} "
                                     "(a variable is a parameter name or a factor declared in factors=)")
        gain_vars = {"k_p", "k_I", "k_D"} & set(self.space.names)
        if gain_vars and self.redesign and self.base.gains == "design":
            raise ParameterError(f"sweeping {sorted(gain_vars)} has no effect with redesign=True and gains = "
                                 "'design': the design sets the gains at every point; use redesign=False")
        unused = set(self.factors) - set(self.space.names)
        if unused:
            raise ParameterError(f"factor(s) {sorted(unused)} declared but not in the space")

    def _check_run_size(self):
        """Refuse a start-up too long for memory before the first point is built (same check as simulate)."""
        from ..simulate import DEFAULT_DT, _check_horizon, _check_size

        opt = self.options
        dt = opt.get("dt", DEFAULT_DT.get(self.model, 1e-3))
        _check_horizon(self.t_end, dt)
        events = opt.get("max_events", 5000)
        events = events if isinstance(events, int) and not isinstance(events, bool) and events > 0 else 0
        # n_grid, rtol, atol do not change the plant's size: the defaults serve (a bad value fails at the point)
        _check_size(self.structure.components(), self.base, self.t_end, dt, events,
                    opt.get("max_samples"), 500, 1e-7, 1e-8, t_end_name="t_end",
                    limit_name="max_samples = N in [options] of the spec (Study(options={'max_samples': N})")

    @staticmethod
    def _check_outputs(outputs):
        if isinstance(outputs, str):
            outputs = [outputs]
        if isinstance(outputs, Mapping):
            custom = dict(outputs)
            for k, f in custom.items():
                if not callable(f):
                    raise ParameterError(f"output {k!r}: {f!r} is not a function of the response")
            return tuple(custom), custom
        outputs = tuple(outputs)
        if not outputs:
            raise ParameterError("a study needs at least one output; choose from " + ", ".join(OUTPUTS))
        for k in outputs:
            if k not in OUTPUTS:
                raise ParameterError(f"unknown output {k!r}: {close_matches_hint(k, OUTPUTS)}")
        if len(set(outputs)) != len(outputs):
            raise ParameterError(f"outputs repeat a name: {list(outputs)}")
        return outputs, {}

    # --- points -----------------------------------------------------------------------------
    @property
    def variables(self) -> tuple[str, ...]:
        """Names of the swept variables, in the space's order."""
        return self.space.names

    def __len__(self) -> int:
        return len(self.space)

    def samples(self) -> dict[str, np.ndarray]:
        """Return the values of every variable at every point (see :meth:`Space.samples`)."""
        return self.space.samples()

    def controlled_base(self) -> Parameters:
        """Return the base parameters with the PID gains every point starts from.

        Returns
        -------
        Parameters
            ``base`` itself with ``redesign=True`` or given gains; otherwise
            ``base`` with the gains designed for it (``gains = 'given'``).
        """
        if self._controlled is None:
            if self.redesign or self.base.gains == "given":
                self._controlled = self.base
            else:
                from ..gains import resolve_gains

                self._controlled = resolve_gains(self.base)
        return self._controlled

    def params_at(self, values: Mapping[str, float | str]) -> Parameters:
        """Return the parameter set of one point.

        Parameters
        ----------
        values : mapping
            Value of each variable (parameter values in their unit, factors [-]).

        Returns
        -------
        Parameters
            :meth:`controlled_base` with the point's values; a factor
            multiplies the base value of each parameter it names (two factors
            on one parameter multiply).
        """
        base = self.controlled_base()
        changes: dict[str, float | str] = {}
        for nm, v in values.items():
            if nm in self.factors:
                for t in self.factors[nm]:
                    changes[t] = changes.get(t, base[t]) * float(v)
            else:
                changes[nm] = v.item() if isinstance(v, np.generic) else v
        return base.replace(**changes)

    def parameter_sets(self) -> list[Parameters]:
        """Return the parameter set of every point, checked before any simulation runs.

        Returns
        -------
        list of Parameters

        Raises
        ------
        ParameterError
            When some points are impossible parameter sets: says how many, and
            shows the first with its reason.
        """
        cols = self.samples()
        out, bad = [], []
        for i in range(len(self)):
            point = {nm: cols[nm][i] for nm in self.variables}
            try:
                out.append(self.params_at(point))
            except ParameterError as exc:
                bad.append((i, point, exc))
        if bad:
            i, point, exc = bad[0]
            shown = {k: (float(v) if not isinstance(v, str) else v) for k, v in point.items()}
            raise ParameterError(
                f"{len(bad)} of {len(self)} points of the sweep are impossible parameter sets; first: point {i} "
                f"{shown}: {exc}. Narrow the ranges, or vary coupled parameters together with a factor "
                "(e.g. factors={'friction': ('mu_c', 'mu_s')})")
        return out

    # --- tasks and cache keys -------------------------------------------------------------------
    def task(self, params: Parameters) -> dict:
        """Return the picklable description of one simulation (what a worker runs).

        Parameters
        ----------
        params : Parameters
            The point's parameters.

        Returns
        -------
        dict
            ``key`` (cache key), ``params`` (dict), ``structure``, ``t_end`` [s],
            ``options`` and ``custom`` outputs.
        """
        ident = {
            "format": 1,
            "code": code_fingerprint(),
            "model": self.model,
            "t_end": self.t_end,
            "effects": list(self.effects),
            "remove": list(self.remove),
            "options": self.options,
            "params": params.as_dict(),
            "custom": sorted((k, f"{f.__module__}.{getattr(f, '__qualname__', repr(f))}")
                             for k, f in self.custom_outputs.items()),
        }
        text = json.dumps(ident, sort_keys=True, allow_nan=False)
        return {"key": hashlib.sha256(text.encode()).hexdigest()[:32], "params": ident["params"],
                "structure": self.structure, "t_end": self.t_end, "options": self.options,
                "custom": self.custom_outputs}

    def describe(self) -> str:
        """Return a few lines saying what the study runs.

        Returns
        -------
        str
        """
        lines = [f"study {self.name!r}: {len(self)} {self.model} start-ups of {self.t_end:g} s "
                 f"({self.space.method})"]
        for nm, txt in self.space.describe().items():
            unit = SPECS[nm].unit if nm in SPECS else "factor on " + ", ".join(self.factors[nm])
            lines.append(f"  {nm:<14} {txt}  [{unit}]")
        if self.base.gains == "design":
            lines.append("  PID gains      " + ("designed at every point" if self.redesign else
                                                "designed once for the base parameters"))
        lines.append("  outputs        " + ", ".join(self.outputs))
        return "\n".join(lines)

    def run(self, executor=None, *, workers: int | None = None, cache=None, progress: bool = True):
        """Run the study; see :func:`kilnctl.sweep.run_sweep` for the arguments.

        Returns
        -------
        SweepResult
        """
        from .engine import run_sweep  # inside: the engine runs studies, a study only hands itself over

        return run_sweep(self, executor, workers=workers, cache=cache, progress=progress)

