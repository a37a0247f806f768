"""Root-locus design of the kiln speed controller (the paper's PID, eq. 21).

>>> from kilnctl import Parameters
>>> from kilnctl.design import design_pid
>>> result = design_pid(Parameters())
>>> result.meets_requirements
True

See ``docs/tutorial_design.md``.
"""

from .analysis import ConditionReport, analyse, damping, dominant_poles
from .gains import GAIN_UNITS, PIDGains
from .locus import (ACCRETION_RANGE, LocusBranches, ParameterLocusData, RootLocusData, StepResponseData,
                    parameter_locus, root_locus, step_responses, vary)
from .pid import DOMINANCE_RATIO, DesignResult, RequirementsNotMetError, design_pid, gains_for, place_poles
from .requirements import WN_FRACTION_OF_TORSIONAL_MODE, Requirements, torsional_mode_frequency

__all__ = [
    "PIDGains", "GAIN_UNITS", "Requirements", "torsional_mode_frequency", "WN_FRACTION_OF_TORSIONAL_MODE",
    "ConditionReport", "analyse", "damping", "dominant_poles",
    "DesignResult", "RequirementsNotMetError", "design_pid", "gains_for", "place_poles", "DOMINANCE_RATIO",
    "RootLocusData", "LocusBranches", "root_locus", "StepResponseData", "step_responses",
    "ParameterLocusData", "parameter_locus", "vary", "ACCRETION_RANGE",
]
