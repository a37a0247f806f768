r"""Linear models of the kiln speed loop (eq. 21 and Fig. 3 of the paper).

The DC motor of eq. 21 drives the kiln through the total reduction ``n``; the
kiln load is reflected to the motor shaft, so the mechanics see one inertia
``J`` that depends on the load condition (eqs. 11 and 15):

``"stick"``
    burden sticks to the wall: ``J = J_m + (J_o + J_v)/n**2`` (``params.J_stick``);
``"slip"``
    burden slides, its inertia drops out: ``J = J_m + J_o/n**2`` (``params.J_slip``).

Signals and units (the speed loop works in r.p.m., the motor in SI):

============  =========  ================================================
name          unit       meaning
============  =========  ================================================
``e_v``       rpm        speed reference
``e_f``       rpm        speed error ``e_v - K*omega_m``
``e_a``       V          armature voltage of the PI part
``i_a``       A          armature current
``omega_m``   rad/s      motor speed
``T_l``       N*m        load torque at the motor shaft (eq. 4)
``z``         rpm*s      integral of the speed error
``x_a``       A          ``i_a - (k_D/L_a)*e_f``, the integrated part of i_a
============  =========  ================================================

The PID acts on ``e_f`` as ``C(s) = k_p + k_I/s + k_D*s`` with ``k_p`` [V/rpm],
``k_I`` [V/(rpm*s)], ``k_D`` [V*s/rpm].  Eq. 21 realises the derivative through
the armature inductance: the voltage ``k_D*de_f/dt``, integrated by ``L_a``,
becomes the direct current term ``(k_D/L_a)*e_f`` (eq. 21, line 2).  The
closed-loop characteristic polynomial, from Fig. 3 and Mason's gain formula
(derivation in ``docs/linear_model.md``), is

.. math::

    L_a J s^3 + (L_a B_m + R_a J + K k_i k_D) s^2
    + (R_a B_m + k_i k_b + K k_i k_p) s + K k_i k_I .

Gains are any object with attributes ``k_p``, ``k_I``, ``k_D`` (normally a
:class:`kilnctl.design.PIDGains`).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import control as ct
import numpy as np

from .errors import ModelError
from .params import Parameters

if TYPE_CHECKING:  # pragma: no cover
    from .gains import PIDGains

__all__ = [
    "CONDITIONS",
    "CHARACTERISTIC_POLYNOMIAL",
    "inertia",
    "motor_plant",
    "motor_tf",
    "pid_tf",
    "loop_tf",
    "eq21_blocks",
    "closed_loop_ss",
    "characteristic_polynomial",
    "electromechanical_frequency",
]

#: load conditions of the paper: burden sticking (eq. 11) or slipping (eq. 15)
CONDITIONS = ("stick", "slip")

#: the closed-loop characteristic polynomial as the paper's Fig. 3 gives it
CHARACTERISTIC_POLYNOMIAL = (
    "L_a*J*s^3 + (L_a*B_m + R_a*J + K*k_i*k_D)*s^2 + (R_a*B_m + k_i*k_b + K*k_i*k_p)*s + K*k_i*k_I")


def _check_condition(condition: str) -> str:
    if condition not in CONDITIONS:
        raise ModelError(
            f"unknown load condition {condition!r}: choose 'stick' (burden sticks, J = J_m + (J_o + J_v)/n^2) "
            "or 'slip' (burden slides, J = J_m + J_o/n^2)")
    return condition


def _check_gains(gains) -> tuple[float, float, float]:
    try:
        kp, ki, kd = float(gains.k_p), float(gains.k_I), float(gains.k_D)
    except (AttributeError, TypeError, ValueError):
        raise ModelError(
            f"gains {gains!r} must have numeric attributes k_p [V/rpm], k_I [V/(rpm*s)], k_D [V*s/rpm]: "
            "pass a kilnctl.design.PIDGains") from None
    for name, v in (("k_p", kp), ("k_I", ki), ("k_D", kd)):
        if not math.isfinite(v):
            raise ModelError(f"gain {name} = {v!r} must be a finite number")
    return kp, ki, kd


def inertia(params: Parameters, condition: str = "stick") -> float:
    """Return the inertia at the motor shaft for a load condition.

    Parameters
    ----------
    params : Parameters
        Parameter set.
    condition : {"stick", "slip"}
        ``"stick"``: ``J_m + (J_o + J_v)/n**2`` (eq. 11); ``"slip"``:
        ``J_m + J_o/n**2`` (eq. 15).  ``J_o`` is ``params.J_kiln``, which
        follows ``params.J_e_mode``.

    Returns
    -------
    float
        Inertia J [kg*m^2].

    Raises
    ------
    ModelError
        For an unknown condition.
    """
    _check_condition(condition)
    return params.J_stick if condition == "stick" else params.J_slip


def electromechanical_frequency(params: Parameters, condition: str = "stick") -> float:
    """Return the natural frequency of the motor's open-loop electromechanical pair.

    The armature circuit at constant voltage and the reflected inertia form the
    pair ``L_a J s^2 + (L_a B_m + R_a J) s + (R_a B_m + k_i k_b)``.

    Parameters
    ----------
    params : Parameters
        Parameter set.
    condition : {"stick", "slip"}
        Load condition (sets J).

    Returns
    -------
    float
        ``sqrt((R_a B_m + k_i k_b) / (L_a J))`` [rad/s].
    """
    J = inertia(params, condition)
    return math.sqrt((params.R_a * params.B_m + params.k_i * params.k_b) / (params.L_a * J))


def motor_plant(params: Parameters, condition: str = "stick") -> ct.StateSpace:
    """Return the open-loop DC motor with the reflected kiln load (eq. 21, no controller).

    ``L_a di_a/dt = e_a - R_a i_a - k_b omega_m`` and
    ``J domega_m/dt = k_i i_a - B_m omega_m - T_l``.

    Parameters
    ----------
    params : Parameters
        Parameter set (R_a [ohm], L_a [H], k_i [N*m/A], k_b [V*s/rad], B_m [N*m*s/rad]).
    condition : {"stick", "slip"}
        Load condition (sets J [kg*m^2], see :func:`inertia`).

    Returns
    -------
    control.StateSpace
        Named ``"motor"``: states ``("i_a", "omega_m")`` [A, rad/s], inputs
        ``("e_a", "T_l")`` [V, N*m], outputs ``("omega_m", "i_a")`` [rad/s, A].
    """
    J = inertia(params, condition)
    La, Ra, ki, kb, Bm = params.L_a, params.R_a, params.k_i, params.k_b, params.B_m
    A = [[-Ra / La, -kb / La], [ki / J, -Bm / J]]
    B = [[1.0 / La, 0.0], [0.0, -1.0 / J]]
    C = [[0.0, 1.0], [1.0, 0.0]]
    D = [[0.0, 0.0], [0.0, 0.0]]
    return ct.ss(A, B, C, D, states=("i_a", "omega_m"), inputs=("e_a", "T_l"),
                 outputs=("omega_m", "i_a"), name="motor")


def motor_tf(params: Parameters, condition: str = "stick") -> ct.TransferFunction:
    """Return G(s) = omega_m/e_a, armature voltage to motor speed.

    ``G(s) = k_i / (L_a J s^2 + (L_a B_m + R_a J) s + R_a B_m + k_i k_b)``.

    Parameters
    ----------
    params : Parameters
        Parameter set.
    condition : {"stick", "slip"}
        Load condition (sets J [kg*m^2]).

    Returns
    -------
    control.TransferFunction
        G(s) [rad/(V*s)], input ``e_a`` [V], output ``omega_m`` [rad/s].
    """
    J = inertia(params, condition)
    La, Ra, ki, kb, Bm = params.L_a, params.R_a, params.k_i, params.k_b, params.B_m
    return ct.tf([ki], [La * J, La * Bm + Ra * J, Ra * Bm + ki * kb],
                 inputs="e_a", outputs="omega_m", name="G")


def pid_tf(gains: "PIDGains") -> ct.TransferFunction:
    """Return the ideal PID C(s) = k_p + k_I/s + k_D s acting on the speed error.

    This is the voltage the armature sees, ``e_a + k_D de_f/dt``, per unit of
    error.  It is improper when ``k_D > 0``; use it inside loops (``C*G`` is
    proper), not on its own.

    Parameters
    ----------
    gains : PIDGains
        ``k_p`` [V/rpm], ``k_I`` [V/(rpm*s)], ``k_D`` [V*s/rpm].

    Returns
    -------
    control.TransferFunction
        ``(k_D s^2 + k_p s + k_I)/s`` [V/rpm], input ``e_f``, output ``e_arm``.
    """
    kp, ki, kd = _check_gains(gains)
    return ct.tf([kd, kp, ki], [1.0, 0.0], inputs="e_f", outputs="e_arm", name="C")


def loop_tf(params: Parameters, gains: "PIDGains", condition: str = "stick") -> ct.TransferFunction:
    """Return the loop transfer function L(s) = K C(s) G(s) of the speed loop.

    The closed loop is stable where ``1 + kappa L(s)`` has its roots in the
    left half plane; the root locus over ``kappa`` (``kappa = 1`` at the given
    gains) scales all three gains together, keeping the PID zeros fixed.  The
    gain at a point ``s0`` of that locus is ``kappa = -1/L(s0)``.

    Parameters
    ----------
    params : Parameters
        Parameter set (``K_fb`` is K [rpm*s/rad]).
    gains : PIDGains
        PID gains.
    condition : {"stick", "slip"}
        Load condition.

    Returns
    -------
    control.TransferFunction
        L(s) [-] (error in rpm around the loop).
    """
    # no minreal: the integrator pole at s = 0 is kept even when k_I = 0 puts a zero there
    Ls = params.K_fb * pid_tf(gains) * motor_tf(params, condition)
    return ct.tf(Ls.num[0][0], Ls.den[0][0], inputs="e_f", outputs="y_fb", name="L")


def eq21_blocks(params: Parameters, gains: "PIDGains", condition: str = "stick") -> list[ct.StateSpace]:
    """Return the blocks of Fig. 3 / eq. 21 as named python-control systems.

    Parameters
    ----------
    params : Parameters
        Parameter set.
    gains : PIDGains
        PID gains ``k_p`` [V/rpm], ``k_I`` [V/(rpm*s)], ``k_D`` [V*s/rpm].
    condition : {"stick", "slip"}
        Load condition (sets J [kg*m^2]).

    Returns
    -------
    list of control.StateSpace
        ``armature`` (state ``x_a``; inputs ``e_a``, ``e_f``, ``omega_m``; output
        ``i_a = x_a + (k_D/L_a) e_f``, eq. 21 lines 1-2), ``mechanics`` (state
        ``omega_m``; inputs ``i_a``, ``T_l``), ``pi`` (state ``z``; input ``e_f``;
        output ``e_a = k_p e_f + k_I z``, eq. 21 line 5) and ``error``
        (``e_f = e_v - K omega_m``, eq. 21 line 6), in that order.
    """
    kp, ki, kd = _check_gains(gains)
    J = inertia(params, condition)
    La, Ra, kt, kb, Bm, K = params.L_a, params.R_a, params.k_i, params.k_b, params.B_m, params.K_fb
    # L_a d(x_a)/dt = e_a - R_a i_a - k_b omega_m, with i_a = x_a + (k_D/L_a) e_f
    armature = ct.ss([[-Ra / La]], [[1.0 / La, -Ra * kd / La**2, -kb / La]], [[1.0]], [[0.0, kd / La, 0.0]],
                     states=("x_a",), inputs=("e_a", "e_f", "omega_m"), outputs=("i_a",), name="armature")
    mechanics = ct.ss([[-Bm / J]], [[kt / J, -1.0 / J]], [[1.0]], [[0.0, 0.0]],
                      states=("omega_m",), inputs=("i_a", "T_l"), outputs=("omega_m",), name="mechanics")
    pi = ct.ss([[0.0]], [[1.0]], [[ki]], [[kp]], states=("z",), inputs=("e_f",), outputs=("e_a",), name="pi")
    error = ct.ss(np.zeros((0, 0)), np.zeros((0, 2)), np.zeros((1, 0)), [[1.0, -K]],
                  inputs=("e_v", "omega_m"), outputs=("e_f",), name="error")
    return [armature, mechanics, pi, error]


def closed_loop_ss(params: Parameters, gains: "PIDGains", condition: str = "stick") -> ct.StateSpace:
    """Return the closed speed loop of eq. 21 as a proper state-space system.

    Built by ``control.interconnect`` from the blocks of :func:`eq21_blocks`.
    The derivative action enters as the direct term ``(k_D/L_a) e_f`` in the
    current, so the system is proper with a feedthrough ``k_D/L_a`` [A/rpm]
    from ``e_v`` to ``i_a``.

    Parameters
    ----------
    params : Parameters
        Parameter set.
    gains : PIDGains
        PID gains ``k_p`` [V/rpm], ``k_I`` [V/(rpm*s)], ``k_D`` [V*s/rpm].
    condition : {"stick", "slip"}
        Load condition (sets J [kg*m^2]).

    Returns
    -------
    control.StateSpace
        Named ``"speed_loop"``: states ``("x_a", "omega_m", "z")`` [A, rad/s,
        rpm*s] in this order; inputs ``("e_v", "T_l")`` [rpm, N*m]; outputs
        ``("omega_m", "i_a")`` [rad/s, A].

    Raises
    ------
    ModelError
        For an unknown condition or non-numeric gains.
    """
    blocks = eq21_blocks(params, gains, condition)
    sys = ct.interconnect(blocks, inplist=["error.e_v", "mechanics.T_l"],
                          outlist=["mechanics.omega_m", "armature.i_a"])
    # interconnect orders states as the blocks are listed: armature, mechanics, pi
    if sys.nstates != 3:  # pragma: no cover - guards a change of interconnect's state ordering
        raise ModelError(f"closed loop has {sys.nstates} states, expected 3 (x_a, omega_m, z)")
    return ct.ss(sys.A, sys.B, sys.C, sys.D, states=("x_a", "omega_m", "z"), inputs=("e_v", "T_l"),
                 outputs=("omega_m", "i_a"), name="speed_loop")


def characteristic_polynomial(params: Parameters, gains: "PIDGains", condition: str = "stick") -> np.ndarray:
    """Return the coefficients of the closed-loop characteristic polynomial.

    ``L_a J s^3 + (L_a B_m + R_a J + K k_i k_D) s^2 + (R_a B_m + k_i k_b + K k_i k_p) s + K k_i k_I``,
    from the signal-flow graph of Fig. 3 by Mason's gain formula (see
    ``docs/linear_model.md``).

    Parameters
    ----------
    params : Parameters
        Parameter set.
    gains : PIDGains
        PID gains ``k_p`` [V/rpm], ``k_I`` [V/(rpm*s)], ``k_D`` [V*s/rpm].
    condition : {"stick", "slip"}
        Load condition (sets J [kg*m^2]).

    Returns
    -------
    numpy.ndarray
        ``[a3, a2, a1, a0]``, highest power first, scaled as written above
        (``a3 = L_a J`` [H*kg*m^2]); its roots are the closed-loop poles [rad/s].
    """
    kp, ki, kd = _check_gains(gains)
    J = inertia(params, condition)
    La, Ra, kt, kb, Bm, K = params.L_a, params.R_a, params.k_i, params.k_b, params.B_m, params.K_fb
    return np.array([
        La * J,
        La * Bm + Ra * J + K * kt * kd,
        Ra * Bm + kt * kb + K * kt * kp,
        K * kt * ki,
    ])
