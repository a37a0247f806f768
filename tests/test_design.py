"""Tests of kilnctl.design: the root-locus PID design, its loci, figures and errors.

Independent truths used: closed-loop poles from ``control.feedback`` (python-control's
own loop closing, not kilnctl's interconnect), step responses simulated with
``scipy.signal`` from the characteristic polynomial written out by hand, and the
damping of roots of hand-written polynomials.
"""

import inspect
import json
import math
import re

import control as ct
import matplotlib
import numpy as np
import pytest
from scipy import signal

matplotlib.use("Agg")

from kilnctl import design as dz  # noqa: E402
from kilnctl import linear  # noqa: E402
from kilnctl.design import (PIDGains, Requirements, RequirementsNotMetError, design_pid, gains_for,  # noqa: E402
                            parameter_locus, place_poles, root_locus, torsional_mode_frequency)
from kilnctl.design.plots import click_text, save_figure  # noqa: E402
from kilnctl.errors import DesignError, KilnctlError, ModelError  # noqa: E402
from kilnctl.params import Parameters  # noqa: E402

P = Parameters()


@pytest.fixture(scope="module")
def result():
    return design_pid(P)


def _hand_den(condition, gains):
    """Fig. 3 characteristic polynomial written out by hand, J from eqs. 11 / 15."""
    J = P.J_m + ((P.J_o + P.J_v) if condition == "stick" else P.J_o) / P.n**2
    K, ki = P.K_fb, P.k_i
    return [P.L_a * J, P.L_a * P.B_m + P.R_a * J + K * ki * gains.k_D,
            P.R_a * P.B_m + P.k_i * P.k_b + K * ki * gains.k_p, K * ki * gains.k_I]


def _hand_step(condition, gains, t):
    """Speed step K*omega_m/e_v from the hand-written closed-loop transfer function (scipy)."""
    num = P.K_fb * P.k_i * np.array([gains.k_D, gains.k_p, gains.k_I])
    den = _hand_den(condition, gains)
    _, y = signal.step(signal.lti(num, den), T=t)
    return np.asarray(y), np.roots(den)


@pytest.mark.parametrize("condition", ["stick", "slip"])
def test_default_design_meets_its_requirements_by_independent_simulation(result, condition):
    req = result.requirements
    assert result.meets_requirements and result.unmet == ()
    t = np.linspace(0, 4, 20001)
    y, roots = _hand_step(condition, result.gains, t)
    final = y[-1]
    assert final == pytest.approx(1.0, abs=1e-6)  # integral action: no steady error
    overshoot = max(0.0, (y.max() - final) / final * 100)
    outside = np.nonzero(np.abs(y - final) > 0.02 * final)[0]
    settling = t[outside[-1] + 1]
    assert overshoot <= req.overshoot_max
    assert settling <= req.settling_time_max
    zetas = -roots.real / np.abs(roots)
    assert zetas.min() >= req.zeta_min - 1e-9
    slowest = roots[np.argmax(roots.real)]
    assert abs(slowest) <= req.wn_max * (1 + 1e-9)
    # the report agrees with the independent simulation
    rep = result.reports[condition]
    assert rep.settling_time == pytest.approx(settling, abs=5e-3)
    assert rep.overshoot == pytest.approx(overshoot, abs=1e-3)
    np.testing.assert_allclose(np.sort_complex(rep.poles), np.sort_complex(roots), rtol=1e-8)


def test_default_wn_max_is_half_the_torsional_mode(result):
    # NOTES.md: k_po with J_e gives a mode near 1.45 Hz; with J_e = J_o + J_v: sqrt(7.012e8/8.656e6) = 9.00 rad/s
    assert torsional_mode_frequency(P) == pytest.approx(math.sqrt(7.012e8 / (6.978e6 + 1.678e6)), rel=1e-12)
    assert result.requirements.wn_max == pytest.approx(0.5 * torsional_mode_frequency(P), rel=1e-12)


def test_place_poles_puts_the_closed_loop_poles_on_target():
    # independent: close the loop with control.feedback(C*G, K), not with kilnctl's interconnect
    sigma, zeta = 3.0, 0.8
    g = place_poles(P, sigma, zeta, "stick")
    w0 = linear.electromechanical_frequency(P, "stick")
    cl = ct.feedback(linear.pid_tf(g) * linear.motor_tf(P, "stick"), P.K_fb)
    want = np.roots(np.polymul([1, sigma], [1, 2 * zeta * w0, w0**2]))
    np.testing.assert_allclose(np.sort_complex(cl.poles()), np.sort_complex(want), rtol=1e-8)


