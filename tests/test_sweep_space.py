"""Parameter spaces of the sweep engine, against independent truths (no simulation here).

Truths used: the definition of a Latin hypercube (one point per stratum of each
variable), the normal table (Phi^-1(0.975) = 1.959964), the moments of the
uniform and triangular distributions, and itertools.product order.
"""

import itertools
import math

import numpy as np
import pytest

from kilnctl import Parameters
from kilnctl.errors import ParameterError
from kilnctl.sweep import (Grid, LatinHypercube, LogUniform, MonteCarlo, Normal, Study, Triangular, TruncNormal,
                           Uniform)


def test_grid_is_the_full_product_first_variable_slowest():
    g = Grid({"m_v": [1e5, 2e5, 3e5], "delta_x": [0.0, 0.01], "friction_law": ["paper", "torque"]})
    s = g.samples()
    assert len(g) == 12
    rows = list(zip(s["m_v"], s["delta_x"], s["friction_law"]))
    assert rows == list(itertools.product([1e5, 2e5, 3e5], [0.0, 0.01], ["paper", "torque"]))


def test_grid_linspace_and_log_scale():
    assert Grid.linspace(240e3, 974e3, 3) == (240e3, 607e3, 974e3)
    vals = Grid.linspace(7.4, 740.0, 3, scale="log")
    assert vals[1] == pytest.approx(74.0)  # geometric mean of 7.4 and 740
    assert Grid.linspace(5.0, 5.0, 1) == (5.0,)


@pytest.mark.parametrize("bounds", [{"m_v": Uniform(240e3, 974e3), "delta_x": Uniform(0.0, 0.016),
                                     "ramp_rate": Uniform(37.0, 740.0)}])
def test_latin_hypercube_is_inside_the_bounds_and_stratified(bounds):
    n = 50
    s = LatinHypercube(bounds, n=n, seed=3).samples()
    for name, d in bounds.items():
        x = s[name]
        assert np.all((x >= d.low) & (x <= d.high))
        strata = np.floor((x - d.low) / (d.high - d.low) * n).astype(int)
        # truth: definition of a Latin hypercube: each of the n equal strata holds exactly one point
        assert sorted(strata) == list(range(n))


def test_latin_hypercube_log_uniform_is_stratified_in_the_logarithm():
    n = 20
    x = LatinHypercube({"ramp_rate": LogUniform(7.4, 740.0)}, n=n, seed=0).samples()["ramp_rate"]
    strata = np.floor(np.log(x / 7.4) / np.log(100.0) * n).astype(int)
    assert sorted(strata) == list(range(n))


def test_sampling_is_reproducible_by_seed():
    d = {"mu_c": Uniform(0.3, 0.5)}
    for cls in (LatinHypercube, MonteCarlo):
        a = cls(d, n=10, seed=7).samples()["mu_c"]
        assert np.array_equal(a, cls(d, n=10, seed=7).samples()["mu_c"])
        assert not np.array_equal(a, cls(d, n=10, seed=8).samples()["mu_c"])


def test_monte_carlo_moments_match_the_distributions():
    n = 20000
    s = MonteCarlo({"a": Uniform(2.0, 4.0), "b": Normal(10.0, 0.5), "c": Triangular(0.0, 1.0, 4.0)},
                   n=n, seed=1).samples()
    # truths: uniform mean (a+b)/2, var (b-a)^2/12; triangular mean (a+c+b)/3
    assert s["a"].mean() == pytest.approx(3.0, abs=4 * math.sqrt(1 / 3 / n))
    assert s["a"].var() == pytest.approx(1 / 3, rel=0.05)
    assert s["b"].mean() == pytest.approx(10.0, abs=4 * 0.5 / math.sqrt(n))
    assert s["b"].std() == pytest.approx(0.5, rel=0.05)
    assert s["c"].mean() == pytest.approx(5 / 3, abs=0.03)
    # independence: sample correlation near zero
    assert abs(np.corrcoef(s["a"], s["b"])[0, 1]) < 0.05


