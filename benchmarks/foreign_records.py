"""Foreign start-up records (red team): a plant written apart from kilnctl, logged as a plant historian would.

The plant is written from the paper (van Dyk & Pretorius 1994, eqs. 1-21, Table 1)
and /work/shared/paper/NOTES.md only, with numpy; it imports nothing of
kilnctl's model nor ``benchmarks/baselines.py``.  Its own formulation:

* DC motor, armature ``L_a di/dt = e_a + k_D de_f/dt - R_a i - k_b w_m`` with the
  derivative realised as a direct term (NOTES, eq. 21), PI voltage clamped to
  +-V_max with the integrator frozen while clamped; reference ramp ``ramp_rate``
  [rpm/s] to ``omega_ref`` [rpm].
* Kiln and burden: the torque-consistent stick-slip law written as a state
  machine (stuck: burden turns with the shell while the holding torque
  ``J_v a_k + m g L sin psi`` stays within ``mu_s m g R cos psi``; sliding:
  kinetic torque ``mu_c m g R cos psi`` against the relative speed; re-stick
  when the relative speed changes sign and the static limit holds), fixed-step
  RK4 at 0.5 ms with mode changes checked after every step.  Bearing friction
  eq. 17 as a tanh-smoothed Coulomb torque.
* Effects in forms of their own: ``J2`` (a second motor rigidly on the shaft),
  ``shaft`` (a compliant shaft between motor and gearbox, stiffness and damping
  on the motor axis), ``lag`` (a speed sensor of first order; its output is
  both fed back and logged), ``coulomb`` (motor-side Coulomb friction, tanh),
  ``isensor`` (current sensor with a gain error and an offset; not in
  kilnctl's catalogue), ``load_step`` (a load torque switched on at the kiln
  mid-record; not in the catalogue).
* Effect forms added by the third red team (each documented where it acts):
  ``ilimit`` (the converter's own current limiter: a PI loop of finite bandwidth on
  the armature current above ``I_lim`` that takes voltage off the speed loop's
  command, the speed integrator frozen while it acts: the catalogue's
  current_limit in another form), ``stribeck`` (sliding friction of the burden
  falling smoothly from mu_s to mu_c with the slip speed, ``exp(-(v/v_s)^2)``,
  instead of the abrupt switch), ``gear_ripple`` (girth-gear mesh torque ripple
  at the tooth-passing frequency, ``a |T| sin(Z theta_k)``), ``encoder`` (speed
  from an incremental encoder: pulses counted over a window ``T_w``, held; fed
  back and logged: quantised and delayed by about ``T_w/2``, the catalogue's
  speed_sensor_lag in another form), ``field_weak`` (flux weakened above
  ``w_base`` rpm: k_b and k_i scaled by ``w_base/|w|``), ``scurve`` (a
  jerk-limited speed reference, the rate rising and falling linearly over
  ``T_j`` s at each end, same end time as the straight ramp), and, in the
  logged signals only, ``idrift`` (a current-sensor offset drifting linearly at
  ``rate`` A/s), ``dropout`` (the logger repeating its last sample of both
  channels from ``t`` for ``dur`` s) and ``adc`` (current quantised to ``q`` A).
* Effect forms added by the fourth red team (each neutral when absent):
  ``delay`` (a pure transport delay ``T_d`` [s] of the speed sensor: the controller
  and the logger see w_m(t - T_d), read from a ring buffer of the motor speed at the
  RK4 steps, linear between them for the substeps: the catalogue's
  speed_sensor_lag in another form), ``filter2`` (a second-order low-pass speed
  filter, natural frequency ``w_n`` [rad/s], damping ``zeta``, fed back and logged;
  two states: speed_sensor_lag in another form), ``quad_drag`` (a drag on the
  kiln shell growing with the square of its speed, ``c_q w_k |w_k|`` [N m],
  w_k in rad/s: the catalogue's viscous_drag in another form, told apart from
  friction on the ramp), ``ovality`` (a kiln-angle-periodic load of two harmonics,
  ``T1 sin(th_k + phi1) + T2 sin(2 th_k + phi2)`` [N m] against the drive:
  kiln_unbalance in another form when T1 dominates) and ``coupling_j2`` (a second
  motor of inertia ``J`` [kg m^2] on the motor shaft through a soft coupling of
  stiffness ``k`` [N m/rad] and damping ``c`` [N m s/rad]; two states: its speed
  and angle, and it carries no torque of its own: second_motor in another form
  when the coupling is stiff enough that the rotor follows).
* Effect forms added by the fifth red team (each neutral when absent):
  ``motor_viscous`` (a viscous drag ``b w_m`` [N m], b in N m s/rad, on the motor
  shaft, e.g. the motor's fan and brushes, on top of Table 1's tiny B_m: the
  catalogue's viscous_drag in another form, acting at the motor and referred
  through the gear ratio, B_o = n^2 b on the kiln axis while the shaft is rigid),
  ``runout`` (girth-gear runout: the mesh binds during the half revolution in
  which the high spot is pressed into the pinion, a load ``T max(0, sin(th_k +
  phi))`` [N m] against the drive, once per kiln revolution but half-wave
  rectified: a kink where it sets in, a mean of T/pi and a first harmonic of
  T/2: kiln_unbalance in another form), ``sgain`` (a speed sensor with a gain
  error ``g``: fed back and logged speed ``g w_m``; the drive settles at
  omega_ref / g; not in the catalogue) and, in the logged signals only,
  ``ilag`` (a current sensor of first order, ``tau`` [s]: the logged current
  is ``tau di_log/dt = i_a - i_log``, filtered exactly at the plant's steps
  before the logger samples it; the control loop does not see it; not in the
  catalogue).

Records are written in layouts kilnctl has not seen (column names, units,
rates, ISO timestamps, missing samples, uneven time base), each with the
setup TOML docs/measurements.md asks for and a ``.truth.json``.

``python -m benchmarks.foreign_records --list`` lists them,
``python -m benchmarks.foreign_records --write DIR [--only NAME,...]`` writes them.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import zlib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

__all__ = ["PlantSpec", "RECORDS", "plant_constants", "simulate_plant", "write_record", "main"]

# Table 1 of the paper (and NOTES.md readings), SI units
TABLE1 = dict(R_a=0.00961, L_a=0.00057, k_i=4.6, k_b=4.6, J_m=21.5, B_m=0.005, J_o=6.978e6, J_v=1.678e6,
              m_v=580e3, L=1.353, R=2.17, mu_c=0.4, mu_s=0.51, n=1076.5, mu_brg=0.001, P=16.512e6,
              l_brg=0.7155, k_brg=0.5475, g=9.81)
K_FB = 60.0 / (2.0 * math.pi)   # rpm per rad/s (eq. 21's K)


@dataclass
class PlantSpec:
    """One foreign start-up: plant values, effects, controller and how it is logged."""

    name: str
    t_end: float                       # s after the trigger
    fs: float                          # logger rate [Hz]
    gains: tuple = (2.0, 5.0, 0.01)    # k_p [V/rpm], k_I [V/(rpm s)], k_D [V s/rpm]
    ramp_rate: float = 74.0            # rpm/s
    omega_ref: float = 500.0           # rpm
    V_max: float = 500.0               # V
    base: dict = field(default_factory=dict)      # Table 1 overrides (true plant)
    setup_kiln: dict = field(default_factory=dict)  # what the user's setup states in [kiln]
    effects: dict = field(default_factory=dict)   # effect name -> values (this plant's forms)
    expected: tuple = ()               # catalogue effects a correct diagnosis selects
    layout: str = "plain"              # how the record is written (see write_record)
    pre_s: float = 1.5                 # logged seconds at rest before the ramp
    noise: tuple = (6.0, 0.4)          # white noise std: current [A], speed [rpm]
    ar1: tuple = (5.0, 0.2, 0.3)       # AR(1) noise: current [A], speed [rpm], time constant [s]
    seed: int = 0
    note: str = ""
    h: float = 5e-4                    # the plant's RK4 step [s] (1e-3 is enough where a test needs speed)
    visibility: dict = field(default_factory=dict)  # how much the effects change the record (measured, written)


def _reference(t, c):
    """Speed reference [rpm]: the straight ramp, or with ``T_j`` > 0 (``scurve``) a jerk-limited one.

    The S-curve's rate rises linearly from 0 to r over T_j, holds, and falls linearly to 0 over T_j,
    ending at the straight ramp's end time T = omega_ref / ramp_rate, so r = omega_ref / (T - T_j).
    """
    if t <= 0:
        return 0.0
    W, T, Tj = c["omega_ref"], c["omega_ref"] / c["ramp_rate"], c["T_j"]
    if Tj <= 0:
        return min(c["ramp_rate"] * t, W)
    if t >= T:
        return W
    r = W / (T - Tj)
    if t < Tj:
        return 0.5 * r * t * t / Tj
    if t <= T - Tj:
        return 0.5 * r * Tj + r * (t - Tj)
    u = T - t
    return W - 0.5 * r * u * u / Tj


def _delayed(c, t):
    """delay: the motor speed at t - T_d [rad/s] from the ring buffer ``c["buf"]`` (slot k % size holds the speed at
    step k of ``c["h"]``), linear between the stored steps; at rest (0) before the trigger."""
    s = (t - c["T_d"]) / c["h"]
    if s <= 0:
        return 0.0
    k0 = int(math.floor(s))
    f = s - k0
    buf = c["buf"]
    return (1.0 - f) * buf[k0 % buf.size] + f * buf[(k0 + 1) % buf.size]


def _rhs(x, t, c, mode):
    """Right-hand side of the plant.

    State x = [x_a, z, w_m, th_m, w_k, th_k, psi, w_b, w_s, z_l, y_f, v_f, w_2, th_2]: the last four (``filter2``'s
    output and its rate, ``coupling_j2``'s rotor speed and angle) may be left off when those forms are absent.
    """
    x_a, z, w_m, th_m, w_k, th_k, psi, w_b, w_s, z_l = x[:10]
    y_f, v_f, w_2, th_2 = x[10:14] if x.size > 10 else (0.0, 0.0, 0.0, 0.0)
    e_v = _reference(t, c)
    if c["T_w"] > 0:
        w_fb = c["w_enc"]           # encoder speed, updated by simulate_plant every T_w
    elif c["T_d"] > 0:
        w_fb = _delayed(c, t)       # delay: transport delay of the speed sensor
    elif c["w_n"] > 0:
        w_fb = y_f                  # filter2: second-order low-pass of the speed
    else:
        w_fb = w_s if c["tau_s"] > 0 else w_m
    w_fb = c["g_s"] * w_fb          # sgain: speed sensor gain error (1 without it)
    e_f = e_v - K_FB * w_fb
    e_pi = c["k_p"] * e_f + c["k_I"] * z
    i_a = x_a + c["k_D"] / c["L_a"] * e_f
    # ilimit: the converter's current limiter takes u_l = k_pl (i - I_lim)+ + k_il z_l off the command
    u_l = 0.0
    if c["I_lim"] > 0:
        u_l = c["k_pl"] * max(0.0, i_a - c["I_lim"]) + c["k_il"] * z_l
    e_cmd = e_pi - u_l
    clamped = (abs(e_cmd) > c["V_max"] and e_pi * e_f > 0) or (u_l > 0 and e_f > 0)
    e_a = max(-c["V_max"], min(c["V_max"], e_cmd))
    dz_l = (i_a - c["I_lim"]) if (c["I_lim"] > 0 and (z_l > 0 or i_a > c["I_lim"])) else 0.0
    # field_weak: flux falls as w_base / |w| above the base speed (k_b and k_i alike)
    phi = 1.0
    if c["w_base"] > 0 and abs(w_m) > c["w_base"]:
        phi = c["w_base"] / abs(w_m)
    # sensor
    dw_s = (w_m - w_s) / c["tau_s"] if c["tau_s"] > 0 else 0.0
    # burden and kiln torques (kiln axis)
    mg = c["m_v"] * c["g"]
    T_grav = mg * c["L"] * math.sin(psi)
    T_brg = c["T_brg"] * math.tanh(w_k / 1e-3)
    T_load = c["load"] if t >= c["load_t"] else 0.0
    if c["c_q"] > 0:   # quad_drag: drag on the shell growing with the square of its speed
        T_load = T_load + c["c_q"] * w_k * abs(w_k)
    if c["T_ro"] > 0:   # runout: the mesh binds during the half revolution the high spot is in the pinion
        T_load = T_load + c["T_ro"] * max(0.0, math.sin(th_k + c["phi_ro"]))
    if c["T1_ov"] > 0 or c["T2_ov"] > 0:   # ovality: kiln-angle-periodic load, first and second harmonic
        T_load = T_load + (c["T1_ov"] * math.sin(th_k + c["phi1_ov"]) + c["T2_ov"] * math.sin(2 * th_k + c["phi2_ov"]))
    T_motor = phi * c["k_i"] * i_a - (c["B_m"] + c["b_mv"]) * w_m - c["T_cm"] * math.tanh(w_m / 0.05)
    a_2 = 0.0
    if c["J_c"] > 0:   # coupling_j2: a second rotor on the motor shaft through a soft coupling
        T_c = c["k_c"] * (th_m - th_2) + c["c_c"] * (w_m - w_2)
        T_motor = T_motor - T_c
        a_2 = T_c / c["J_c"]
    J_mot = c["J_m"] + c["J2"]
    if c["k_s"] > 0:   # compliant shaft on the motor axis between motor and gearbox
        T_sh = c["k_s"] * (th_m - c["n"] * th_k) + c["c_s"] * (w_m - c["n"] * w_k)
        a_m = (T_motor - T_sh) / J_mot
        T_drive_k = c["n"] * T_sh
        J_k = c["J_o"]
        J_drv = 0.0
    else:
        a_m = None
        T_drive_k = c["n"] * T_motor
        J_drv = J_mot * c["n"] ** 2
        J_k = c["J_o"] + J_drv
    if c["a_rip"] > 0:   # gear_ripple: mesh torque ripple at the girth gear's tooth-passing frequency
        T_drive_k = T_drive_k * (1.0 + c["a_rip"] * math.sin(c["Z_rip"] * th_k))
    if mode == 0:  # stuck: burden turns with the shell
        a_k = (T_drive_k - T_grav - T_brg - T_load) / (J_k + c["J_v"])
        a_b = a_k
    else:
        mu = c["mu_c"]
        if c["v_st"] > 0:   # stribeck: friction falls smoothly from mu_s to mu_c with the slip speed
            mu = c["mu_c"] + (c["mu_s"] - c["mu_c"]) * math.exp(-((w_k - w_b) / c["v_st"]) ** 2)
        T_f = mu * mg * c["R"] * math.cos(psi) * (1.0 if mode > 0 else -1.0)
        a_k = (T_drive_k - T_f - T_brg - T_load) / J_k
        a_b = (T_f - T_grav) / c["J_v"]
    if a_m is None:
        a_m = c["n"] * a_k
    # derivative of e_f for x_a: x_a = i_a - (k_D/L_a) e_f, L_a di/dt = e_a + k_D de_f - R i - k_b w
    dx_a = (e_a - c["R_a"] * i_a - phi * c["k_b"] * w_m) / c["L_a"]
    dz = 0.0 if clamped else e_f
    d = [dx_a, dz, a_m, w_m, a_k, w_k, w_b if mode else w_k, a_b, dw_s, dz_l]
    if x.size > 10:
        # filter2: y'' = w_n^2 (w_m - y) - 2 zeta w_n y'; coupling_j2: the rotor's speed and angle
        dv_f = c["w_n"] ** 2 * (w_m - y_f) - 2 * c["zeta"] * c["w_n"] * v_f if c["w_n"] > 0 else 0.0
        d += [v_f, dv_f, a_2, w_2]
    return np.array(d), i_a, w_fb, e_v


def _holding(x, t, c):
    """Friction torque needed to keep the burden stuck, and the static limit [N m]."""
    d, *_ = _rhs(x, t, c, 0)
    mg = c["m_v"] * c["g"]
    T_h = c["J_v"] * d[4] + mg * c["L"] * math.sin(x[6])
    return T_h, c["mu_s"] * mg * c["R"] * math.cos(x[6])


def plant_constants(spec: PlantSpec) -> dict:
    """The plant's constants for ``_rhs``: Table 1 with the spec's overrides, controller and effect values."""
    p = dict(TABLE1)
    p.update(spec.base)
    eff = spec.effects
    return dict(p, k_p=spec.gains[0], k_I=spec.gains[1], k_D=spec.gains[2], ramp_rate=spec.ramp_rate,
             omega_ref=spec.omega_ref, V_max=spec.V_max,
             T_brg=2 * p["mu_brg"] * p["P"] / 2 * math.cos(math.pi / 6) * (p["l_brg"] + p["k_brg"]) / 2,
             J2=eff.get("J2", {}).get("J", 0.0), k_s=eff.get("shaft", {}).get("k", 0.0),
             c_s=eff.get("shaft", {}).get("c", 0.0), tau_s=eff.get("lag", {}).get("tau", 0.0),
             T_cm=eff.get("coulomb", {}).get("T", 0.0), load=eff.get("load_step", {}).get("T", 0.0),
             load_t=eff.get("load_step", {}).get("t", 1e9),
             I_lim=eff.get("ilimit", {}).get("I", 0.0), k_pl=eff.get("ilimit", {}).get("k_p", 0.1),
             k_il=eff.get("ilimit", {}).get("k_i", 1.7), v_st=eff.get("stribeck", {}).get("v_s", 0.0),
             a_rip=eff.get("gear_ripple", {}).get("a", 0.0), Z_rip=eff.get("gear_ripple", {}).get("Z", 180),
             T_w=eff.get("encoder", {}).get("T_w", 0.0), ppr=eff.get("encoder", {}).get("ppr", 1024),
             w_enc=0.0, w_base=eff.get("field_weak", {}).get("w_base", 0.0) / K_FB,
             T_j=eff.get("scurve", {}).get("T_j", 0.0),
             T_d=eff.get("delay", {}).get("T_d", 0.0), w_n=eff.get("filter2", {}).get("w_n", 0.0),
             zeta=eff.get("filter2", {}).get("zeta", 0.5), c_q=eff.get("quad_drag", {}).get("c_q", 0.0),
             T1_ov=eff.get("ovality", {}).get("T1", 0.0), phi1_ov=eff.get("ovality", {}).get("phi1", 0.0),
             T2_ov=eff.get("ovality", {}).get("T2", 0.0), phi2_ov=eff.get("ovality", {}).get("phi2", 0.0),
             J_c=eff.get("coupling_j2", {}).get("J", 0.0), k_c=eff.get("coupling_j2", {}).get("k", 0.0),
             c_c=eff.get("coupling_j2", {}).get("c", 0.0),
             b_mv=eff.get("motor_viscous", {}).get("b", 0.0), T_ro=eff.get("runout", {}).get("T", 0.0),
             phi_ro=eff.get("runout", {}).get("phi", 0.0), g_s=eff.get("sgain", {}).get("g", 1.0))


def simulate_plant(spec: PlantSpec, h: float = 5e-4):
    """Simulate a foreign start-up.

    Parameters
    ----------
    spec : PlantSpec
        The plant, its effects and its controller.
    h : float
        Fixed RK4 step [s].

    Returns
    -------
    dict
        ``t`` [s] (0 = ramp start), true motor current ``i_a`` [A], motor speed ``w_m`` [rad/s],
        sensor speed ``w_s`` [rad/s], reference ``e_v`` [rpm], ``coupling_j2``'s rotor speed ``w_2`` [rad/s]
        (0 without it), number of mode changes ``events``.
    """
    c = plant_constants(spec)
    n_steps = int(round(spec.t_end / h))
    x = np.zeros(14)
    if c["T_d"] > 0:   # delay: ring buffer of the motor speed at the steps, long enough for t - T_d - h
        if c["T_d"] < h:
            raise ValueError(f"delay T_d = {c['T_d']} s is shorter than the step {h} s")
        c["h"] = h
        c["buf"] = np.zeros(int(math.ceil(c["T_d"] / h)) + 3)
    sensed = c["tau_s"] > 0 or c["T_w"] > 0 or c["T_d"] > 0 or c["w_n"] > 0 or c["g_s"] != 1.0
    enc_every = max(1, int(round(c["T_w"] / h))) if c["T_w"] > 0 else 0
    enc_prev = 0
    mode = 0
    out_t = np.empty(n_steps + 1)
    out = np.empty((n_steps + 1, 5))
    events = 0
    t = 0.0
    for k in range(n_steps + 1):
        d, i_a, w_fb, e_v = _rhs(x, t, c, mode)
        out_t[k] = t
        out[k] = (i_a, x[2], w_fb if sensed else x[2], e_v, x[12])
        if k == n_steps:
            break
        k1 = d
        k2 = _rhs(x + 0.5 * h * k1, t + 0.5 * h, c, mode)[0]
        k3 = _rhs(x + 0.5 * h * k2, t + 0.5 * h, c, mode)[0]
        k4 = _rhs(x + h * k3, t + h, c, mode)[0]
        x_new = x + h / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
        t += h
        if mode == 0:
            x_new[7] = x_new[4]
            T_h, T_s = _holding(x_new, t, c)
            if abs(T_h) > T_s:      # breakaway: slides down against the shell's motion
                mode = 1 if T_h > 0 else -1
                events += 1
        else:
            rel_new = x_new[4] - x_new[7]
            if (rel_new > 0) != (mode > 0):
                x_new[7] = x_new[4]   # relative speed through zero: try to re-stick
                T_h, T_s = _holding(x_new, t, c)
                mode = 0 if abs(T_h) <= T_s else (1 if T_h > 0 else -1)
                events += 1
        if c["I_lim"] > 0:
            x_new[9] = max(0.0, x_new[9])   # the limiter's integrator only takes voltage off
        x = x_new
        if c["T_d"] > 0:
            c["buf"][(k + 1) % c["buf"].size] = x[2]
        if enc_every and (k + 1) % enc_every == 0:   # encoder: whole pulses counted over the last window
            cnt = math.floor(x[3] * c["ppr"] / (2 * math.pi))
            c["w_enc"] = (cnt - enc_prev) * 2 * math.pi / c["ppr"] / (enc_every * h)
            enc_prev = cnt
    return dict(t=out_t, i_a=out[:, 0], w_m=out[:, 1], w_s=out[:, 2], e_v=out[:, 3], w_2=out[:, 4], events=events)


def _noise(rng, n, dt, std, tau):
    a = math.exp(-dt / tau)
    e = rng.standard_normal(n) * std * math.sqrt(1 - a * a)
    y = np.empty(n)
    acc = rng.standard_normal() * std
    for k in range(n):
        acc = a * acc + e[k]
        y[k] = acc
    return y


def logged(spec: PlantSpec):
    """The record as the logger saw it: sample times [s] (0 = ramp start), current [A], speed [rpm], ref [rpm].

    Parameters
    ----------
    spec : PlantSpec
        The record's description.

    Returns
    -------
    dict
        ``t`` [s], ``i`` [A] (as the current sensor reads it), ``n`` [rpm] (as the speed sensor reads it),
        ``ref`` [rpm], ``events`` (mode changes of the burden).
    """
    sim = simulate_plant(spec, spec.h)
    rng = np.random.default_rng(zlib.crc32(spec.name.encode()) + spec.seed)
    dt = 1.0 / spec.fs
    t = np.arange(-spec.pre_s, spec.t_end + 1e-9, dt)
    if spec.layout in ("uneven", "iso_uneven"):
        t = t + rng.uniform(-0.3, 0.3, t.size) * dt    # logger jitter
        t = np.sort(t)
    i_a = sim["i_a"]
    if "ilag" in spec.effects:     # current sensor of first order: exact discrete filter at the plant's steps
        a = math.exp(-(sim["t"][1] - sim["t"][0]) / spec.effects["ilag"]["tau"])
        i_a = np.empty_like(sim["i_a"])
        acc = sim["i_a"][0]
        for k, v in enumerate(sim["i_a"]):
            acc = a * acc + (1.0 - a) * v
            i_a[k] = acc
    i = np.interp(t, sim["t"], i_a, left=0.0)
    w = np.interp(t, sim["t"], sim["w_s"], left=0.0)
    ref = np.interp(t, sim["t"], sim["e_v"], left=0.0)
    if "isensor" in spec.effects:
        s = spec.effects["isensor"]
        i = s["gain"] * i + s["offset"]
    n = w * K_FB
    i = i + rng.standard_normal(t.size) * spec.noise[0] + _noise(rng, t.size, dt, spec.ar1[0], spec.ar1[2])
    n = n + rng.standard_normal(t.size) * spec.noise[1] + _noise(rng, t.size, dt, spec.ar1[1], spec.ar1[2])
    if "idrift" in spec.effects:   # current-sensor offset drifting from the trigger on (warm-up)
        i = i + spec.effects["idrift"]["rate"] * (t + spec.pre_s)
    if "adc" in spec.effects:      # current ADC: quantised to q A
        q = spec.effects["adc"]["q"]
        i = q * np.round(i / q)
    if "dropout" in spec.effects:  # logger repeats its last sample of both channels for dur s
        d = spec.effects["dropout"]
        held = (t >= d["t"]) & (t < d["t"] + d["dur"])
        if held.any():
            k0 = np.flatnonzero(held)[0] - 1
            i[held], n[held] = i[k0], n[k0]
    return dict(t=t, i=i, n=n, ref=ref, events=sim["events"])


# layouts: how the historian writes the columns. Each: header names, converters, and the --columns map
LAYOUTS = {
    # kA and rad/s at the motor, seconds, 3 samples dropped (a logger hiccup)
    "plain": dict(cols=("t [s]", "I_arm [kA]", "n_mot [rad/s]", "n_ref [rpm]"),
                  conv=(1.0, 1e-3, 2 * math.pi / 60, 1.0), drop=3,
                  columns="time_s=t [s],current_A=I_arm [kA],speed_rpm=n_mot [rad/s],speed_ref_rpm=n_ref [rpm]"),
    # ISO timestamps, semicolon separated, 1/min, no reference column
    "iso": dict(cols=("Timestamp", "Ankerstrom (A)", "Drehzahl (1/min)"), conv=(None, 1.0, 1.0), drop=0,
                columns="time_s=Timestamp,current_A=Ankerstrom (A),speed_rpm=Drehzahl (1/min)", sep=";"),
    # ms time base, tab separated, units only in the --columns map
    "ms": dict(cols=("t_ms", "Ia", "nM", "nRef"), conv=(1e3, 1.0, 1.0, 1.0), drop=0,
               columns="time_s=t_ms [ms],current_A=Ia [A],speed_rpm=nM [rpm],speed_ref_rpm=nRef [rpm]", sep="\t"),
    # uneven time base (jittered logger), kiln speed logged in rpm at the kiln (the historian's tag)
    "uneven": dict(cols=("time", "motor_current_A", "motor_speed_rpm", "kiln_speed_rpm", "quality"),
                   conv=(1.0, 1.0, 1.0, None), drop=0,
                   columns="time_s=time,current_A=motor_current_A,speed_rpm=motor_speed_rpm"),
    # only the kiln's speed is logged (rpm at the kiln), names with spaces
    "kiln": dict(cols=("Time [s]", "Motor current [A]", "Kiln speed [rpm]"), conv=(1.0, 1.0, 1.0 / 1076.5), drop=0,
                 columns="time_s=Time,current_A=Motor current,speed_rpm=Kiln speed [kiln rpm]"),
    # ISO timestamps with offset, uneven, kA
    "iso_uneven": dict(cols=("ts", "I [kA]", "speed [rpm]"), conv=(None, 1e-3, 1.0), drop=2,
                       columns="time_s=ts,current_A=I [kA],speed_rpm=speed [rpm]"),
}


def write_record(spec: PlantSpec, folder) -> dict:
    """Write ``<name>.csv``, ``<name>.toml`` (the setup) and ``<name>.truth.json`` into ``folder``.

    Parameters
    ----------
    spec : PlantSpec
        The record.
    folder : str or Path
        Output folder (created).

    Returns
    -------
    dict
        The truth, with the ``--columns`` map to give and the paths written.
    """
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    rec = logged(spec)
    lay = LAYOUTS[spec.layout]
    rng = np.random.default_rng(zlib.crc32(spec.name.encode()) + 7)
    keep = np.ones(rec["t"].size, bool)
    if lay["drop"]:
        keep[rng.choice(np.arange(10, rec["t"].size - 10), lay["drop"], replace=False)] = False
    sep = lay.get("sep", ",")
    lines = [f"# foreign plant record {spec.name}, logger {spec.fs:g} Hz", sep.join(lay["cols"])]
    t0_abs = np.datetime64("2026-03-01T06:15:00.000")
    for k in np.flatnonzero(keep):
        t = rec["t"][k] + spec.pre_s
        cells = []
        if lay["conv"][0] is None:
            stamp = t0_abs + np.timedelta64(int(round(t * 1e6)), "us")
            s = str(stamp)
            cells.append(s + ("+02:00" if spec.layout == "iso_uneven" else ""))
        else:
            cells.append(f"{t * lay['conv'][0]:.6f}")
        cells.append(f"{rec['i'][k] * lay['conv'][1]:.6g}")
        cells.append(f"{rec['n'][k] * lay['conv'][2]:.6g}")
        if len(lay["cols"]) > 3 and lay["cols"][3].startswith("n"):
            cells.append(f"{rec['ref'][k] * lay['conv'][3]:.6g}")
        if spec.layout == "uneven":
            cells.append(f"{rec['n'][k] / TABLE1['n']:.6g}")
            cells.append("good")
        lines.append(sep.join(cells))
    csv = folder / f"{spec.name}.csv"
    csv.write_text("\n".join(lines) + "\n")
    kiln = "\n".join(f"{k} = {v!r}" for k, v in spec.setup_kiln.items())
    toml = (f"# setup of foreign record {spec.name}\n[controller]\ngains = \"given\"\n"
            f"k_p = {spec.gains[0]}\nk_I = {spec.gains[1]}\nk_D = {spec.gains[2]}\n\n"
            f"[drive]\nramp_rate = {spec.ramp_rate}\nomega_ref = {spec.omega_ref}\n\n[kiln]\n{kiln}\n")
    (folder / f"{spec.name}.toml").write_text(toml)
    truth = dict(name=spec.name, effects=spec.effects, expected=list(spec.expected), base=spec.base,
                 fs=spec.fs, t_end=spec.t_end, layout=spec.layout, columns=lay["columns"], note=spec.note,
                 events=rec["events"], i_max=float(np.max(rec["i"])), n_samples=int(keep.sum()))
    if spec.visibility:
        truth["visibility"] = dict(definition=_VIS_DEF, **spec.visibility)
    (folder / f"{spec.name}.truth.json").write_text(json.dumps(truth, indent=1) + "\n")
    return dict(truth, csv=str(csv), toml=str(folder / f"{spec.name}.toml"))


_NUIS = dict(m_v=580e3 * 1.04, mu_c=0.4 * 0.97, mu_s=0.51 * 1.03, J_v=1.678e6 * 0.95)
_G1_BASE = dict(_NUIS, J_o=6.978e6 * 1.05, J_m=21.5 * 0.96, k_i=4.6 * 1.03, k_b=4.6 * 1.03, L=1.353 * 0.97,
                R_a=0.00961 * 1.08, mu_brg=0.0012)
# fifth red team: how much each record's effects change it, measured with this plant (written into the truth JSON)
_VIS_DEF = ("logged record minus itself without the effect(s) (without_<name>: that one only; g1: with f1's base "
            "values), the same noise draws: rms_A, mean_A (A) and rms_pct_std (% of the record's current std i_std_A) "
            "of the current difference after the ramp (t > omega_ref/ramp_rate), ramp_rms_A during it, speed_rms_rpm "
            "of the logged speed after it; noise_std_A: the logger's current noise (white and coloured)")
_G_VIS = {
    "g1": dict(i_std_A=172.1, noise_std_A=9.4,
               with_f1_base_only=dict(ramp_rms_A=8.4, rms_A=82.7, rms_pct_std=48.1, mean_A=-33.5, speed_rms_rpm=0.44)),
    "g2": dict(i_std_A=179.2, noise_std_A=7.8,
               without_effects=dict(ramp_rms_A=38.5, rms_A=68.3, rms_pct_std=38.1, mean_A=68.3, speed_rms_rpm=0.01)),
    "g3": dict(i_std_A=189.8, noise_std_A=7.8,
               without_effects=dict(ramp_rms_A=0.0, rms_A=27.9, rms_pct_std=14.7, mean_A=18.0, speed_rms_rpm=0.0)),
    "g4": dict(i_std_A=179.1, noise_std_A=7.8,
               without_effects=dict(ramp_rms_A=3.1, rms_A=20.4, rms_pct_std=11.4, mean_A=-0.6, speed_rms_rpm=0.0)),
    "g5": dict(i_std_A=181.1, noise_std_A=7.8,
               without_effects=dict(ramp_rms_A=4.4, rms_A=90.0, rms_pct_std=49.7, mean_A=-6.9, speed_rms_rpm=0.46)),
    "g6": dict(i_std_A=179.7, noise_std_A=7.8,
               without_effects=dict(ramp_rms_A=122.8, rms_A=49.9, rms_pct_std=27.7, mean_A=45.9, speed_rms_rpm=0.27),
               without_J2=dict(ramp_rms_A=99.8, rms_A=18.9, rms_pct_std=10.5, mean_A=0.3, speed_rms_rpm=0.26),
               without_motor_viscous=dict(ramp_rms_A=25.7, rms_A=45.5, rms_pct_std=25.3, mean_A=45.5,
                                          speed_rms_rpm=0.01)),
    "g7": dict(i_std_A=207.5, noise_std_A=7.8,
               without_effects=dict(ramp_rms_A=42.8, rms_A=94.1, rms_pct_std=45.3, mean_A=7.8, speed_rms_rpm=0.43),
               without_shaft=dict(ramp_rms_A=7.1, rms_A=89.1, rms_pct_std=42.9, mean_A=-1.2, speed_rms_rpm=0.43),
               without_ovality=dict(ramp_rms_A=41.4, rms_A=27.4, rms_pct_std=13.2, mean_A=8.7, speed_rms_rpm=0.01)),
    "g8": dict(i_std_A=187.8, noise_std_A=7.8,
               without_effects=dict(ramp_rms_A=23.0, rms_A=47.3, rms_pct_std=25.2, mean_A=22.0, speed_rms_rpm=1.0),
               without_coulomb=dict(ramp_rms_A=21.9, rms_A=21.7, rms_pct_std=11.6, mean_A=21.7, speed_rms_rpm=0.0),
               without_lag=dict(ramp_rms_A=5.4, rms_A=41.9, rms_pct_std=22.3, mean_A=0.2, speed_rms_rpm=1.0)),
}
RECORDS = [
    PlantSpec("f1_free_torque", 40.0, 100.0, base=_NUIS, setup_kiln=dict(friction_law="torque"),
              layout="plain", note="no effect; the setup knows the torque law; kA and rad/s, 3 samples missing"),
    PlantSpec("f2_j2_small", 30.0, 200.0, gains=(3.0, 4.0, 0.005), base=_NUIS,
              setup_kiln=dict(friction_law="torque"), effects={"J2": {"J": 7.0}}, expected=("second_motor",),
              layout="iso", note="second motor of 7 kg m^2 (below the usual 10-45); ISO timestamps; 200 Hz"),
    PlantSpec("f3_shaft", 25.0, 500.0, base=_NUIS, setup_kiln=dict(friction_law="torque"),
              effects={"shaft": {"k": 700.0, "c": 8.0}}, expected=("drivetrain_compliance",),
              layout="ms", note="compliant shaft on the motor axis: k_po = 700 n^2 = 8.1e8, C_po = 9.3e6 N m s/rad "
                                "(kiln axis); 500 Hz, time in ms"),
    PlantSpec("f4_lag_paperlaw", 60.0, 20.0, base=_NUIS, effects={"lag": {"tau": 0.008}},
              expected=("torque_friction_law", "speed_sensor_lag"), layout="uneven",
              note="8 ms speed sensor (in the logged speed too), torque law the setup does not know; 20 Hz "
                   "jittered time base, kiln speed column"),
    PlantSpec("f5_isensor", 40.0, 50.0, base=_NUIS, setup_kiln=dict(friction_law="torque"),
              effects={"isensor": {"gain": 1.05, "offset": 25.0}}, expected=(),
              layout="iso_uneven", note="current sensor 5 % high with +25 A offset (not in the catalogue)"),
    PlantSpec("f6_coulomb", 90.0, 10.0, base=_NUIS, setup_kiln=dict(friction_law="torque"),
              effects={"coulomb": {"T": 60.0}}, expected=("motor_coulomb_friction",), layout="plain",
              note="motor-side Coulomb friction 60 N m; 10 Hz, 90 s"),
    PlantSpec("f6b_coulomb_paperlaw", 90.0, 10.0, base=_NUIS, effects={"coulomb": {"T": 60.0}},
              expected=("torque_friction_law", "motor_coulomb_friction"), layout="plain",
              note="f6's plant, the setup not knowing the torque law"),
    PlantSpec("f7_load_step", 45.0, 50.0, base=_NUIS, effects={"load_step": {"T": 3e5, "t": 28.0}},
              expected=("torque_friction_law", "unexplained"), layout="ms",
              note="load torque of 3e5 N m at the kiln from t = 28 s (not in the catalogue); setup not knowing the "
                   "torque law"),
    PlantSpec("f8_kiln_speed", 120.0, 25.0, base=_NUIS, effects={"J2": {"J": 21.5}},
              expected=("torque_friction_law", "second_motor"), layout="kiln",
              note="the paper's second motor (21.5 kg m^2); only the kiln speed logged; 120 s at 25 Hz"),
    # third red team: effect forms of its own (see the module's docstring)
    PlantSpec("f10_ilimit", 40.0, 50.0, base=_NUIS, setup_kiln=dict(friction_law="torque"),
              effects={"ilimit": {"I": 900.0, "k_p": 0.1, "k_i": 1.7}}, expected=("current_limit",),
              layout="plain", note="converter current limiter at 900 A, PI of about 30 Hz bandwidth (overshoots "
                                   "briefly), speed integrator frozen while it acts; kilnctl's form: I_max = 900 A"),
    PlantSpec("f11_stribeck", 40.0, 100.0, base=_NUIS, setup_kiln=dict(friction_law="torque"),
              effects={"stribeck": {"v_s": 0.003}}, expected=(), layout="ms",
              note="burden friction falling smoothly from mu_s to mu_c with slip speed (v_s = 3 mrad/s), not "
                   "abruptly; the setup knows the torque law; not in the catalogue"),
    PlantSpec("f12_gear_ripple", 40.0, 50.0, base=_NUIS, setup_kiln=dict(friction_law="torque"),
              effects={"gear_ripple": {"a": 0.03, "Z": 180}}, expected=(), layout="iso",
              note="girth-gear mesh ripple, 3 % of the transmitted torque at 180 x kiln angle (1.39 Hz at set "
                   "speed, a chirp along the ramp); not in the catalogue"),
    PlantSpec("f13_encoder", 40.0, 50.0, base=_NUIS, setup_kiln=dict(friction_law="torque"),
              effects={"encoder": {"T_w": 0.006, "ppr": 4096}}, expected=("speed_sensor_lag",), layout="uneven",
              note="speed from an encoder, 4096 counts/rev over 6 ms windows, held (about 6 ms delay, 2.4 rpm "
                   "steps); fed back and logged; the loop hunts at 8 ms; kilnctl's form: tau_s of about 0.006 s"),
    PlantSpec("f14_idrift", 40.0, 50.0, base=_NUIS, setup_kiln=dict(friction_law="torque"),
              effects={"idrift": {"rate": 0.75}}, expected=(), layout="plain",
              note="current-sensor offset drifting 0.75 A/s (30 A over the record); logged only; not in the "
                   "catalogue"),
    PlantSpec("f15_field_weak", 40.0, 50.0, base=_NUIS, setup_kiln=dict(friction_law="torque"),
              effects={"field_weak": {"w_base": 350.0}}, expected=(), layout="ms",
              note="field weakening above 350 rpm (k_b, k_i x 350/n: 0.7 at 500 rpm); not in the catalogue"),
    PlantSpec("f16_scurve", 30.0, 50.0, base=_NUIS, setup_kiln=dict(friction_law="torque"),
              effects={"scurve": {"T_j": 2.0}}, expected=(), layout="plain",
              note="jerk-limited reference (rate up and down over 2 s, peak 105 rpm/s, same end time as the 74 "
                   "rpm/s ramp) logged in n_ref; not in the catalogue"),
    PlantSpec("f17_dropout_adc", 40.0, 100.0, base=_NUIS, setup_kiln=dict(friction_law="torque"),
              effects={"dropout": {"t": 22.0, "dur": 1.2}, "adc": {"q": 10.0}}, expected=(), layout="ms",
              note="logger repeats its last sample for 1.2 s from t = 22 s; current quantised to 10 A; not in "
                   "the catalogue (a logging fault)"),
    PlantSpec("f18_j2_field_weak", 40.0, 50.0, base=_NUIS, setup_kiln=dict(friction_law="torque"),
              effects={"J2": {"J": 21.5}, "field_weak": {"w_base": 420.0}}, expected=("second_motor",),
              layout="iso", note="the paper's second motor (21.5 kg m^2) on a drive weakening its field above 420 "
                                 "rpm (0.84 at 500 rpm, not in the catalogue); J_m2 = 21.5 in kilnctl's form"),
    PlantSpec("f19_stribeck_paperlaw", 40.0, 50.0, base=_NUIS, effects={"stribeck": {"v_s": 0.003}},
              expected=("torque_friction_law",), layout="plain",
              note="f11's Stribeck burden at 50 Hz, the setup not knowing the torque law (stick-slip cycles are "
                   "there, shaped smoothly)"),
    PlantSpec("f20_idrift_long", 140.0, 10.0, base=_NUIS, setup_kiln=dict(friction_law="torque"),
              effects={"idrift": {"rate": 0.25}}, expected=(), layout="plain",
              note="f14's drifting current-sensor offset, slower (0.25 A/s, 35 A over the record), on a record "
                   "longer than one kiln revolution (140 s at 10 Hz); not in the catalogue"),
    PlantSpec("f20b_free_long", 140.0, 10.0, base=_NUIS, setup_kiln=dict(friction_law="torque"), layout="plain",
              note="f20's control: the same plant and logger without the drift (no effect)"),
    # fourth red team: further forms of catalogue effects (see the module's docstring)
    PlantSpec("f21_delay", 40.0, 50.0, gains=(0.2, 1.5, 0.0), base=_NUIS, setup_kiln=dict(friction_law="torque"),
              effects={"delay": {"T_d": 0.03}}, expected=("speed_sensor_lag",), layout="uneven",
              note="speed sensor with a 30 ms transport delay (fed back and logged) on a drive tuned softly for it "
                   "(k_p 0.2, k_I 1.5, k_D 0: the paper's gains diverge); the loop rings at about 6 Hz after "
                   "each breakaway; kilnctl's form: tau_s of about 0.03 s"),
    PlantSpec("f22_filter2", 40.0, 100.0, gains=(0.22, 1.5, 0.0), base=_NUIS, setup_kiln=dict(friction_law="torque"),
              effects={"filter2": {"w_n": 2 * math.pi * 10.0, "zeta": 0.5}}, expected=("speed_sensor_lag",),
              layout="ms", note="second-order speed filter, 10 Hz, zeta 0.5 (fed back and logged; its low-frequency "
                                "lag 2 zeta / w_n = 16 ms), soft gains as f21; kilnctl's form: tau_s of 10-20 ms"),
    PlantSpec("f23_quad_drag", 60.0, 20.0, base=_NUIS, setup_kiln=dict(friction_law="torque"),
              effects={"quad_drag": {"c_q": 1.03e8}}, expected=("viscous_drag",), layout="plain",
              note="drag on the shell c_q w_k |w_k| with c_q = 1.03e8 N m s^2/rad^2: 2.4e5 N m at the set speed "
                   "(0.0486 rad/s), as a viscous B_o = 5.0e6 there (about 50 A); a quarter of it at half speed"),
    PlantSpec("f24_ovality", 90.0, 20.0, base=_NUIS, setup_kiln=dict(friction_law="torque"),
              effects={"ovality": {"T1": 2.0e5, "phi1": 0.6, "T2": 1.0e5, "phi2": 2.0}}, expected=("kiln_unbalance",),
              layout="iso", note="kiln load 2e5 sin(th_k + 0.6) + 1e5 sin(2 th_k + 2.0) N m (once and twice per "
                                 "revolution); 90 s is 0.7 of a kiln revolution; kilnctl's form: T_unb = 2e5"),
    PlantSpec("f25_coupling_j2", 30.0, 200.0, base=_NUIS, setup_kiln=dict(friction_law="torque"),
              effects={"coupling_j2": {"J": 25.0, "k": 4.0e4, "c": 150.0}}, expected=("second_motor",),
              layout="iso_uneven", note="second motor of 25 kg m^2 through a coupling of 4e4 N m/rad and 150 N m s/rad "
                                        "(8.7 Hz against the motor and the held kiln); kilnctl's form: J_m2 = 25"),
    PlantSpec("f26_delay_j2", 40.0, 50.0, gains=(0.3, 2.0, 0.0), base=_NUIS, setup_kiln=dict(friction_law="torque"),
              effects={"J2": {"J": 21.5}, "delay": {"T_d": 0.025}}, expected=("second_motor", "speed_sensor_lag"),
              layout="plain", note="the paper's second motor (21.5 kg m^2, rigid) and a 25 ms speed-sensor delay, soft "
                                   "gains (k_p 0.3, k_I 2, k_D 0)"),
    PlantSpec("f27_quad_ovality", 75.0, 25.0, base=_NUIS, setup_kiln=dict(friction_law="torque"),
              effects={"quad_drag": {"c_q": 1.03e8}, "ovality": {"T1": 2.0e5, "phi1": -1.0, "T2": 1.0e5, "phi2": 0.5}},
              expected=("viscous_drag", "kiln_unbalance"), layout="uneven",
              note="f23's quadratic drag (as B_o = 5e6 at the set speed) and an ovality 2e5 sin(th_k - 1.0) + "
                   "1e5 sin(2 th_k + 0.5) N m"),
    PlantSpec("f28_quad_drag_large", 45.0, 50.0, base=_NUIS, setup_kiln=dict(friction_law="torque"),
              effects={"quad_drag": {"c_q": 3.1e8}}, expected=("viscous_drag",), layout="kiln",
              note="f23's quadratic drag three times larger: 7.3e5 N m at the set speed (as B_o = 1.5e7, about "
                   "150 A); only the kiln speed logged"),
    PlantSpec("f24b_unbalance_only", 90.0, 20.0, base=_NUIS, setup_kiln=dict(friction_law="torque"),
              effects={"ovality": {"T1": 2.0e5, "phi1": 0.6}}, expected=("kiln_unbalance",), layout="iso",
              note="f24's control: its first harmonic alone (2e5 sin(th_k + 0.6) N m, kilnctl's own form), the same "
                   "logger"),
    PlantSpec("f25b_j2_rigid", 30.0, 200.0, base=_NUIS, setup_kiln=dict(friction_law="torque"),
              effects={"J2": {"J": 25.0}}, expected=("second_motor",), layout="iso_uneven",
              note="f25's control: its 25 kg m^2 second motor rigidly on the shaft (the J2 form), the same logger"),
    # fifth red team: further forms, nuisance and sensor faults (see the module's docstring); 40 s at 50 Hz each
    PlantSpec("g1_free_nuisance", 40.0, 50.0, base=_G1_BASE, setup_kiln=dict(friction_law="torque"),
              noise=(5.0, 0.3), ar1=(8.0, 0.3, 2.0), expected=(), layout="plain", visibility=_G_VIS.get("g1", {}),
              note="no effect; besides f1's mismatches (m_v +4 %, mu_c -3 %, mu_s +3 %, J_v -5 %) the plant has J_o "
                   "+5 %, J_m -4 %, k_i and k_b +3 %, L -3 %, R_a +8 %, mu_brg 0.0012 against the setup's Table 1, "
                   "and coloured noise of 2 s correlation time (8 A, 0.3 rpm) on top of 5 A / 0.3 rpm white; a "
                   "correct diagnosis selects nothing"),
    PlantSpec("g2_motor_viscous", 40.0, 50.0, base=_NUIS, setup_kiln=dict(friction_law="torque"),
              effects={"motor_viscous": {"b": 6.0}}, expected=("viscous_drag",), layout="plain",
              visibility=_G_VIS.get("g2", {}),
              note="viscous drag 6 N m s/rad on the motor shaft (314 N m, 68 A at 500 rpm); referred through the gear: "
                   "B_o = 6 n^2 = 6.95e6 N m s/rad on the kiln axis"),
    PlantSpec("g3_runout_paperlaw", 40.0, 50.0, base=_NUIS, effects={"runout": {"T": 4.0e5, "phi": -0.9}},
              expected=("torque_friction_law", "kiln_unbalance"), layout="plain", visibility=_G_VIS.get("g3", {}),
              note="girth-gear runout: load 4e5 max(0, sin(th_k - 0.9)) N m, zero until the kiln has turned 0.9 rad "
                   "(about t = 22 s) and then rising (to 3.1e5 N m, 62 A, by 40 s at 1.78 rad); a kink, not a "
                   "sine; the setup not knowing the torque law; kilnctl's form: T_unb of about 2e5 (first harmonic)"),
    PlantSpec("g4_ilag", 40.0, 50.0, base=_NUIS, setup_kiln=dict(friction_law="torque"),
              effects={"ilag": {"tau": 0.04}}, expected=(), layout="plain", visibility=_G_VIS.get("g4", {}),
              note="current sensor of first order, 40 ms, on the logged current only (the loop does not see it); not "
                   "in the catalogue: the right outcome is 'unexplained' or nothing selected, never a catalogue effect "
                   "(speed_sensor_lag in particular would be wrong: the speed is measured without lag)"),
    PlantSpec("g5_sgain_paperlaw", 40.0, 50.0, base=_NUIS, effects={"sgain": {"g": 1.03}},
              expected=("torque_friction_law",), layout="plain", visibility=_G_VIS.get("g5", {}),
              note="speed sensor reading 3 % high (fed back and logged: 1.03 w_m), so the kiln turns at 485 rpm "
                   "motor speed while the record says 500 and accelerates 3 % slower than logged; not in the "
                   "catalogue; the setup not knowing the torque law, so only torque_friction_law is right"),
    PlantSpec("g6_j2_large_drag", 40.0, 50.0, base=_NUIS, setup_kiln=dict(friction_law="torque"),
              effects={"J2": {"J": 60.0}, "motor_viscous": {"b": 4.0}}, expected=("second_motor", "viscous_drag"),
              layout="plain", visibility=_G_VIS.get("g6", {}),
              note="second motor of 60 kg m^2 (above the usual 10-45), rigid, and a viscous drag of 4 N m s/rad on the "
                   "motor shaft (209 N m, 45 A at 500 rpm; B_o = 4.6e6 on the kiln axis); kilnctl's form: J_m2 = 60"),
    PlantSpec("g7_shaft_unbalance", 40.0, 50.0, base=_NUIS, setup_kiln=dict(friction_law="torque"),
              effects={"shaft": {"k": 400.0, "c": 12.0}, "ovality": {"T1": 3.0e5, "phi1": -0.8}},
              expected=("drivetrain_compliance", "kiln_unbalance"), layout="plain", visibility=_G_VIS.get("g7", {}),
              note="compliant shaft on the motor axis, 400 N m/rad and 12 N m s/rad (k_po = 4.6e8, C_po = 1.4e7 on "
                   "the kiln axis; about 0.7 Hz against the held kiln) and a kiln unbalance 3e5 sin(th_k - 0.8) N m "
                   "(-43 A at rest, through zero at t = 20 s, +50 A at 40 s; kilnctl's form: T_unb = 3e5); the plant "
                   "has no backlash form, so this pair replaces the brief's backlash + unbalance"),
    PlantSpec("g8_coulomb_lag", 40.0, 50.0, gains=(0.7, 2.5, 0.003), base=_NUIS, setup_kiln=dict(friction_law="torque"),
              effects={"coulomb": {"T": 100.0}, "lag": {"tau": 0.015}},
              expected=("motor_coulomb_friction", "speed_sensor_lag"), layout="plain", visibility=_G_VIS.get("g8", {}),
              note="motor-side Coulomb friction 100 N m (22 A; f6 had 60) and a 15 ms first-order speed sensor (fed "
                   "back and logged), on a drive tuned softer for the lag (k_p 0.7, k_I 2.5, k_D 0.003: the paper's "
                   "gains diverge with it)"),
]


def main(argv=None) -> int:
    """Command line: list or write the foreign records."""
    ap = argparse.ArgumentParser(prog="python -m benchmarks.foreign_records",
                                 description="Write start-up records of an independently written kiln plant, "
                                             "in plant-historian layouts, with setup TOML and truth JSON.")
    ap.add_argument("--list", action="store_true", help="list the records and their truth")
    ap.add_argument("--write", metavar="DIR", help="write the records into DIR")
    ap.add_argument("--only", metavar="A,B", help="only these records")
    a = ap.parse_args(argv)
    specs = [s for s in RECORDS if not a.only or s.name in a.only.split(",")]
    if a.list or not a.write:
        for s in specs:
            print(f"{s.name:18s} {s.t_end:5.0f} s {s.fs:5.0f} Hz  expected={list(s.expected)}  {s.note}")
        return 0
    for s in specs:
        tr = write_record(s, a.write)
        print(f"{s.name}: {tr['csv']} ({tr['n_samples']} samples, {tr['events']} burden mode changes, "
              f"peak {tr['i_max']:.0f} A); --columns '{tr['columns']}'")
    return 0


if __name__ == "__main__":
    sys.exit(main())
