"""Parametric studies at scale: grids, Latin hypercubes and Monte Carlo samples of start-ups.

A :class:`Study` declares a parameter space and the outputs to tabulate;
:func:`run_sweep` (or ``study.run()``) simulates every point in parallel on
local processes or a Dask cluster, caches finished points so that an
interrupted sweep resumes, and returns a :class:`SweepResult` with a pandas
table, a summary, file writers and ``.plot()``.

>>> from kilnctl.sweep import Study, Grid
>>> study = Study(Grid({"m_v": [290e3, 580e3]}), outputs=["final_current_A"], model="macro", t_end=40.0)
>>> result = study.run(executor="serial", progress=False)
>>> result.table[["m_v", "final_current_A", "status"]].round(0)
            m_v  final_current_A status
point
0      290000.0            420.0     ok
1      580000.0            842.0     ok

Command line: ``kilnctl sweep SPEC.toml`` (format in :mod:`kilnctl.sweep.spec`).
Needs the optional dependencies: ``pip install 'kilnctl[sweep]'``.
"""

from .confirm import WorstPoint, confirm_worst
from .engine import EXECUTORS, PointCache, SweepInterrupted, run_point, run_sweep
from .limits import GIRTH_GEAR_HARDNESS_HB, allowable_bending_stress
from .result import SweepResult, wilson_interval
from .space import DISTRIBUTIONS, Grid, LatinHypercube, LogUniform, MonteCarlo, Normal, Triangular, TruncNormal, Uniform
from .spec import METHODS, SpecError, load_spec, study_from_dict
from .study import OUTPUTS, SIM_OPTIONS, Study, code_fingerprint

__all__ = [
    "Study", "run_sweep", "SweepResult", "Grid", "LatinHypercube", "MonteCarlo",
    "Uniform", "LogUniform", "Normal", "TruncNormal", "Triangular", "DISTRIBUTIONS",
    "load_spec", "study_from_dict", "SpecError", "METHODS", "OUTPUTS", "SIM_OPTIONS", "EXECUTORS",
    "PointCache", "run_point", "SweepInterrupted", "wilson_interval", "code_fingerprint",
    "allowable_bending_stress", "GIRTH_GEAR_HARDNESS_HB", "WorstPoint", "confirm_worst",
]
