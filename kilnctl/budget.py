"""Size limits, checked before any work starts.

A simulation keeps every output sample in memory (the grid ``k*dt`` plus two
samples per mode switch), and a sweep builds one parameter set per point.  A
slip of the horizon (``t_end = 1e9`` seconds) or of a grid (``num = 10000000``)
would otherwise fill the machine's memory before anything is reported.  So
kilnctl counts first and refuses a run above a limit the user can raise:

========================  ==================  ==========================  =======================
limit                     default             keyword                     CLI option / environment
========================  ==================  ==========================  =======================
samples of one run        1 000 000           ``simulate(max_samples=)``  ``--max-samples``,
                                                                          ``KILNCTL_MAX_SAMPLES``
points of a sweep         100 000             ``Study(max_points=)``      ``--max-points``,
                                                                          ``KILNCTL_MAX_POINTS``
========================  ==================  ==========================  =======================

One million samples is 1000 s of the micro model at its 1 ms step (about
0.4 GB), or 5000 s of the macro model at 5 ms: far beyond a kiln start-up
(about 40 s).  The memory figure comes from :func:`run_bytes`, measured on
both models (the peak of a run, with its mode labels read or not, 0.78 to
0.97 of the formula).

Examples
--------
>>> from kilnctl.budget import estimate_run
>>> est = estimate_run(t_end=40.0, dt=1e-3, n_states=9, n_outputs=12, n_moded=5)
>>> est.samples
40001
>>> round(est.bytes / 1e6, 1)
14.7
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass

from .errors import ParameterError, SimulationError

__all__ = ["RunSize", "estimate_run", "run_bytes", "check_run_size", "check_points", "resolve_limit",
           "DEFAULT_MAX_SAMPLES", "DEFAULT_MAX_POINTS", "ENV_MAX_SAMPLES", "ENV_MAX_POINTS"]

#: default largest number of output samples of one simulation
DEFAULT_MAX_SAMPLES = 1_000_000
#: default largest number of points of one sweep
DEFAULT_MAX_POINTS = 100_000
#: environment variables that raise (or lower) the defaults
ENV_MAX_SAMPLES = "KILNCTL_MAX_SAMPLES"
ENV_MAX_POINTS = "KILNCTL_MAX_POINTS"


def resolve_limit(value, env: str, default: int, name: str) -> int:
    """Return the limit to apply: ``value`` if given, else the environment variable, else the default.

    Parameters
    ----------
    value : int or None
        Limit given by keyword or CLI option.
    env : str
        Name of the environment variable read when ``value`` is None.
    default : int
        Limit when neither is set.
    name : str
        Keyword name, for the error message.

    Returns
    -------
    int
        The limit, >= 1.

    Raises
    ------
    ParameterError
        A limit that is not a positive integer (names the keyword or variable).
    """
    where = name
    if value is None:
        text = os.environ.get(env, "").strip()
        if not text:
            return default
        where = f"environment variable {env}"
        try:
            value = int(float(text)) if float(text).is_integer() else text
        except ValueError:
            value = text
    if isinstance(value, bool) or not isinstance(value, int) or value < 1:
        raise ParameterError(f"{where} = {value!r} must be a whole number >= 1")
    return int(value)


def run_bytes(samples: int, n_states: int, n_outputs: int, n_moded: int) -> int:
    """Return the peak memory of a simulation's recorded output [bytes].

    Per sample, while the run records: time and mode code, the scaled
    states (recorded, then concatenated), the outputs and the states in
    physical units.  The mode labels (one six-character string, 24 bytes,
    per moded component) are spelled out when the response's ``modes`` are
    first read, after the recording buffers are freed: the response then
    holds time, states, outputs and labels, counted when that is more.

    Parameters
    ----------
    samples : int
        Output samples.
    n_states, n_outputs, n_moded : int
        States, outputs and moded components of the plant.

    Returns
    -------
    int
    """
    recording = 8 * (2 * n_states + 2 * n_outputs + 4)
    read = 8 * (n_states + n_outputs + 1) + 24 * n_moded
    return int(samples) * max(recording, read)


@dataclass(frozen=True)
class RunSize:
    """Estimated size of one simulation run.

    Attributes
    ----------
    samples : int
        Output samples: the grid ``k*dt`` from 0 to ``t_end`` plus two per
        mode switch allowed.
    bytes : int
        Peak memory of the recorded output [bytes] (:func:`run_bytes`).
    """

    samples: int
    bytes: int


def estimate_run(t_end: float, dt: float, n_states: int, n_outputs: int, n_moded: int,
                 max_events: int = 0) -> RunSize:
    """Estimate the samples and memory of a run before it starts.

    Parameters
    ----------
    t_end : float
        Simulated time [s].
    dt : float
        Output step [s].
    n_states, n_outputs, n_moded : int
        States, outputs and moded components of the plant.
    max_events : int, default 0
        Mode switches allowed (each adds two samples at most).

    Returns
    -------
    RunSize
    """
    grid = min(t_end / dt, 1e18)  # capped: t_end = 1e300 must give a number, not an overflow
    samples = math.floor(grid) + 1 + 2 * int(max_events)
    return RunSize(samples=samples, bytes=run_bytes(samples, n_states, n_outputs, n_moded))


def _size(nbytes: float) -> str:
    for unit, scale in (("TB", 1e12), ("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if nbytes >= scale:
            return f"{nbytes / scale:.3g} {unit}"
    return f"{nbytes:.0f} B"


def check_run_size(t_end: float, dt: float, n_states: int, n_outputs: int, n_moded: int,
                   max_events: int = 0, max_samples: int | None = None, *,
                   t_end_name: str = "t_end (CLI --t-end)",
                   limit_name: str = "max_samples= (CLI --max-samples") -> RunSize:
    """Refuse a simulation whose output would exceed the sample limit.

    Parameters
    ----------
    t_end : float
        Simulated time [s].
    dt : float
        Output step [s].
    n_states, n_outputs, n_moded : int
        States, outputs and moded components of the plant.
    max_events : int, default 0
        Mode switches allowed.
    max_samples : int, optional
        The limit; default: ``KILNCTL_MAX_SAMPLES`` or
        :data:`DEFAULT_MAX_SAMPLES`.
    t_end_name, limit_name : str
        How the caller spells the horizon and the limit, for the message.

    Returns
    -------
    RunSize
        The estimate, when within the limit.

    Raises
    ------
    SimulationError
        Above the limit: names ``t_end``, ``dt``, the estimate, and how to
        raise the limit.
    """
    limit = resolve_limit(max_samples, ENV_MAX_SAMPLES, DEFAULT_MAX_SAMPLES, "max_samples (CLI --max-samples)")
    est = estimate_run(t_end, dt, n_states, n_outputs, n_moded, max_events)
    grid = est.samples - 2 * int(max_events)
    if grid > limit:
        at_limit = run_bytes(limit, n_states, n_outputs, n_moded)
        longest = (limit - 1) * dt
        raise SimulationError(
            f"t_end = {t_end:g} s with dt = {dt:g} s needs {'more than ' if grid >= 1e18 else ''}{grid:.3g} output samples (about {_size(est.bytes)} of "
            f"memory), above the limit of {limit:,} samples ({_size(at_limit)}): shorten {t_end_name} to at "
            f"most {longest:.4g} s or raise dt, or raise the limit with {limit_name}, "
            f"environment {ENV_MAX_SAMPLES}) if the machine has the memory")
    return est


def check_points(n_points: float, max_points: int | None = None, what: str = "the sweep") -> int:
    """Refuse a sweep with more points than the limit, before its points are built.

    Parameters
    ----------
    n_points : int or float
        Number of points (a float for a product too large for exact counting).
    max_points : int, optional
        The limit; default: ``KILNCTL_MAX_POINTS`` or :data:`DEFAULT_MAX_POINTS`.
    what : str, default 'the sweep'
        What is counted, for the message (e.g. ``[parameters.m_v] num``).

    Returns
    -------
    int
        The limit applied.

    Raises
    ------
    ParameterError
        Above the limit: says how many points and how to raise the limit.
    """
    limit = resolve_limit(max_points, ENV_MAX_POINTS, DEFAULT_MAX_POINTS, "max_points (CLI --max-points)")
    if n_points > limit:
        raise ParameterError(
            f"{what} has {n_points:,.0f} points, above the limit of {limit:,}: use fewer values (num, n), or "
            f"raise the limit with max_points= (CLI --max-points, environment {ENV_MAX_POINTS}) if you mean it")
    return limit
