"""The linear models of the design equal the exact Jacobian of the nonlinear plant.

Truth: the nonlinear plant's components (ramp held, PID, DC motor, rigid
reducer, kiln carrying the stuck burden as inertia) are eq. 21 with
J = J_m + (J_o + J_v)/n^2; CasADi's exact Jacobian of their right-hand side at
any point must equal ``closed_loop_ss(...).A`` (and the reference input
column ``B[:, e_v]``) of :mod:`kilnctl.linear`, an independent implementation
built with python-control's ``interconnect``.
"""

import casadi as ca
import numpy as np
import pytest

from kilnctl import Parameters
from kilnctl.design import PIDGains
from kilnctl.linear import closed_loop_ss
from kilnctl.model import get_plant
from kilnctl.model.base import NUMERIC_NAMES

LOOP = ("ramp", "pid", "dc_motor", "gearbox", "kiln")


@pytest.mark.parametrize("condition", ["stick", "slip"])
def test_jacobian_equals_linear_model(condition):
    gains = PIDGains(k_p=0.08, k_I=2.2, k_D=0.014)
    p = Parameters(gains="given", k_p=gains.k_p, k_I=gains.k_I, k_D=gains.k_D)
    # the kiln node carries the burden's inertia when it sticks, only the shell when it slips
    J_kiln = p.J_o + p.J_v if condition == "stick" else p.J_o
    q = p.replace(J_o=J_kiln)
    plant = get_plant(LOOP, q)
    e, xs, t, sp = plant.equations(("hold",))
    order = ("x_a", "omega_motor", "z")
    idx = [plant.state_names.index(s) for s in order]
    rates = ca.vertcat(*[e.rates[s] for s in order])
    scales = plant.scales[idx]
    jac = ca.Function("jac_f", [xs, t, sp.vector], [ca.jacobian(rates, xs)[:, idx]])
    dref = ca.Function("dref", [xs, t, sp.vector], [ca.jacobian(rates, sp.vector)[:, NUMERIC_NAMES.index("omega_ref")]])
    x0 = np.random.default_rng(1).normal(size=len(plant.state_names))  # linear: any point will do
    P = plant.param_vector(q)
    A_nl = np.asarray(jac(x0, 3.0, P)) / scales[None, :]
    B_nl = np.asarray(dref(x0, 3.0, P)).ravel()
    lin = closed_loop_ss(p, gains, condition)
    assert A_nl == pytest.approx(np.asarray(lin.A), rel=1e-10, abs=1e-9)
    assert B_nl == pytest.approx(np.asarray(lin.B)[:, 0], rel=1e-10, abs=1e-12)
