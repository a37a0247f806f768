"""Long ramp optimizations: a finite smooth maximum, progress lines, and Ctrl-C inside IPOPT's evaluations."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from kilnctl.optimize import RampProblem, RampSolveError, Stage, optimize_ramp
from kilnctl.optimize.transcription import EXP_CAP, exp_capped
from kilnctl.params import Parameters
from kilnctl.simulate import resolve_gains

P = resolve_gains(Parameters())


def test_capped_exponential_is_exp_below_the_cap_and_its_tangent_above():
    # independent truth: numpy's exp below the cap, the tangent line y = e^c (1 + x - c) above it
    x = ca.SX.sym("x")
    f = ca.Function("f", [x], [exp_capped(x), ca.jacobian(exp_capped(x), x)])
    for v in (-50.0, 0.0, 3.0, 150.0, EXP_CAP):
        val, der = (float(o) for o in f(v))
        assert val == pytest.approx(np.exp(v), rel=1e-12) and der == pytest.approx(np.exp(v), rel=1e-12)
    for v in (EXP_CAP + 0.5, 800.0, 1e6):  # exp(800) overflows to inf; the tangent stays finite
        val, der = (float(o) for o in f(v))
        assert np.isfinite(val) and np.isfinite(der)
        assert val == pytest.approx(np.exp(EXP_CAP) * (1 + v - EXP_CAP), rel=1e-12)
        assert der == pytest.approx(np.exp(EXP_CAP), rel=1e-12)


def test_progress_lines_and_interrupt_inside_an_evaluation(monkeypatch):
    prob = RampProblem(P, profile="constant", t_max=3.0, horizon=3.5, objective="dynamic")
    stage = (Stage(smooth_ds=1e-5, smooth_v=1e-3, ramp_corner=0.2, beta=100.0),)
    lines = []
    with pytest.raises(RampSolveError, match="Maximum_Iterations_Exceeded"):  # two iterations: short test
        optimize_ramp(prob, stages=stage, verify=False, progress=lines.append, ipopt_options={"max_iter": 2})
    assert any("stage 1 of 1" in ln for ln in lines) and any("after 2 iterations" in ln for ln in lines)

    # Ctrl-C while IPOPT evaluates the objective: CasADi turns the KeyboardInterrupt raised in the Python
    # callback into a failed evaluation; optimize_ramp must raise it again, not report a solver failure
    import kilnctl.optimize.sensitivity as sens

    calls = {"n": 0}
    real = sens.CaseCallback._evaluate

    def interrupted_on_the_third(self, z):
        calls["n"] += 1
        if calls["n"] == 3:
            raise KeyboardInterrupt
        return real(self, z)

    monkeypatch.setattr(sens.CaseCallback, "_evaluate", interrupted_on_the_third)
    with pytest.raises(KeyboardInterrupt):
        optimize_ramp(prob, stages=stage, verify=False)


def test_max_rate_bounds_every_rate_of_the_reference():
    # truth: the definition of the option -- every pwl segment and the constant rate, only the S-curve's
    # acceleration (not its jerk)
    from kilnctl.errors import ParameterError
    from kilnctl.optimize.problem import RATE_BOUNDS

    lo, hi = RampProblem(P, profile="pwl:3", max_rate=100.0).bounds()
    assert list(hi) == [100.0] * 3 and list(lo) == [RATE_BOUNDS[0]] * 3
    assert list(RampProblem(P, profile="pwl:3").bounds()[1]) == [RATE_BOUNDS[1]] * 3
    lo, hi = RampProblem(P, profile="scurve", max_rate=100.0).bounds()
    assert hi[0] == 100.0 and hi[1] > 100.0
    for bad in (0.0, -5.0, 1e6, float("nan")):
        with pytest.raises(ParameterError, match="max_rate"):
            RampProblem(P, profile="pwl:2", max_rate=bad)
