"""The C boundary of the compiled stepper (issue 11 item 6): what happens when the library or the call is wrong.

A library that cannot be loaded (stale, foreign, truncated) and a mode beyond the stepper's fixed sizes
fall back to CVODES with a warning; arrays of the wrong length are refused before any C runs (C trusts
the lengths it is given).
"""

import casadi as ca
import numpy as np
import pytest

import kilnctl.model.stepper as stepper_mod
from kilnctl import Parameters
from kilnctl.errors import SimulationError
from kilnctl.model import get_plant


def _toy(n=2, ng=1):
    xs, t, P = ca.SX.sym("x", n), ca.SX.sym("t"), ca.SX.sym("P", 1)
    f = -P[0] * xs
    g = ca.vertcat(*[xs[0] + 1.0 for _ in range(ng)])
    return f, xs, t, P, g, xs, ca.SX.ones(ng), ca.SX.zeros(ng), xs


def test_a_library_that_does_not_load_falls_back_with_a_warning(tmp_path, monkeypatch):
    bad = tmp_path / "mode_bad.so"
    bad.write_bytes(b"not a shared library")
    monkeypatch.setattr(stepper_mod, "compile_sources", lambda stem, sources: bad)
    with pytest.warns(RuntimeWarning, match="does not load"):
        assert stepper_mod.build_stepper(*_toy()) is None


def test_a_mode_beyond_the_stepper_limits_falls_back_with_a_warning():
    with pytest.warns(RuntimeWarning, match="beyond the compiled stepper's limit"):
        assert stepper_mod.build_stepper(*_toy(n=stepper_mod.NMAX + 1)) is None


def test_wrong_lengths_are_refused_before_any_c_runs():
    plant = get_plant(("ramp", "pid", "voltage_limit", "dc_motor", "current_limit", "gearbox", "kiln",
                       "bearing_friction", "burden", "bending_stress"), Parameters())
    xs0, mode0 = plant.initial(Parameters())
    st = plant.functions(mode0).stepper
    if st is None:
        pytest.skip("no C compiler: the compiled stepper is not used")
    P = plant.param_vector(Parameters())
    with pytest.raises(SimulationError, match="x0 has 3 entries"):
        st.run(P, 0.0, 1.0, np.zeros(3), 1e-3, 1e-7, 1e-8, 0.1, 0.0, 1e-9)
    with pytest.raises(SimulationError, match="P has"):
        st.run(P[:-1], 0.0, 1.0, xs0, 1e-3, 1e-7, 1e-8, 0.1, 0.0, 1e-9)
    with pytest.raises(SimulationError, match="x has"):
        st.guard(P, xs0[:-1], 0.0)


def test_the_first_step_comes_from_python():
    # rosenbrock.c keeps no first step of its own (it was a hidden 1e-4 there): a step <= 0 is refused as a
    # bad argument (status -7), and the one definition, stepper.FIRST_STEP, integrates. Truth for the result:
    # the exact decay x(t) = x0 exp(-t) of the toy plant dx/dt = -x (P = 1), its guard x + 1 never crossing
    st = stepper_mod.build_stepper(*_toy())
    if st is None:
        pytest.skip("no C compiler: the compiled stepper is not used")
    P, x0 = np.array([1.0]), np.array([1.0, 2.0])
    r = st.run(P, 0.0, 1.0, x0, 1e-2, 1e-9, 1e-10, 0.1, 0.0, 1e-9)
    assert stepper_mod.STATUS[r["status"]] == "bad arguments to the compiled stepper"
    r = st.run(P, 0.0, 1.0, x0, 1e-2, 1e-9, 1e-10, 0.1, stepper_mod.FIRST_STEP, 1e-9)
    assert r["status"] == 0
    np.testing.assert_allclose(r["x_ev"], x0 * np.exp(-1.0), rtol=1e-6)  # ROS3P global error at rtol 1e-9: 2e-7