def test_design_reads_the_gain_off_the_locus(result):
    # the target dominant pole lies on the locus of L at kappa = 1: -1/L(s0) = 1 (TOOLING.md: exact to 1e-16)
    L = linear.loop_tf(P, result.gains, "stick")
    s0 = -result.target["sigma"]
    assert complex(-1 / L(s0)) == pytest.approx(1.0, abs=1e-9)


def test_pi_alone_leaves_the_electromechanical_pair_poorly_damped(result):
    # paper: "P, PI, and PD equivalent controllers ... not satisfactory". With k_D = 0 the pair keeps
    # about the motor's own damping (hand: roots of the Fig. 3 polynomial with k_D = 0)
    g = PIDGains(result.gains.k_p, result.gains.k_I, 0.0)
    rep = dz.analyse(P, g, "stick")
    roots = np.roots(_hand_den("stick", g))
    assert rep.zeta_min_all == pytest.approx((-roots.real / np.abs(roots)).min(), rel=1e-9)
    assert rep.zeta_min_all < 0.3 < result.requirements.zeta_min


@pytest.mark.parametrize("condition", ["stick", "slip"])
def test_root_locus_points_are_closed_loop_poles(result, condition):
    data = root_locus(P, result.gains, conditions=[condition], kappas=[0.0, 0.05, 0.5, 1.0, 1.7, 20.0])
    br = data.branches[condition]
    L = linear.loop_tf(P, result.gains, condition)
    for k, row in zip(br.kappas, br.loci):
        # independent truth: python-control closing k*L with unity feedback
        want = np.sort_complex(ct.feedback(k * L, 1).poles()) if k > 0 else np.sort_complex(L.poles())
        np.testing.assert_allclose(np.sort_complex(row), want, rtol=1e-7, atol=1e-9)
        if k > 0:
            for p in row:
                assert data.gain_at(p, condition) == pytest.approx(k, rel=1e-6)
    np.testing.assert_allclose(np.sort_complex(br.chosen), np.sort_complex(result.reports[condition].poles),
                               rtol=1e-8)


def test_default_locus_is_continuous_and_passes_kappa_one(result):
    data = result.locus()
    for br in data.branches.values():
        assert 1.0 in br.kappas and br.kappas[0] == 0.0
        np.testing.assert_allclose(np.sort_complex(br.loci[0]), np.sort_complex(br.open_loop_poles), atol=1e-9)
        # within the plotted region (|s| < 3 * 36 rad/s) no branch jumps by more than 1 % of the scale
        near = np.abs(br.loci[:-1]) < 100
        assert np.max(np.abs(np.diff(br.loci, axis=0))[near]) < 0.6


def test_gain_at_off_the_locus_and_click_text(result):
    data = root_locus(P, result.gains, conditions=["stick"], kappas=np.linspace(0, 3, 301))
    with pytest.raises(DesignError, match="not on the stick root locus"):
        data.gain_at(complex(-10, 30), "stick")
    # a click next to the dominant pole reports kappa about 1 and the designed k_D
    text = click_text(data, complex(-4.55, 0.05))
    kappa = float(re.search(r"kappa = ([0-9.]+)", text).group(1))
    assert kappa == pytest.approx(1.0, abs=0.02)
    assert f"k_D = {kappa * result.gains.k_D:.4g}" in text


def test_impossible_settling_time_is_a_clear_error_with_the_best_design():
    req = Requirements(settling_time_max=0.3)
    with pytest.raises(RequirementsNotMetError) as info:
        design_pid(P, req)
    msg = str(info.value)
    assert re.search(r"settling_time_max = 0.3 s: best achieved 0\.\d+ s", msg)
    assert "raise settling_time_max to at least" in msg and "or raise wn_max" in msg
    assert isinstance(info.value, DesignError) and isinstance(info.value, ValueError)
    best = info.value.best
    assert not best.meets_requirements
    assert best.reports["stick"].settling_time > 0.3
    # strict=False returns the same best design instead of raising
    loose = design_pid(P, req, strict=False)
    assert loose.gains == best.gains and loose.unmet == best.unmet


def test_lower_wn_max_gives_a_slower_design(result):
    r = design_pid(P, Requirements(wn_max=2.5, settling_time_max=3.0))
    assert r.meets_requirements
    assert max(rep.dominant_wn for rep in r.reports.values()) <= 2.5 * (1 + 1e-6)
    assert r.gains.k_I < result.gains.k_I


