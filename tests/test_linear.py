"""Tests of kilnctl.linear against hand derivations from eq. 21 and Fig. 3.

The independent truths here are the transfer functions derived by hand from the
motor equations (written out below as polynomials in R_a, L_a, J, B_m, k_i, k_b),
the state matrices of eq. 21 written by hand, and the characteristic polynomial
read off the signal-flow graph of Fig. 3 with Mason's gain formula.
"""

import control as ct
import numpy as np
import pytest

from kilnctl.design import PIDGains
from kilnctl.errors import KilnctlError, ModelError
from kilnctl.linear import (CONDITIONS, characteristic_polynomial, closed_loop_ss, electromechanical_frequency,
                            inertia, loop_tf, motor_plant, motor_tf, pid_tf)
from kilnctl.params import Parameters

P = Parameters()
# odd gains so that no term can hide behind another
G = PIDGains(k_p=0.3, k_I=1.7, k_D=0.021)


def _tf_coeffs(sys, out=0, inp=0):
    """Numerator and denominator of one channel, normalised to a monic denominator."""
    tf = ct.ss2tf(sys[out, inp]) if isinstance(sys, ct.StateSpace) else sys
    num = np.atleast_1d(np.squeeze(tf.num[0][0]))
    den = np.atleast_1d(np.squeeze(tf.den[0][0]))
    return num / den[0], den / den[0]


def _same_poly(a, b, rtol=1e-9):
    a = np.trim_zeros(np.asarray(a, float), "f")
    b = np.trim_zeros(np.asarray(b, float), "f")
    # ss2tf may leave tiny leading coefficients where the hand form has none
    n = max(len(a), len(b))
    a = np.concatenate([np.zeros(n - len(a)), a])
    b = np.concatenate([np.zeros(n - len(b)), b])
    np.testing.assert_allclose(a, b, rtol=rtol, atol=rtol * np.max(np.abs(b)))


def hand(condition):
    """Symbols of eq. 21 for a condition, J from eqs. 11 / 15 by hand."""
    J = P.J_m + ((P.J_o + P.J_v) if condition == "stick" else P.J_o) / P.n**2
    return P.R_a, P.L_a, J, P.B_m, P.k_i, P.k_b, P.K_fb


@pytest.mark.parametrize("condition", CONDITIONS)
def test_inertia_matches_eqs_11_and_15(condition):
    Ra, La, J, Bm, ki, kb, K = hand(condition)
    assert inertia(P, condition) == pytest.approx(J, rel=1e-14)


@pytest.mark.parametrize("condition", CONDITIONS)
def test_motor_transfer_functions_vs_hand_derivation(condition):
    # hand: (L_a s + R_a) i = e_a - k_b w ;  (J s + B_m) w = k_i i - T_l
    # => den = L_a J s^2 + (L_a B_m + R_a J) s + (R_a B_m + k_i k_b)
    Ra, La, J, Bm, ki, kb, K = hand(condition)
    den = np.array([La * J, La * Bm + Ra * J, Ra * Bm + ki * kb])
    plant = motor_plant(P, condition)
    assert plant.input_labels == ["e_a", "T_l"] and plant.output_labels == ["omega_m", "i_a"]
    cases = {
        (0, 0): [ki],              # omega_m / e_a
        (1, 0): [J, Bm],           # i_a / e_a
        (0, 1): [-La, -Ra],        # omega_m / T_l
        (1, 1): [kb],              # i_a / T_l
    }
    for (out, inp), num in cases.items():
        n, d = _tf_coeffs(plant, out, inp)
        _same_poly(d, den / den[0])
        _same_poly(n, np.asarray(num, float) / den[0])
    n, d = _tf_coeffs(motor_tf(P, condition))
    _same_poly(n, [ki / den[0]])
    _same_poly(d, den / den[0])


def test_open_loop_electromechanical_pair():
    # hand: w0^2 = (R_a B_m + k_i k_b)/(L_a J); with Table 1: about 35.8 rad/s, zeta about 0.235
    Ra, La, J, Bm, ki, kb, K = hand("stick")
    w0 = np.sqrt((Ra * Bm + ki * kb) / (La * J))
    assert electromechanical_frequency(P, "stick") == pytest.approx(w0, rel=1e-14)
    poles = motor_plant(P, "stick").poles()
    assert np.abs(poles) == pytest.approx([w0, w0], rel=1e-9)
    zeta = -poles[0].real / abs(poles[0])
    assert zeta == pytest.approx((La * Bm + Ra * J) / (2 * La * J * w0), rel=1e-9)
    assert 0.2 < zeta < 0.25


@pytest.mark.parametrize("condition", CONDITIONS)
def test_characteristic_polynomial_vs_mason_and_poles(condition):
    # Fig. 3 by Mason's gain formula (docs/linear_model.md), written out by hand:
    Ra, La, J, Bm, ki, kb, K = hand(condition)
    mason = [La * J, La * Bm + Ra * J + K * ki * G.k_D, Ra * Bm + ki * kb + K * ki * G.k_p, K * ki * G.k_I]
    coeffs = characteristic_polynomial(P, G, condition)
    np.testing.assert_allclose(coeffs, mason, rtol=1e-14)
    # independent of the formula: eigenvalues of the interconnected state-space system
    poles = np.sort_complex(closed_loop_ss(P, G, condition).poles())
    np.testing.assert_allclose(poles, np.sort_complex(np.roots(mason)), rtol=1e-9)


