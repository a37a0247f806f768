"""A logged speed reference that is not one ramp and hold: the model follows it through knots.

Truths: the reference through knots against numpy's linear interpolation of the same knots (a second
implementation); the knots found in a logged two-stage reference and a ramp down against the corners the
record was made with; and red team 10's independent plant (benchmarks/red10_plant.py, another kiln than the
paper's, its own reference generator) against kilnctl's model following the logged reference: the red team
found kilnctl fitting one straight line through a two-stage reference (17 % current fit at the true values).
"""

import casadi as ca
import numpy as np
import pytest

from benchmarks.red10_plant import Plant, kiln_A
from kilnctl import Parameters
from kilnctl.measure import compare
from kilnctl.measure.io import Measurement
from kilnctl.measure.reference import fit_knots, knots_values, scurve_values
from kilnctl.model.ramps import knots_reference


def test_reference_through_knots_is_the_polyline():
    """The sum of ramp functions equals np.interp through (0, 0) and the knots, holds the last value after
    them, and its derivative is the segment's slope."""
    times, values = [5.0, 18.0, 26.0, 31.0], [500.0, 500.0, 900.0, 600.0]
    t = ca.SX.sym("t")
    f = ca.Function("f", [t], list(knots_reference(t, times, values)))
    tt = np.linspace(0.0, 40.0, 4001)
    ev, evd = (np.asarray(v, float).ravel() for v in f(ca.DM(tt).T))
    np.testing.assert_allclose(ev, np.interp(tt, [0.0] + times, [0.0] + values), atol=1e-9)
    mid = np.array([2.5, 10.0, 22.0, 28.0, 35.0])  # one point inside each segment and after the last knot
    np.testing.assert_allclose(np.asarray(f(ca.DM(mid).T)[1], float).ravel(), [100.0, 0.0, 50.0, -60.0, 0.0])


@pytest.mark.parametrize("corners", [
    [(1.0, 0.0), (7.0, 600.0), (20.0, 600.0), (28.0, 1000.0)],          # two rates with a hold between
    [(1.0, 0.0), (16.0, 750.0), (34.0, 750.0), (39.0, 500.0)],          # a ramp down before the end
    [(0.6, 0.0), (5.1, 300.0), (13.7, 1000.0)],                         # two rates, no hold
])
def test_fit_knots_finds_the_corners(corners):
    """The knots of a logged reference (50 Hz, 45 s) are its corners after the start, to a millisecond and a
    hundredth of an rpm, whatever the samples' phase against the corners."""
    t = np.arange(0.0, 45.0, 0.02) + 0.0073
    tc, wc = zip(*corners)
    ref = np.interp(t, tc, wc)
    straight = np.clip((wc[1] / (tc[1] - tc[0])) * (t - tc[0]), 0.0, max(wc))
    fit = fit_knots(t, ref, tc[0], straight)
    assert fit is not None
    assert fit.t0 == pytest.approx(tc[0], abs=1e-3)
    expect_t = [c - tc[0] for c in tc[1:]]
    held = len(wc) > 2 and wc[-1] == wc[-2]
    np.testing.assert_allclose(fit.times, expect_t[:-1] if held else expect_t, atol=1e-3)
    np.testing.assert_allclose(fit.values, (wc[1:-1] if held else wc[1:]), atol=1e-2)
    assert fit.rms < 0.05


def test_fit_knots_leaves_one_ramp_and_an_s_curve_alone():
    """A straight ramp and hold, or the S-curve the tools already follow, is not replaced by knots (the records
    of every earlier red team keep their model)."""
    t = np.arange(0.0, 40.0, 0.02)
    ramp = np.clip(74.0 * (t - 1.0), 0.0, 500.0)
    assert fit_knots(t, ramp, 1.0, ramp) is None
    s = scurve_values(t, 1.0, 74.0, 60.0, 500.0)
    assert fit_knots(t, s, 1.0, s) is None
    # a reference the straight ramp misses by less than KNOTS_FROM (a rounded corner) is left to the S-curve
    assert fit_knots(t, s, 1.6, np.clip(74.0 * (t - 1.6), 0.0, 500.0)) is None


def _params(p, top, rate):
    keys = ("R_a", "L_a", "k_i", "k_b", "J_m", "B_m", "k_p", "k_I", "k_D", "V_max", "I_max", "J_o", "J_v", "m_v",
            "L", "R", "mu_c", "mu_s", "mu_brg", "P", "l_brg", "k_brg", "n")
    return Parameters(gains="given", ramp_rate=rate, omega_ref=top, **{k: p[k] for k in keys})


@pytest.mark.parametrize("ref", [
    [(0.0, 0.0), (1.0, 0.0), (7.0, 600.0), (20.0, 600.0), (28.0, 1000.0)],
    [(0.0, 0.0), (1.0, 0.0), (11.0, 1000.0), (26.0, 1000.0), (31.0, 750.0)],
])
def test_kilnctl_follows_the_red_teams_reference(ref):
    """Red team 10's kiln A (not the paper's) under a two-stage reference and a ramp down, no noise: kilnctl's
    model, given the plant's values and the logged reference, fits its current to 99.9 % (the red team
    measured 17 % on the two-stage record before); the knots are the reference's corners."""
    p = kiln_A()
    p["ref"] = ref
    out = Plant(p).run(36.0, 1e-3)
    t = np.arange(0.0, 36.0, 0.02)
    i, w = np.interp(t, out["t"], out["i"]), np.interp(t, out["t"], out["w"])
    ref_t = np.interp(t, *zip(*ref))
    m = Measurement.from_arrays(t, current_A=i, speed_rpm=w, speed_ref_rpm=ref_t)
    params = _params(p, 1000.0, 100.0)
    exp = m.experiment(params)
    assert exp.knots is not None and exp.t0 == pytest.approx(1.0, abs=1e-3)
    np.testing.assert_allclose([k[0] for k in exp.knots], [c[0] - 1.0 for c in ref[2:]], atol=1e-3)
    c = compare(m, params)
    assert c.fit["current_A"] > 99.9, c.fit
    assert c.fit["speed_rpm"] > 99.9, c.fit
    np.testing.assert_allclose(knots_values(t, exp.t0, *zip(*exp.knots)), ref_t, atol=0.05)