@pytest.mark.parametrize("kwargs, match", [
    ({"zeta_min": -0.1}, "zeta_min = -0.1 is negative"),
    ({"zeta_min": 1.2}, "zeta_min = 1.2 exceeds 1"),
    ({"zeta_min": "high"}, "zeta_min = 'high' must be a number"),
    ({"settling_time_max": 0.0}, "settling_time_max = 0.0 s must be > 0"),
    ({"settling_time_max": -2}, "settling_time_max = -2.0 s must be > 0"),
    ({"settling_time_max": math.inf}, "settling_time_max = inf must be a finite"),
    ({"overshoot_max": -1}, "overshoot_max = -1.0 % must be >= 0"),
    ({"wn_max": 0}, "wn_max = 0.0 rad/s must be > 0"),
])
def test_bad_requirements_are_clear_errors(kwargs, match):
    with pytest.raises(DesignError, match=re.escape(match)):
        Requirements(**kwargs)


@pytest.mark.parametrize("gains, match", [
    ((-1.0, 1.0, 0.01), "gain k_p = -1.0 must be a finite number >= 0"),
    ((1.0, math.nan, 0.01), "gain k_I = nan"),
    ((1.0, 1.0, "0.01"), "gain k_D = '0.01' must be a number"),
])
def test_bad_gains_are_clear_errors(gains, match):
    with pytest.raises(DesignError, match=re.escape(match)):
        PIDGains(*gains)


def test_unknown_condition_is_a_clear_error(result):
    with pytest.raises(DesignError, match="unknown design_condition 'stuck'"):
        design_pid(P, design_condition="stuck")
    with pytest.raises(ModelError, match="unknown load condition 'stuck'"):
        root_locus(P, result.gains, conditions=["stuck"])
    with pytest.raises(ModelError, match="unknown load condition"):
        dz.analyse(P, result.gains, "sliding")
    with pytest.raises(DesignError, match="must be a kilnctl.design.Requirements"):
        design_pid(P, {"zeta_min": 0.7})


def test_gains_for_given_and_designed_with_cache(result):
    given = P.replace(gains="given", k_p=0.5, k_I=2.0, k_D=0.02)
    assert gains_for(given) == PIDGains(0.5, 2.0, 0.02)
    assert gains_for(P) == result.gains
    before = dz.pid._default_design.cache_info().hits
    # friction does not enter the linear design: same cache entry
    assert gains_for(P.replace(mu_c=0.3, mu_s=0.35)) == result.gains
    assert dz.pid._default_design.cache_info().hits == before + 1
    # the motor does: a different design
    assert gains_for(P.replace(L_a=1.0e-3)) != result.gains


def test_json_has_the_documented_keys_and_no_nan(result):
    d = result.to_dict()
    text = json.dumps(d, allow_nan=False)  # raises on NaN/inf
    keys = {"kp", "ki", "kd", "closed_loop_poles", "dominant_zeta", "dominant_wn", "settling_time_s",
            "overshoot_pct", "gain_margin_db", "phase_margin_deg"}
    assert keys <= set(d)
    for cond in ("stick", "slip"):
        assert keys - {"kp", "ki", "kd"} <= set(d["conditions"][cond])
        poles = np.array([complex(*p) for p in d["conditions"][cond]["closed_loop_poles"]])
        np.testing.assert_allclose(np.sort_complex(poles), np.sort_complex(result.reports[cond].poles))
    assert (d["kp"], d["ki"], d["kd"]) == (result.gains.k_p, result.gains.k_I, result.gains.k_D)
    # the gain margin is infinite here (phase of L never reaches -180 deg): null with the reason
    assert d["gain_margin_db"] is None and "never crosses -180" in d["notes"]["gain_margin_db"]
    assert "NaN" not in text and "Infinity" not in text