@pytest.mark.parametrize("condition", CONDITIONS)
def test_closed_loop_transfer_functions_vs_hand_derivation(condition):
    # hand (docs/linear_model.md), char = s (L_a s + R_a)(J s + B_m) + s k_i k_b + K k_i (k_D s^2 + k_p s + k_I):
    #   omega_m/e_v = k_i (k_D s^2 + k_p s + k_I) / char
    #   omega_m/T_l = -s (L_a s + R_a) / char
    #   i_a/e_v     = (k_D s^2 + k_p s + k_I)(J s + B_m) / char     (feedthrough k_D/L_a)
    Ra, La, J, Bm, ki, kb, K = hand(condition)
    pid = np.array([G.k_D, G.k_p, G.k_I])
    char = np.polyadd(np.polymul([1, 0], np.polymul([La, Ra], [J, Bm])), [ki * kb, 0])
    char = np.polyadd(char, K * ki * pid)
    sys = closed_loop_ss(P, G, condition)
    for (out, inp), num in {(0, 0): ki * pid, (0, 1): -np.polymul([1, 0], [La, Ra]),
                            (1, 0): np.polymul(pid, [J, Bm])}.items():
        n, d = _tf_coeffs(sys, out, inp)
        _same_poly(d, char / char[0], rtol=1e-8)
        _same_poly(n, np.asarray(num) / char[0], rtol=1e-8)
    # the direct term of i_a is the derivative through the inductance, eq. 21 line 2
    assert sys.D[1, 0] == pytest.approx(G.k_D / La, rel=1e-14)
    assert sys.D[0, 0] == 0 and sys.D[0, 1] == 0 and sys.D[1, 1] == 0


def test_closed_loop_state_order_and_matrices_by_hand():
    # states (x_a, omega_m, z), x_a = i_a - (k_D/L_a) e_f; matrices written out from eq. 21 by hand
    Ra, La, J, Bm, ki, kb, K = hand("stick")
    kp, kI, kD = G.k_p, G.k_I, G.k_D
    A = [[-Ra / La, (-kp * K + Ra * kD * K / La - kb) / La, kI / La],
         [ki / J, (-ki * kD * K / La - Bm) / J, 0.0],
         [0.0, -K, 0.0]]
    B = [[(kp - Ra * kD / La) / La, 0.0], [ki * kD / (La * J), -1.0 / J], [1.0, 0.0]]
    C = [[0.0, 1.0, 0.0], [1.0, -kD * K / La, 0.0]]
    D = [[0.0, 0.0], [kD / La, 0.0]]
    sys = closed_loop_ss(P, G, "stick")
    assert sys.state_labels == ["x_a", "omega_m", "z"]
    assert sys.input_labels == ["e_v", "T_l"]
    assert sys.output_labels == ["omega_m", "i_a"]
    for got, want in ((sys.A, A), (sys.B, B), (sys.C, C), (sys.D, D)):
        np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-12)


def test_loop_tf_is_K_C_G_and_closes_to_the_same_poles():
    # L = K C G; feedback(C G, K) is built by python-control, independently of closed_loop_ss
    L = loop_tf(P, G, "slip")
    n, d = _tf_coeffs(L)
    Ra, La, J, Bm, ki, kb, K = hand("slip")
    den = np.polymul([1, 0], [La * J, La * Bm + Ra * J, Ra * Bm + ki * kb])
    _same_poly(d, den / den[0])
    _same_poly(n, K * ki * np.array([G.k_D, G.k_p, G.k_I]) / den[0])
    cl = ct.feedback(pid_tf(G) * motor_tf(P, "slip"), K)
    np.testing.assert_allclose(np.sort_complex(cl.poles()),
                               np.sort_complex(closed_loop_ss(P, G, "slip").poles()), rtol=1e-8)


def test_steady_state_speed_tracks_reference():
    # integral action: K*omega_m = e_v at DC, with no load; the DC gain from e_v is 1/K rad/s per rpm
    sys = closed_loop_ss(P, G, "stick")
    assert ct.dcgain(sys)[0, 0] == pytest.approx(1 / P.K_fb, rel=1e-9)
    assert ct.dcgain(sys)[0, 1] == pytest.approx(0.0, abs=1e-12)


def test_unknown_condition_is_a_clear_error():
    with pytest.raises(ModelError, match="unknown load condition 'stuck'.*'stick'.*'slip'"):
        closed_loop_ss(P, G, "stuck")
    with pytest.raises(ValueError):  # ModelError is also a ValueError
        inertia(P, "Stick")


def test_gains_without_attributes_are_a_clear_error():
    with pytest.raises(KilnctlError, match="k_p .*PIDGains"):
        closed_loop_ss(P, (1.0, 2.0, 3.0))
