"""Start-up ramp optimization: least gear bending stress, verified on the full hybrid plant.

The problem is declared once (:class:`RampProblem`: profile, objective,
constraints, scenarios); :func:`optimize_ramp` solves it with CasADi/IPOPT on
the smoothed micro model (a continuation sharpens the smoothing) and
re-simulates the optimum on the exact hybrid plant.  See
``docs/optimization.md`` for the formulation and ``docs/tutorial_ramp.md``
for a walk-through.

>>> from kilnctl import Parameters
>>> from kilnctl.optimize import RampProblem
>>> RampProblem(Parameters(gains="given"), profile="pwl:3", t_max=10.0).profile.label
'pwl:3'
"""

from ..model import ramps, smooth  # noqa: F401  (register the profile and smooth components)
from .problem import OBJECTIVES, Profile, RampProblem, Scenario, default_scenarios
from .result import RampResult, StageLog
from .solve import DEFAULT_STAGES, VERIFY_RTOL, RampSolveError, Stage, optimize_ramp
from .transcription import TRANSCRIPTIONS, smooth_max
from .verify import StartupMeasures, measure_hybrid

__all__ = ["Profile", "RampProblem", "Scenario", "default_scenarios", "OBJECTIVES", "RampResult", "StageLog",
           "Stage", "DEFAULT_STAGES", "VERIFY_RTOL", "RampSolveError", "optimize_ramp", "TRANSCRIPTIONS",
           "smooth_max", "StartupMeasures", "measure_hybrid"]