def test_parameter_locus_over_burden_mass():
    g = PIDGains(0.1, 2.0, 0.015)
    data = parameter_locus(P, g, values=[240e3, 580e3, 974e3])
    ratio = P.J_v / P.m_v
    for v, row_stick, row_slip in zip(data.values, data.poles["stick"], data.poles["slip"]):
        # hand: J_v = m_v * (J_v/m_v)_Table1, then the Fig. 3 polynomial's roots
        J = P.J_m + (P.J_o + v * ratio) / P.n**2
        K, ki = P.K_fb, P.k_i
        den = [P.L_a * J, P.L_a * P.B_m + P.R_a * J + K * ki * g.k_D, P.R_a * P.B_m + ki * P.k_b + K * ki * g.k_p,
               K * ki * g.k_I]
        np.testing.assert_allclose(np.sort_complex(row_stick), np.sort_complex(np.roots(den)), rtol=1e-8)
        # slip: the burden's inertia drops out (eq. 15), so the poles do not move
        np.testing.assert_allclose(row_slip, data.poles["slip"][0], rtol=1e-12)
    assert data.inertias["stick"][-1] == pytest.approx(P.J_m + (P.J_o + 974e3 * ratio) / P.n**2, rel=1e-12)
    with pytest.raises(DesignError, match="give the values of 'R_a'"):
        parameter_locus(P, g, parameter="R_a")
    with pytest.raises(KilnctlError, match="unknown parameter 'm_w'"):
        parameter_locus(P, g, values=[1, 2], parameter="m_w")


def test_plots_draw_the_computed_data(result, tmp_path):
    fig = result.locus().plot()
    ax_full = fig.axes[0]
    # the chosen closed-loop poles are drawn where the analysis put them
    drawn = [complex(x, y) for line in ax_full.lines if line.get_marker() == "s"
             for x, y in zip(line.get_xdata(), line.get_ydata())]
    for cond in ("stick", "slip"):
        for p in result.reports[cond].poles:
            assert min(abs(np.array(drawn) - p)) < 1e-9
    # a click on the zoom panel next to the dominant pole marks it and shows kappa = 1 (no GUI needed)
    from types import SimpleNamespace
    ax_zoom = fig.axes[1]
    fig._kilnctl_click(SimpleNamespace(inaxes=ax_zoom, xdata=-4.5, ydata=0.02))
    shown = [t.get_text() for t in ax_zoom.texts if t.get_text().startswith("stick:") or
             t.get_text().startswith("slip:")]
    assert len(shown) == 1 and re.search(r"kappa = 1(\.0+)?:", shown[0])
    out = tmp_path / "rl.png"
    out.write_bytes(b"old")
    save_figure(fig, out, dpi=30)
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"  # replaced whole
    assert [p.name for p in tmp_path.iterdir()] == ["rl.png"]  # no temporary left
    with pytest.raises(KilnctlError, match="unknown figure format 'xyz'"):
        save_figure(fig, tmp_path / "rl.xyz")
    import matplotlib.pyplot as plt
    plt.close("all")


def _public_callables():
    mods = [linear, dz.pid, dz.locus, dz.analysis, dz.requirements, dz.gains, dz.plots]
    for mod in mods:
        for name in getattr(mod, "__all__", []):
            obj = getattr(mod, name)
            if inspect.isfunction(obj):
                yield f"{mod.__name__}.{name}", obj
            elif inspect.isclass(obj):
                for mname, meth in vars(obj).items():
                    if inspect.isfunction(meth) and not mname.startswith("_"):
                        yield f"{mod.__name__}.{name}.{mname}", meth


def test_every_public_function_documents_every_parameter():
    missing = []
    for qual, fn in _public_callables():
        doc = inspect.getdoc(fn) or ""
        if not doc:
            missing.append(f"{qual}: no docstring")
            continue
        for pname, par in inspect.signature(fn).parameters.items():
            if pname in ("self", "cls") or par.kind is par.VAR_KEYWORD and f"**{pname}" in doc:
                continue
            if not re.search(rf"^\s*\**{pname}\b.*:", doc, re.M):
                missing.append(f"{qual}: parameter {pname}")
    assert not missing, missing


def test_fast_step_and_bandwidth_match_python_control(result):
    # truth: control.step_response and control.bandwidth on the same closed loop
    from kilnctl.design.analysis import closed_loop_bandwidth, step_samples
    sys = linear.closed_loop_ss(P, result.gains, "slip")[0, 0] * P.K_fb
    t = np.linspace(0, 2, 801)
    np.testing.assert_allclose(step_samples(sys, t), ct.step_response(sys, timepts=t).outputs, atol=1e-10)
    assert closed_loop_bandwidth(sys) == pytest.approx(ct.bandwidth(sys), rel=1e-6)
    assert result.reports["slip"].bandwidth == pytest.approx(ct.bandwidth(sys), rel=1e-6)


def test_design_pid_given_a_dict_names_params():
    # truth: a dict of values built by hand where the Parameters belong (was "'dict' object has no attribute 'k_po'")
    with pytest.raises(DesignError, match=r"params must be a kilnctl.Parameters.*not dict"):
        design_pid({"m_v": 5e5})
