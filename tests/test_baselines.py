"""kilnctl against a second method: the same equations written independently for scipy.

Truth: ``benchmarks.baselines.ScipyHybrid`` is an independent implementation of
the hybrid plant (plain Python right-hand side per mode, scipy ``solve_ivp``
with terminal events and restarts, its own guard and Filippov logic).  Two
independent implementations at rtol 1e-8 must agree on the event sequence,
the event times and the currents far below the differences a user would read.
"""

import numpy as np
import pytest

from benchmarks.baselines import ControlSmooth, ScipyHybrid, summarize, summary_errors
from kilnctl import Parameters
from kilnctl.simulate import simulate

GIVEN = dict(gains="given", k_p=2.0, k_I=5.0, k_D=0.01)


def _events(r):
    return [(e.kind, e.component, e.from_mode, e.to_mode) for e in r.events]


def _away_from_events(r, margin=1e-2):
    """Samples more than ``margin`` seconds from every event (signals jump at a switch)."""
    if not r.events:
        return np.ones(len(r.t), bool)
    return np.min(np.abs(r.t[:, None] - np.array([e.t for e in r.events])[None, :]), axis=1) > margin


def _run_both(p, model, t_end, method="DOP853"):
    r = simulate(p, model=model, t_end=t_end)
    b = ScipyHybrid(p, model).simulate(t_end, method=method)
    return r, b


@pytest.mark.parametrize("law", ["torque", "paper"])
def test_macro_events_and_currents_agree_with_scipy(law):
    # torque law: ramp end, breakaway, re-stick; printed law: breakaway -> Filippov held -> breakaway
    p = Parameters(friction_law=law, **GIVEN)
    r, b = _run_both(p, "macro", 20.0)
    assert _events(r) == [e[1:] for e in b.events]
    assert len(r.events) >= 3
    assert [e.t for e in r.events] == pytest.approx([e[0] for e in b.events], abs=1e-6)
    err = summary_errors(summarize(r.t, r.outputs, r.events), summarize(b.t, b.outputs, b.events))
    assert err["peak_current"] < 1e-6 and err["final_current"] < 1e-6 and err["event_times"] < 1e-6
    # the whole current trace, on kilnctl's samples (away from the event instants themselves)
    i_b = np.interp(r.t, b.t, b.outputs["i_a"])
    far = _away_from_events(r)
    assert np.max(np.abs(r["i_a"][far] - i_b[far])) < 1e-4 * np.max(np.abs(r["i_a"]))


def test_macro_gear_stress_agrees_while_the_burden_slips():
    p = Parameters(friction_law="torque", **GIVEN)
    r, b = _run_both(p, "macro", 20.0)
    slip = np.isin(r.burden_mode, ("slip_pos", "slip_neg")) & _away_from_events(r)
    assert slip.sum() > 100
    s_b = np.interp(r.t[slip], b.t, b.outputs["sigma"])
    assert np.max(np.abs(r["sigma"][slip] - s_b)) < 1e-5 * np.max(np.abs(s_b))


def test_macro_gear_stress_while_the_burden_sticks():
    # Truth: while stuck, the reducer turns kiln and burden: W_t*R_o = (J_o+J_v)*acc + m_v*g*L*sin(psi) + T_brg
    p = Parameters(friction_law="torque", **GIVEN)
    r, b = _run_both(p, "macro", 15.0)
    far = _away_from_events(r)
    s_b = np.interp(r.t[far], b.t, b.outputs["sigma"])
    assert np.max(np.abs(r["sigma"][far] - s_b)) < 1e-5 * np.max(np.abs(s_b))


def test_micro_backlash_events_agree_with_scipy():
    # backlash take-up at start: contact / separation impacts, then steady contact
    p = Parameters(friction_law="torque", **GIVEN)
    r, b = _run_both(p, "micro", 3.0, method="LSODA")
    assert _events(r) == [e[1:] for e in b.events]
    kinds = [e.kind for e in r.events]
    assert kinds.count("contact") >= 3 and kinds.count("separation") >= 2
    assert [e.t for e in r.events] == pytest.approx([e[0] for e in b.events], abs=2e-5)
    err = summary_errors(summarize(r.t, r.outputs, r.events), summarize(b.t, b.outputs, b.events))
    assert err["peak_current"] < 1e-5 and err["peak_stress"] < 1e-5


def test_smooth_python_control_model_is_close_to_the_hybrid_one():
    # baseline (b) replaces stick-slip and the limits by smooth laws: close, not equal
    p = Parameters(friction_law="torque", **GIVEN)
    b = ScipyHybrid(p, "macro").simulate(8.0, method="DOP853")
    c = ControlSmooth(p, "macro").simulate(8.0)
    err = summary_errors(summarize(c.t, c.outputs), {**summarize(b.t, b.outputs, b.events), "event_times": None})
    assert err["peak_current"] < 1e-3 and err["final_current"] < 1e-3
