"""Closed-loop figures of merit of the speed loop for one load condition."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import control as ct
import numpy as np

from ..linear import CONDITIONS, closed_loop_ss, inertia, loop_tf
from ..params import Parameters
from .gains import PIDGains
from .requirements import Requirements

__all__ = ["ConditionReport", "analyse", "damping", "dominant_poles", "unmet_requirements", "step_samples",
           "closed_loop_bandwidth"]

#: points of the step response used for step information
_STEP_POINTS = 3000


def damping(poles) -> np.ndarray:
    """Return the damping ratio of each pole.

    Parameters
    ----------
    poles : array_like of complex
        Poles [rad/s].

    Returns
    -------
    numpy.ndarray
        ``-Re(p)/|p|`` [-]: 1 for a stable real pole, negative when unstable,
        0 for a pole at the origin.
    """
    p = np.asarray(poles, dtype=complex)
    mag = np.abs(p)
    with np.errstate(invalid="ignore", divide="ignore"):
        z = np.where(mag > 0, -p.real / np.where(mag > 0, mag, 1.0), 0.0)
    return z


def dominant_poles(poles) -> np.ndarray:
    """Return the dominant pole(s): the one nearest the imaginary axis, with its conjugate.

    Parameters
    ----------
    poles : array_like of complex
        Closed-loop poles [rad/s].

    Returns
    -------
    numpy.ndarray
        One real pole, or a conjugate pair (positive imaginary part first) [rad/s].
    """
    p = np.asarray(poles, dtype=complex)
    slowest = p[np.argmax(p.real)]
    scale = max(1.0, abs(slowest))
    if abs(slowest.imag) <= 1e-9 * scale:
        return np.array([complex(slowest.real, 0.0)])
    return np.array([complex(slowest.real, abs(slowest.imag)), complex(slowest.real, -abs(slowest.imag))])


@dataclass(frozen=True)
class ConditionReport:
    """Closed-loop figures of the speed loop in one load condition.

    Attributes
    ----------
    condition : str
        ``"stick"`` or ``"slip"``.
    J : float
        Inertia at the motor shaft [kg*m^2].
    gains : PIDGains
        The gains analysed.
    poles : numpy.ndarray
        Closed-loop poles [rad/s], slowest first.
    dominant_zeta, dominant_wn : float
        Damping ratio [-] and natural frequency [rad/s] of the dominant pole(s).
    zeta_min_all : float
        Smallest damping ratio of all closed-loop poles [-].
    stable : bool
        All poles in the open left half plane.
    settling_time, rise_time, peak_time : float or None
        2 % settling time, 10-90 % rise time, time of the peak [s] of the speed
        after a reference step; None when unstable.
    overshoot : float or None
        Overshoot of the speed after a reference step [%]; None when unstable.
    dip : float or None
        Largest fall of the speed below its running maximum after a reference
        step [% of the final value]: the derivative on the error (eq. 21) kicks
        the current by ``k_D/L_a`` per rpm, the speed leaps ahead, then falls
        back before it rises again.  0 for a monotone response.
    gain_margin : float
        Gain margin of L(s) as a factor [-]; ``inf`` when the phase never
        crosses -180 degrees.
    phase_margin : float
        Smallest phase margin over all gain crossovers [deg]; ``inf`` when
        |L| never crosses 1.
    crossover_frequency : float or None
        Gain crossover frequency with the smallest phase margin [rad/s].
    bandwidth : float or None
        -3 dB bandwidth of ``K*omega_m/e_v`` [rad/s]; None when unstable.
    current_jump : float
        Step of the armature current per rpm of reference step, ``k_D/L_a`` [A/rpm].
    ramp_lag : float or None
        Steady lag of the speed behind the start-up ramp of ``params.ramp_rate``
        [rpm]: ``ramp_rate / K_v`` with ``K_v = lim s L(s)`` [1/s]; None when
        unstable or ``k_I = 0`` (the lag then grows without bound).
    characteristic_polynomial : numpy.ndarray
        ``[a3, a2, a1, a0]`` of :func:`kilnctl.linear.characteristic_polynomial`.
    notes : dict
        Why a figure is missing or infinite, by field name.
    """

    condition: str
    J: float
    gains: PIDGains
    poles: np.ndarray
    dominant_zeta: float
    dominant_wn: float
    zeta_min_all: float
    stable: bool
    settling_time: float | None
    rise_time: float | None
    peak_time: float | None
    overshoot: float | None
    dip: float | None
    gain_margin: float
    phase_margin: float
    crossover_frequency: float | None
    bandwidth: float | None
    current_jump: float
    ramp_lag: float | None
    characteristic_polynomial: np.ndarray
    notes: dict = field(default_factory=dict)

    @property
    def gain_margin_db(self) -> float:
        """Gain margin [dB] (``inf`` when infinite)."""
        if math.isinf(self.gain_margin):
            return math.inf
        return 20.0 * math.log10(self.gain_margin) if self.gain_margin > 0 else -math.inf

    def to_dict(self) -> dict:
        """Return the figures as JSON-ready values (no NaN or inf: ``None`` and a note).

        Returns
        -------
        dict
            Keys ``closed_loop_poles`` ([re, im] pairs, rad/s), ``dominant_zeta``,
            ``dominant_wn`` [rad/s], ``zeta_min_all``, ``settling_time_s``,
            ``overshoot_pct``, ``dip_pct``, ``rise_time_s``, ``peak_time_s``,
            ``gain_margin_db``, ``phase_margin_deg``, ``crossover_rad_s``,
            ``bandwidth_rad_s``, ``current_jump_A_per_rpm``, ``ramp_lag_rpm``, ``inertia_kg_m2``,
            ``stable``, ``characteristic_polynomial`` and ``notes``.
        """
        notes = dict(self.notes)

        def num(key, value):
            if value is None:
                return None
            value = float(value)
            if not math.isfinite(value):
                notes.setdefault(key, f"{value} (not representable in JSON)")
                return None
            return value

        return {
            "inertia_kg_m2": self.J,
            "closed_loop_poles": [[float(p.real), float(p.imag)] for p in self.poles],
            "dominant_zeta": num("dominant_zeta", self.dominant_zeta),
            "dominant_wn": num("dominant_wn", self.dominant_wn),
            "zeta_min_all": num("zeta_min_all", self.zeta_min_all),
            "stable": bool(self.stable),
            "settling_time_s": num("settling_time_s", self.settling_time),
            "overshoot_pct": num("overshoot_pct", self.overshoot),
            "dip_pct": num("dip_pct", self.dip),
            "rise_time_s": num("rise_time_s", self.rise_time),
            "peak_time_s": num("peak_time_s", self.peak_time),
            "gain_margin_db": num("gain_margin_db", self.gain_margin_db),
            "phase_margin_deg": num("phase_margin_deg", self.phase_margin),
            "crossover_rad_s": num("crossover_rad_s", self.crossover_frequency),
            "bandwidth_rad_s": num("bandwidth_rad_s", self.bandwidth),
            "current_jump_A_per_rpm": self.current_jump,
            "ramp_lag_rpm": num("ramp_lag_rpm", self.ramp_lag),
            "characteristic_polynomial": [float(c) for c in self.characteristic_polynomial],
            "notes": notes,
        }


def _step_time(poles: np.ndarray) -> np.ndarray:
    slowest = -float(np.max(poles.real))
    fastest = float(np.max(np.abs(poles)))
    t_final = 8.0 / slowest
    n = int(min(200_000, max(_STEP_POINTS, 20 * t_final * fastest)))
    return np.linspace(0.0, t_final, n)


def step_samples(sys: ct.StateSpace, t: np.ndarray) -> np.ndarray:
    """Return the exact sampled unit-step response of a SISO state-space system.

    Zero-order-hold discretisation (``scipy.linalg.expm`` of the augmented
    matrix) is exact for a step input; a few milliseconds for 3 000 samples,
    against about 0.15 s for ``control.step_response``.

    Parameters
    ----------
    sys : control.StateSpace
        Single-input, single-output system, zero initial state.
    t : numpy.ndarray
        Equally spaced times from 0 [s].

    Returns
    -------
    numpy.ndarray
        Output at ``t`` (units of the output per unit of input).
    """
    from scipy.linalg import expm

    A, B, C, D = (np.asarray(m, dtype=float) for m in (sys.A, sys.B, sys.C, sys.D))
    n = A.shape[0]
    dt = float(t[1] - t[0])
    M = np.zeros((n + 1, n + 1))
    M[:n, :n], M[:n, n:] = A * dt, B * dt
    E = expm(M)
    Ad, bd = E[:n, :n], E[:n, n]
    x = np.zeros((len(t), n))
    for k in range(1, len(t)):
        x[k] = Ad @ x[k - 1] + bd
    return x @ C[0] + D[0, 0]


def closed_loop_bandwidth(sys: ct.StateSpace, dbdrop: float = -3.0) -> float:
    """Return the first frequency where the gain falls ``dbdrop`` below its DC value.

    The same definition as ``control.bandwidth``, evaluated on the transfer
    function's polynomials and refined by bisection (``control.bandwidth``
    takes about 0.25 s here).

    Parameters
    ----------
    sys : control.StateSpace
        Stable single-input, single-output system with a non-zero DC gain.
    dbdrop : float, default -3
        Drop [dB], negative.

    Returns
    -------
    float
        Bandwidth [rad/s]; ``inf`` when the gain never drops that far.
    """
    from scipy.optimize import brentq

    tf = ct.ss2tf(sys)
    num, den = np.asarray(tf.num[0][0], float), np.asarray(tf.den[0][0], float)
    level = abs(num[-1] / den[-1]) * 10 ** (dbdrop / 20)
    scale = max(1e-6, float(np.max(np.abs(np.roots(den))))) if len(den) > 1 else 1.0
    w = np.logspace(np.log10(scale) - 6, np.log10(scale) + 3, 2000)

    def excess(x):
        return np.abs(np.polyval(num, 1j * x) / np.polyval(den, 1j * x)) - level

    e = excess(w)
    below = np.nonzero(e < 0)[0]
    if below.size == 0:
        return math.inf
    i = below[0]
    return float(w[0]) if i == 0 else float(brentq(excess, w[i - 1], w[i], xtol=1e-12, rtol=1e-12))


def analyse(params: Parameters, gains: PIDGains, condition: str = "stick") -> ConditionReport:
    """Compute the closed-loop figures of the speed loop in one load condition.

    Parameters
    ----------
    params : Parameters
        Parameter set.
    gains : PIDGains
        PID gains ``k_p`` [V/rpm], ``k_I`` [V/(rpm*s)], ``k_D`` [V*s/rpm].
    condition : {"stick", "slip"}
        Load condition.

    Returns
    -------
    ConditionReport
        Poles, dominant damping and natural frequency, step information of
        ``omega_m`` after a reference step (``control.step_info``), margins of
        ``L(s) = K C(s) G(s)`` (``control.stability_margins``) and bandwidth.
    """
    from ..linear import characteristic_polynomial

    sys = closed_loop_ss(params, gains, condition)
    poles = np.asarray(sys.poles(), dtype=complex)
    poles = poles[np.lexsort((-np.abs(poles.imag), -poles.real))]
    zetas = damping(poles)
    dom = dominant_poles(poles)
    stable = bool(np.all(poles.real < 0))
    notes: dict[str, str] = {}

    settling = rise = peak = overshoot = dip = bandwidth = ramp_lag = None
    if stable:
        speed = sys[0, 0] * params.K_fb  # K*omega_m/e_v, unit DC gain
        t = _step_time(poles)
        y = step_samples(speed, t)
        info = ct.step_info(y, timepts=t)
        settling, rise, peak, overshoot = (float(info[k]) for k in ("SettlingTime", "RiseTime", "PeakTime",
                                                                   "Overshoot"))
        dip = float(np.max(np.maximum.accumulate(y) - y) / abs(y[-1]) * 100.0)
        bandwidth = closed_loop_bandwidth(speed)
        if gains.k_I > 0:
            den0 = params.R_a * params.B_m + params.k_i * params.k_b
            ramp_lag = params.ramp_rate / (params.K_fb * gains.k_I * params.k_i / den0)
        else:
            notes["ramp_lag_rpm"] = "k_I = 0: the lag behind a ramp grows without bound"
        if not math.isfinite(bandwidth):
            notes["bandwidth_rad_s"] = "the closed-loop gain never drops 3 dB below its DC value"
            bandwidth = math.inf
    else:
        msg = "closed loop unstable: no step information"
        for key in ("settling_time_s", "rise_time_s", "peak_time_s", "overshoot_pct", "dip_pct", "bandwidth_rad_s",
                    "ramp_lag_rpm"):
            notes[key] = msg

    L = loop_tf(params, gains, condition)
    gm, pm, _sm, _wpc, wgc, _wms = ct.stability_margins(L)
    gm, pm = float(gm), float(pm)
    if math.isinf(gm):
        notes["gain_margin_db"] = "infinite: the phase of L(jw) never crosses -180 deg"
    if math.isinf(pm):
        notes["phase_margin_deg"] = "infinite: |L(jw)| never crosses 1"
    crossover = float(wgc) if math.isfinite(float(wgc)) else None

    return ConditionReport(
        condition=condition, J=inertia(params, condition), gains=gains, poles=poles,
        dominant_zeta=float(damping(dom)[0]), dominant_wn=float(abs(dom[0])),
        zeta_min_all=float(zetas.min()), stable=stable,
        settling_time=settling, rise_time=rise, peak_time=peak, overshoot=overshoot, dip=dip,
        gain_margin=gm, phase_margin=pm, crossover_frequency=crossover, bandwidth=bandwidth,
        current_jump=gains.k_D / params.L_a, ramp_lag=ramp_lag,
        characteristic_polynomial=characteristic_polynomial(params, gains, condition), notes=notes)


def unmet_requirements(reports, requirements: Requirements) -> list[tuple[str, str, float]]:
    """List the requirements the reports do not meet.

    Parameters
    ----------
    reports : mapping of str to ConditionReport
        Reports by load condition.
    requirements : Requirements
        Resolved requirements (``wn_max`` a number).

    Returns
    -------
    list of (str, str, float)
        ``(requirement name, sentence, relative violation)``, empty when all
        are met.  The sentence names the condition and the value achieved.
    """
    req = requirements
    tol = 1e-6
    out = []
    for cond in CONDITIONS:
        if cond not in reports:
            continue
        r = reports[cond]
        if not r.stable:
            out.append(("stability", f"closed loop unstable in {cond} (poles {np.round(r.poles, 3)})", 1e3))
            continue
        if r.zeta_min_all < req.zeta_min - tol:
            out.append(("zeta_min", f"damping ratio {r.zeta_min_all:.3f} < zeta_min = {req.zeta_min:g} ({cond})",
                        (req.zeta_min - r.zeta_min_all) / max(req.zeta_min, 1e-3)))
        if r.dominant_wn > req.wn_max * (1 + tol):
            out.append(("wn_max", f"dominant natural frequency {r.dominant_wn:.3f} rad/s > wn_max = "
                        f"{req.wn_max:.3f} rad/s ({cond})", (r.dominant_wn - req.wn_max) / req.wn_max))
        if r.settling_time > req.settling_time_max * (1 + tol):
            out.append(("settling_time_max", f"settling time {r.settling_time:.3f} s > settling_time_max = "
                        f"{req.settling_time_max:g} s ({cond})",
                        (r.settling_time - req.settling_time_max) / req.settling_time_max))
        if r.overshoot > req.overshoot_max + 1e-6:
            out.append(("overshoot_max", f"overshoot {r.overshoot:.3f} % > overshoot_max = {req.overshoot_max:g} % "
                        f"({cond})", (r.overshoot - req.overshoot_max) / max(req.overshoot_max, 1.0)))
    return out