def test_quantile_functions_against_tables():
    assert Normal(1.0, 2.0).ppf(0.975) == pytest.approx(1.0 + 2.0 * 1.959964, rel=1e-6)  # normal table
    t = TruncNormal(0.4, 0.1, 0.3, 0.5)
    x = t.ppf(np.linspace(0.0, 1.0, 11))
    assert x[0] == pytest.approx(0.3) and x[-1] == pytest.approx(0.5) and x[5] == pytest.approx(0.4)
    assert LogUniform(1.0, 100.0).ppf(0.5) == pytest.approx(10.0)
    assert Triangular(0.0, 0.0, 1.0).ppf(0.25) == pytest.approx(1 - math.sqrt(0.75))


@pytest.mark.parametrize("make, match", [
    (lambda: Grid({"m_v": []}), "no values"),
    (lambda: Grid({"m_v": [1.0, 1.0]}), "repeats"),
    (lambda: Grid({}), "at least one variable"),
    (lambda: Uniform(0.5, 0.3), "empty range"),
    (lambda: Uniform(0.3, 0.3), "empty range"),
    (lambda: LogUniform(0.0, 1.0), "> 0"),
    (lambda: Normal(0.4, 0.0), "std"),
    (lambda: Triangular(0.0, 2.0, 1.0), "mode"),
    (lambda: LatinHypercube({"mu_c": Uniform(0.3, 0.5)}, n=0), "n = 0"),
    (lambda: MonteCarlo({"mu_c": (0.3, 0.5)}, n=5), "not a distribution"),
    (lambda: Grid.linspace(1.0, 2.0, 0), "num"),
])
def test_bad_spaces_are_errors(make, match):
    with pytest.raises(ParameterError, match=match):
        make()


def test_study_refuses_unknown_names_with_close_matches():
    with pytest.raises(ParameterError, match="did you mean 'delta_x'"):
        Study(Grid({"delta_xx": [0.0]}))
    with pytest.raises(ParameterError, match="did you mean 'peak_stress_Pa'"):
        Study(Grid({"m_v": [1e5]}), outputs=["peak_stres_Pa"])
    with pytest.raises(ParameterError, match="did you mean 'rtol'"):
        Study(Grid({"m_v": [1e5]}), options={"rtoll": 1e-6})


def test_simulation_options_are_keywords_of_simulate():
    import inspect

    from kilnctl.simulate import simulate
    from kilnctl.sweep import SIM_OPTIONS

    assert set(SIM_OPTIONS) <= set(inspect.signature(simulate).parameters)


def test_factor_multiplies_every_named_parameter():
    st = Study(Grid({"friction": [0.8, 1.2]}), factors={"friction": ("mu_c", "mu_s")})
    lo, hi = st.parameter_sets()
    assert (lo.mu_c, lo.mu_s) == pytest.approx((0.32, 0.408))  # 0.8 x Table/Fig. 4 values 0.4, 0.51
    assert (hi.mu_c, hi.mu_s) == pytest.approx((0.48, 0.612))


def test_impossible_points_are_reported_before_any_run():
    # mu_c and mu_s drawn independently: some points have mu_c > mu_s
    st = Study(MonteCarlo({"mu_c": Uniform(0.3, 0.5), "mu_s": Uniform(0.35, 0.55)}, n=200, seed=0))
    with pytest.raises(ParameterError, match=r"of 200 points .* impossible.*mu_c.*factor"):
        st.parameter_sets()


def test_gains_are_designed_once_for_the_base_unless_redesign():
    from kilnctl.simulate import resolve_gains

    space = Grid({"burden": [0.5, 1.5]})
    once = Study(space, factors={"burden": ("m_v", "J_v")}).parameter_sets()
    nominal = resolve_gains(Parameters())
    assert all(p.gains == "given" and (p.k_p, p.k_I, p.k_D) == (nominal.k_p, nominal.k_I, nominal.k_D)
               for p in once)
    each = Study(space, factors={"burden": ("m_v", "J_v")}, redesign=True).parameter_sets()
    assert all(p.gains == "design" for p in each)  # the simulation designs them for each J_v
    with pytest.raises(ParameterError, match="redesign"):
        Study(Grid({"k_p": [0.5, 1.0]}), redesign=True)
