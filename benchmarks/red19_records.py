"""Red team 19's start-up records: twelve records of kiln K-19 from an independent plant.

The plant is :mod:`benchmarks.red19_plant` (written apart from kilnctl by red team 19's helper; it imports
no kilnctl).  The record definitions, nuisance draws, logger, noise, file writing and truth texts are the
helper's (``/work/runs/red19/make_records.py``, ``common.py`` and ``truth.json``, the truth written before
any diagnosis was run), gathered here: regenerating a record gives the helper's CSV and TOML byte for byte.

Every record: kiln K-19 (:func:`benchmarks.red19_plant.default_params`: mu_c R / L = 0.35 x 1.6 / 1.05 =
0.533 < mu_s 0.57, so under the paper's friction law the burden sticks and breaks away again and again at
the set speed), 50 Hz, 1 s at rest before the ramp (the ramp starts at the record's start time + 1 s), 40 s
after it, ``speed_ref_rpm`` logged; the setup (TOML) is the base kiln's nominal values with the record's
setup changes (E2 only) and the gains stated (``gains = "given"``), the paper's friction law; the plant
differs from the setup by the record's effects and by nuisance factors of 2-6 % on m_v, mu_c, mu_s and
J_v (:func:`nuisance`, not in the TOML).

What a correct diagnosis says is in each record's ``expected`` (the helper's words); the catalogue effects
the plant holds in ``effects`` (X1's burden slump is outside the catalogue).

``python -m benchmarks.red19_records --list`` lists them,
``python -m benchmarks.red19_records --write DIR [--only N2,E1]`` writes ``NAME.csv``, ``NAME.toml`` (the
setup) and ``NAME.truth.json`` into DIR; then ``kilnctl diagnose --data DIR/NAME.csv --config DIR/NAME.toml``.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from benchmarks.red19_plant import default_params, simulate

__all__ = ["Red19Record", "RECORDS", "COMMON", "NOTES", "T_END", "R_O", "nuisance", "plant_params", "ar1",
           "log_clean", "add_noise", "noise_text", "write_toml", "write_csv", "simulate_record", "write_record",
           "main"]

#: length of every simulation [s] (the logger keeps 0 .. T_END - 0.05 s: 2058 samples at 50 Hz)
T_END = 41.2
#: girth-gear pitch radius used to convert E4's backlash play [m]
R_O = 3.1

#: what every record holds (the helper's truth.md head, paths updated)
COMMON = ("Plant: benchmarks/red19_plant.py (red team 19's own, written from the paper's eqs. 1-21 + NOTES.md; "
          "fixed-step RK4, dt 0.25 ms, bisection-located stick/slip switches). Base kiln K-19 (nominal setup, every "
          "TOML except E2): R_a 0.021, L_a 1.4 mH, k_i = k_b 3.0, J_m 12, B_m 0.008; PID 0.6 / 6.0 / 0.02 (given); "
          "set 680 rpm, ramp 60 rpm/s, V_max 300 V, I_max 700 A; J_o 2.6e6, J_v 2.9e5, m_v 1.9e5 kg, L 1.05 m, "
          "R 1.6 m, mu_c 0.35, mu_s 0.57, mu_brg 0.0011, P 5.4e6 N, l_brg 0.48, k_brg 0.38; n 850. mu_c R/L = 0.533 "
          "< mu_s, so the printed (paper) law has no Filippov 'held' mode: breakaway at tan psi = mu_s (about 29.7 "
          "deg), small stick-slip cycles of about 2.4 s; running current about 340-380 A. Nuisance draws keep mu_c "
          "R/L < 0.98 mu_s. Every record: 50 Hz, 1 s at rest before the ramp (ramp start = start time + 1 s), 40 s "
          "after it. The plant uses the paper friction law unless stated. Base check (kilnctl compare, noise-free, "
          "effect-free, true values in the TOML): paper law current rms 0.0099 A (bias -0.0002 A) against ~360 A "
          "running, speed 0.00045 rpm; torque law 0.019 A, 0.00087 rpm; a torque-law record against the paper-law "
          "setup 67.8 A, 0.82 rpm (the law matters). No difference from kilnctl's paper model in the base.")

#: the helper's notes on single records (truth.md, "Notes")
NOTES = {
    "N1": "N1/N2 'effect size' is the logger artefact against ideal sampling of the same clean plant, not a physical "
          "effect; it is expected to be small or speed-only.",
    "N2": "N1/N2 'effect size' is the logger artefact against ideal sampling of the same clean plant, not a physical "
          "effect; it is expected to be small or speed-only.",
    "P1": "P1 exceeds 30 x: the torque-consistent law by itself changes the stick-slip pattern completely in this "
          "kiln (breakaway 41 deg instead of 30 deg); the motor friction on top of it is 10.9 x.",
    "E5": "E5: a 25 ms second-order sensor destabilised the loop (k_D acts through the lagged speed), so 18 ms / "
          "zeta 0.6 was used (equivalent lag 21.6 ms).",
    "E2": "E2: the nameplate I_max in its TOML (380 A) is above every current in the record (peak 344 A), so "
          "kilnctl's own nameplate limit is never reached; the converter limit at 342 A is.",
    "X1": "X1 is outside the catalogue: any catalogue selection is a false positive; the honest answer is "
          "'unexplained' (a ~11 % step drop of the running current at ~27-28 s after the start of the file).",
}

#: how ``effect_size`` was measured (the helper's make_records.py; not recomputed by :func:`write_record`)
EFFECT_SIZE_DEF = ("measured by red team 19 (make_records.py) on the noise-free logger output: the worst 1 s window "
                   "rms of the difference and where it starts [s of the record], against the rms of the record's "
                   "noise; for N1/N2 the difference is the logger's artefact against ideal sampling of the same "
                   "plant, for the others the plant with its effects against the same plant (same nuisance, paper "
                   "law) without any; P1/P2's 'parts' split the two effects (the first alone, the second on top)")


@dataclass
class Red19Record:
    """One record of red team 19: plant effects, setup changes, logger, noise and truth."""

    name: str
    effects: tuple                  # catalogue effects the plant holds (truth.json "effects")
    fx: dict                        # the plant's effects (benchmarks.red19_plant.Plant's fx keys)
    t0: float                       # the record's start time [s]; the ramp starts 1 s later
    noise: dict                     # noise seed and sizes (make_records.py NOISE; see add_noise)
    form: str                       # the effects' form in the plant (truth.json "form")
    expected: str                   # what a correct diagnosis says (truth.json "expected_diagnosis")
    effect_size: dict               # measured by the helper (EFFECT_SIZE_DEF; truth.json "effect_size")
    setup: dict = field(default_factory=dict)  # setup changes against K-19 (in the TOML and the plant)
    logger: str = "plain"           # 'plain', 'average' (box-car over each period) or 'jitter_encoder'
    law: str = "paper"              # the plant's friction law (the setup always states 'paper')


def _noise(seed, i_w, i_ar, phi, w_w, w_ar, wphi, t_df, qi, qw):
    return dict(seed=seed, i_w=i_w, i_ar=i_ar, phi=phi, w_w=w_w, w_ar=w_ar, wphi=wphi, t_df=t_df, qi=qi, qw=qw)


def _size(what, ci, cs, cn, cr, si, ss, sn, sr, parts=None):
    d = dict(what=what, current_worst_1s_rms_A=ci, current_window_start_s=cs, current_noise_rms_A=cn,
             current_ratio=cr, speed_worst_1s_rms_rpm=si, speed_window_start_s=ss, speed_noise_rms_rpm=sn,
             speed_ratio=sr)
    if parts:
        d["parts"] = parts
    return d


_LOGGER = "logger artefact (vs ideal sampling of the same clean signal)"
_EFFECT = "noise-free effect (plant with vs without the effect, same nuisance)"
_N = 850.0  # the gear ratio of K-19 (default_params()["n"])

_RECORDS = [
    Red19Record(
        "N1", (), {}, 37.52, _noise(101, 1.6, 2.0, 0.93, 0.08, 0.08, 0.9, None, 0.0, 0.001), logger="average",
        form="no physical effect; logger integrates (box-car averages) each 20 ms period and "
             "stamps the sample at the end of the period",
        expected="nothing from the catalogue (base model with calibrated nuisance); the averaging "
                 "is a measurement property (10 ms apparent delay, smoothing)",
        effect_size=_size(_LOGGER, 1.7, 56.82, 2.46, 0.69, 0.6, 48.86, 0.117, 5.13)),
    Red19Record(
        "N2", (), {}, 0.0, _noise(102, 2.5, 1.5, 0.85, 0.0, 0.0, 0.9, None, 0.49, None), logger="jitter_encoder",
        form="no physical effect; sampling instants jitter (sigma 1.5 ms, written as nominal "
             "times) and speed comes from an 8192-ppr encoder counted over each 20 ms period",
        expected="nothing from the catalogue; encoder quantisation (0.37 rpm steps) and jitter "
                 "are measurement properties",
        effect_size=_size(_LOGGER, 0.44, 17.0, 2.89, 0.15, 0.629, 7.02, 0.348, 1.81)),
    Red19Record(
        "E1", ("second_motor",), dict(J_m2=30.0, c_fan=0.002), 5.0,
        _noise(103, 2.0, 1.0, 0.9, 0.10, 0.06, 0.95, 3, 0.0, 0.01),
        form="second motor rigid on the same shaft (J_m2 = 30 kg m^2) with its cooling-fan "
             "windage torque c_fan*w|w| (c_fan = 0.002 N m s^2, ~10 N m at set speed)",
        expected="second_motor (J_m2 ~ 30 kg m^2)",
        effect_size=_size(_EFFECT, 65.86, 16.36, 2.25, 29.23, 0.529, 17.36, 0.118, 4.49)),
    Red19Record(
        "E2", ("current_limit",), dict(ilim=0.90 * 380.0, G_l=2.0, tau_l=0.04), 0.0,
        _noise(104, 1.2, 1.0, 0.95, 0.12, 0.05, 0.9, None, 0.25, 0.001), setup=dict(I_max=380.0, ramp_rate=90.0),
        form="converter current limit at 0.90 x nameplate (342 A of 380 A) realised as a "
             "first-order voltage take-off: tau_l du/dt = -u + G_l (i - I_lim)+, e_a = e_pi - u, "
             "G_l = 2 V/A, tau_l = 40 ms, speed integrator frozen while u > 0.5 V (soft limit, "
             "current overshoots the limit a little)",
        expected="current_limit (I_max ~ 0.90 x 380 A = 342 A)",
        effect_size=_size(_EFFECT, 7.84, 12.62, 1.66, 4.71, 1.474, 12.48, 0.129, 11.46)),
    Red19Record(
        "E3", ("drivetrain_compliance",), dict(k_c=1.5e8 / _N ** 2, eta_c=0.15, J_g=2.0), 12.0,
        _noise(105, 2.8, 1.2, 0.8, 0.15, 0.05, 0.8, 4, 0.0, 0.001),
        form="elastomeric coupling between gearbox and pinion: linear stiffness k_po = 1.5e8 "
             "N m/rad referred to the kiln (k_c = k_po/n^2 = 207.6 N m/rad at the motor) with "
             "hysteretic (rate-independent) damping T_d = eta |T_spring| tanh(dphi/0.02), eta = 0.15; "
             "gearbox inertia J_g = 2 kg m^2 (motor side) on the load side of the coupling",
        expected="drivetrain_compliance (k_po ~ 1.5e8 N m/rad; C_po whatever fits the hysteretic damping)",
        effect_size=_size(_EFFECT, 17.37, 24.34, 3.09, 5.62, 0.595, 24.36, 0.163, 3.66)),
    Red19Record(
        "E4", ("backlash",), dict(gap=0.010 / R_O * _N, gap0=0.7, k_h=5.4e5, c_h=0.5, J_g=1.5), 0.0,
        _noise(106, 1.5, 2.2, 0.96, 0.09, 0.10, 0.97, None, 0.49, 0.001),
        form="girth/pinion play 10 mm (at R_o = 3.1 m: 2.74 rad at the motor), 70 % of it open "
             "at start; Hunt-Crossley tooth contact T = k_h d^1.5 (1 + c_h d'), k_h = 5.4e5 "
             "N m/rad^1.5 (motor side), c_h = 0.5 s/rad; gearbox/pinion inertia J_g = 1.5 kg m^2 "
             "on the motor side of the mesh",
        expected="backlash (delta_x ~ 7 mm open at start, 10 mm total play)",
        effect_size=_size(_EFFECT, 50.64, 1.16, 2.61, 19.37, 2.541, 1.6, 0.134, 19.02)),
    Red19Record(
        "E5", ("speed_sensor_lag",), dict(tau_s2=0.018, zeta_s=0.6), 0.0,
        _noise(107, 1.2, 0.6, 0.9, 0.05, 0.04, 0.9, None, 0.0, 0.01),
        form="second-order speed sensor (tacho filter), w_n = 1/18 ms, zeta = 0.6: equivalent "
             "first-order lag 2 zeta/w_n = 21.6 ms (about 4-10 x the usual range; 25 ms made the loop unstable); "
             "the drive feeds back and the logger records the filtered speed",
        expected="speed_sensor_lag (tau_s ~ 20 ms, far above the usual 2-6 ms)",
        effect_size=_size(_EFFECT, 10.91, 12.36, 1.35, 8.07, 0.494, 12.36, 0.064, 7.73)),
    Red19Record(
        "E6", ("kiln_unbalance",), dict(T_unb=2.2e5, phi_unb=1.1, e_R=0.01), 0.0,
        _noise(108, 3.0, 2.0, 0.97, 0.12, 0.10, 0.95, 5, 0.0, 0.001),
        form="bent (eccentric) shell: unbalance torque -T_unb sin(theta_o + phi), T_unb = 2.2e5 "
             "N m, phi = 1.1 rad, and the burden friction arm modulated R(1 + 0.01 cos(theta_o + phi))",
        expected="kiln_unbalance (T_unb ~ 2.2e5 N m plus a little from the arm modulation, phi ~ 1.1 rad)",
        effect_size=_size(_EFFECT, 86.23, 11.84, 3.57, 24.13, 0.714, 0.02, 0.158, 4.53)),
    Red19Record(
        "E7", ("viscous_drag",), dict(B0=2.2e6, B1=0.9e6, tau_B=15.0), 3.3,
        _noise(109, 2.2, 1.5, 0.9, 0.10, 0.08, 0.9, None, 0.49, 0.001),
        form="viscous drag on the kiln that falls as the tyre/roller oil film warms: "
             "B(t) = B1 + (B0 - B1) exp(-(t - t_ramp)/tau), B0 = 2.2e6, B1 = 0.9e6 N m s/rad, "
             "tau = 15 s (drag torque ~1.1e5 N m at the end, ~0.45 x the usual B_o range)",
        expected="viscous_drag (an average B_o ~ 1e6-1.5e6 N m s/rad; a time-varying residual may remain)",
        effect_size=_size(_EFFECT, 49.06, 15.4, 2.65, 18.52, 0.021, 4.68, 0.125, 0.17)),
    Red19Record(
        "P1", ("torque_friction_law", "motor_coulomb_friction"), dict(T_cm=35.0, T_cb=110.0, th_cb=3.0), 0.0,
        _noise(110, 1.8, 1.8, 0.94, 0.13, 0.05, 0.85, 3, 0.0, 0.001), law="torque",
        form="torque-consistent burden law (breakaway when the holding torque exceeds mu_s N R) + "
             "motor Coulomb friction whose breakaway part decays with shaft angle "
             "(grease displaced): T = T_cm + (T_cb - T_cm) exp(-theta_m/3 rad) sign(w), "
             "T_cm = 35 N m, T_cb = 110 N m",
        expected="torque_friction_law + motor_coulomb_friction (T_cm ~ 35 N m)",
        effect_size=_size(_EFFECT, 131.09, 40.0, 2.89, 45.36, 1.939, 21.46, 0.145, 13.35,
                          parts={"torque_friction_law_alone_current_ratio": 47.86,
                                 "motor_coulomb_friction_on_top_current_ratio": 10.86})),
    Red19Record(
        "P2", ("second_motor", "kiln_unbalance"), dict(J_m2=14.0, T_unb=1.2e5, phi_unb=4.0, e_R=0.0), 101.0,
        _noise(111, 2.6, 1.0, 0.9, 0.09, 0.09, 0.95, None, 0.25, 0.01),
        form="plain rigid second motor J_m2 = 14 kg m^2 + plain unbalance -T_unb sin(theta_o + phi), "
             "T_unb = 1.2e5 N m, phi = 4.0 rad",
        expected="second_motor (J_m2 ~ 14) + kiln_unbalance (T_unb ~ 1.2e5 N m, phi ~ 4.0 rad)",
        effect_size=_size(_EFFECT, 47.97, 115.8, 2.76, 17.37, 0.322, 101.02, 0.124, 2.61,
                          parts={"second_motor_alone_current_ratio": 10.69,
                                 "kiln_unbalance_on_top_current_ratio": 17.03})),
    Red19Record(
        "X1", (), dict(slump_t=27.0, slump_frac=0.11, slump_dur=1.2), 0.0,
        _noise(112, 2.0, 2.0, 0.95, 0.11, 0.07, 0.9, 4, 0.0, 0.001),
        form="outside the catalogue: burden slump, 11 % of the burden (m_v and J_v together) "
             "leaves the bed over 1.2 s (smoothstep) starting at t = 26 s after the ramp start "
             "(part of the bed discharges over the outlet dam)",
        expected="no catalogue effect (unexplained: a step drop of ~11 % in the running current "
                 "at ~26-27 s after ramp start); any catalogue selection is a false positive",
        effect_size=_size(_EFFECT, 42.89, 28.1, 2.93, 14.65, 0.141, 27.2, 0.129, 1.1)),
]

#: the twelve records by name, in the helper's order (N1 N2 E1..E7 P1 P2 X1)
RECORDS = {r.name: r for r in _RECORDS}


def _record(name) -> Red19Record:
    if isinstance(name, Red19Record):
        return name
    try:
        return RECORDS[name]
    except KeyError:
        raise KeyError(f"no red team 19 record {name!r}; there are {', '.join(RECORDS)}") from None


# ---------------- plant values ----------------
def nuisance(name: str) -> dict:
    """The record's nuisance: relative deviations of the plant's m_v, mu_c, mu_s and J_v from the setup.

    The helper's draw, seeded by the record's name: each deviation is +-2..6 %, drawn again until mu_c R / L <
    0.98 mu_s (the printed law then has no Filippov 'held' chatter).

    Parameters
    ----------
    name : str
        The record's name (e.g. ``'N2'``).

    Returns
    -------
    dict
        ``m_v``, ``mu_c``, ``mu_s``, ``J_v``: the deviation [-] (the plant's value is the setup's times
        ``1 + deviation``).
    """
    rng = np.random.default_rng(sum(map(ord, name)) * 31 + 5)
    p = default_params()
    while True:
        dev = {k: float(rng.choice([-1, 1]) * rng.uniform(0.02, 0.06)) for k in ["m_v", "mu_c", "mu_s", "J_v"]}
        mc = p["mu_c"] * (1 + dev["mu_c"])
        ms = p["mu_s"] * (1 + dev["mu_s"])
        if mc * p["R"] / p["L"] < 0.98 * ms:     # keep the printed law free of Filippov 'held' chatter
            return dev


def plant_params(name) -> tuple:
    """The record's plant parameters: K-19 with the record's setup changes, nuisance and friction law.

    Parameters
    ----------
    name : str or Red19Record
        The record.

    Returns
    -------
    p : dict
        Parameters of :class:`benchmarks.red19_plant.Plant`.
    dev : dict
        The nuisance deviations (:func:`nuisance`).
    """
    rec = _record(name)
    p = default_params()
    p.update(rec.setup)
    dev = nuisance(rec.name)
    for k, v in dev.items():
        p[k] = p[k] * (1 + v)
    p["friction_law"] = rec.law
    return p, dev


def simulate_record(name) -> dict:
    """The record's plant (effects, nuisance, law) simulated for :data:`T_END` s (about 4 s of CPU).

    Parameters
    ----------
    name : str or Red19Record
        The record.

    Returns
    -------
    dict
        As :meth:`benchmarks.red19_plant.Plant.run`.
    """
    rec = _record(name)
    p, _ = plant_params(rec)
    return simulate(p, rec.fx, T_END)


# ---------------- logger and noise ----------------
def ar1(rng, n, phi, sig):
    """An AR(1) sequence of ``n`` samples, coefficient ``phi`` and stationary standard deviation ``sig``."""
    e = rng.standard_normal(n) * sig * math.sqrt(1 - phi ** 2)
    x = np.zeros(n)
    x[0] = rng.standard_normal() * sig
    for k in range(1, n):
        x[k] = phi * x[k - 1] + e[k]
    return x


def log_clean(res, mode, fs=50.0, rng=None):
    """Noise-free logger output at the nominal sample times (t from 0).

    Parameters
    ----------
    res : dict
        A plant run (:meth:`benchmarks.red19_plant.Plant.run`).
    mode : {'plain', 'average', 'jitter_encoder'}
        'plain': the signals at the sample times; 'average': box-car average over each period, stamped at its
        end; 'jitter_encoder': the current at jittered instants (sigma 1.5 ms, clipped to 5 ms; written as the
        nominal times) and the speed from an 8192-ppr encoder counted over each period.
    fs : float, default 50.0
        Logger rate [Hz].
    rng : numpy.random.Generator, optional
        The jitter's draws ('jitter_encoder'; none without it).

    Returns
    -------
    ts, current, speed, reference : numpy.ndarray
        Times [s], current [A], speed [rpm], speed reference [rpm].
    """
    t, i, w, r = res["t"], res["i"], res["w"], res["r"]
    ts = np.arange(0.0, T_END - 0.05 + 1e-9, 1.0 / fs)
    if mode == "average":
        T = 1.0 / fs
        ci = np.concatenate([[0], np.cumsum(0.5 * (i[1:] + i[:-1]) * np.diff(t))])
        cw = np.concatenate([[0], np.cumsum(0.5 * (w[1:] + w[:-1]) * np.diff(t))])
        ta = np.maximum(ts - T, 0.0)
        den = np.maximum(ts - ta, 1e-12)
        I = (np.interp(ts, t, ci) - np.interp(ta, t, ci)) / den
        W = (np.interp(ts, t, cw) - np.interp(ta, t, cw)) / den
        I[0], W[0] = i[0], w[0]
        return ts, I, W, np.interp(ts, t, r)
    if mode == "jitter_encoder":
        jit = np.clip(rng.normal(0, 0.0015, ts.size), -0.005, 0.005) if rng is not None else np.zeros(ts.size)
        tj = np.clip(ts + jit, 0, t[-1])
        I = np.interp(tj, t, i)
        theta = np.concatenate([[0], np.cumsum(0.5 * (w[1:] + w[:-1]) * np.diff(t))]) / 60.0  # revolutions
        ppr = 8192
        counts = np.floor(np.interp(ts, t, theta) * ppr)   # counter gated by its own clock
        W = np.zeros(ts.size)
        W[1:] = np.diff(counts) / ppr / (1.0 / fs) * 60.0   # logger divides by the nominal period
        return ts, I, W, np.interp(tj, t, r)
    return ts, np.interp(ts, t, i), np.interp(ts, t, w), np.interp(ts, t, r)


def add_noise(name, I, W):
    """The record's noise added to the noise-free current ``I`` [A] and speed ``W`` [rpm].

    White plus AR(1) noise on each channel, for some records 1 % Student-t outliers, then quantisation (the
    record's :attr:`Red19Record.noise`, seeded by its ``seed``).

    Returns
    -------
    current, speed : numpy.ndarray
    """
    c = _record(name).noise
    rng = np.random.default_rng(c["seed"])
    n = I.size
    ni = rng.standard_normal(n) * c["i_w"] + ar1(rng, n, c["phi"], c["i_ar"])
    nw = rng.standard_normal(n) * c["w_w"] + ar1(rng, n, c["wphi"], c["w_ar"])
    if c["t_df"]:
        m = rng.random(n) < 0.01       # occasional Student-t outliers
        ni[m] += rng.standard_t(c["t_df"], m.sum()) * 3 * c["i_w"]
        nw[m] += rng.standard_t(c["t_df"], m.sum()) * 2 * max(c["w_w"], 0.05)
    In = I + ni
    Wn = W + nw
    if c["qi"]:
        In = np.round(In / c["qi"]) * c["qi"]
    if c["qw"]:
        Wn = np.round(Wn / c["qw"]) * c["qw"]
    return In, Wn


def noise_text(name) -> str:
    """The record's noise in words (truth.json "noise")."""
    c = _record(name).noise
    return ("white %.1f A + AR(1) %.1f A (phi %.2f) on current%s%s; white %.2f + AR(1) %.2f rpm on speed%s"
            % (c["i_w"], c["i_ar"], c["phi"],
               ", 1 %% Student-t(%d) outliers" % c["t_df"] if c["t_df"] else "",
               ", quantised %.2f A" % c["qi"] if c["qi"] else "",
               c["w_w"], c["w_ar"],
               ", quantised %.3f rpm" % c["qw"] if c["qw"] else " (speed = encoder counts only, 0.366 rpm steps)"))


# ---------------- files ----------------
#: the TOML's sections and keys, in the helper's order
KEYS = dict(motor=["R_a", "L_a", "k_i", "k_b", "J_m", "B_m"], controller=["k_p", "k_I", "k_D"],
            drive=["omega_ref", "ramp_rate", "V_max", "I_max"],
            kiln=["J_o", "J_v", "m_v", "L", "R", "mu_c", "mu_s", "mu_brg", "P", "l_brg", "k_brg"], gear=["n"])


def write_toml(path, p, extra_kiln=None):
    """Write the setup ``p`` as kilnctl's TOML (gains given; the friction law only with ``extra_kiln``)."""
    L = []
    for sec, keys in KEYS.items():
        L.append("[%s]" % sec)
        if sec == "controller":
            L.append('gains = "given"')
        for k in keys:
            L.append("%s = %r" % (k, float(p[k])))
        if sec == "kiln" and p.get("friction_law", "paper") != "paper" and extra_kiln:
            L.append('friction_law = "%s"' % p["friction_law"])
        L.append("")
    with open(path, "w") as fh:
        fh.write("\n".join(L))


def write_csv(path, title, t, i, w, r, fmt_i="%.2f", fmt_w="%.3f"):
    """Write a record: a comment line ``# title``, the header, then time, current, speed and reference."""
    with open(path, "w") as fh:
        fh.write("# %s\n" % title)
        fh.write("time_s,current_A,speed_rpm,speed_ref_rpm\n")
        for a, b, c, d in zip(t, i, w, r):
            fh.write(("%.4f," + fmt_i + "," + fmt_w + ",%.1f\n") % (a, b, c, d))


def write_record(name, folder, sim=None) -> dict:
    """Write ``NAME.csv``, ``NAME.toml`` (the setup) and ``NAME.truth.json`` into ``folder``.

    The CSV and TOML are the helper's byte for byte.

    Parameters
    ----------
    name : str or Red19Record
        The record (e.g. ``'N2'``).
    folder : str or Path
        Output folder (created).
    sim : dict, optional
        The record's plant run (:func:`simulate_record`), when already at hand.

    Returns
    -------
    dict
        The truth as in the JSON: ``effects`` (catalogue), ``expected_diagnosis``, ``form``,
        ``plant_effect_params``, ``nuisance`` (as the helper wrote it), ``base`` (the plant's true m_v [kg],
        mu_c, mu_s, J_v [kg m^2]), ``noise``, ``effect_size`` (the helper's), ``record`` (start, samples, logger,
        burden mode switches, peak and running current of the noise-free logger output); with the paths
        written (``csv``, ``toml``, ``truth``) and the noise-free current ``i_clean`` [A] and speed ``w_clean``
        [rpm] at the record's times ``t`` [s] (not in the JSON).
    """
    rec = _record(name)
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    p, dev = plant_params(rec)
    rw = simulate_record(rec) if sim is None else sim
    rng = np.random.default_rng(rec.noise["seed"] + 1000)
    ts, I, W, Rf = log_clean(rw, rec.logger, rng=rng)
    In, Wn = add_noise(rec, I, W)
    tt = ts + rec.t0
    csv = folder / f"{rec.name}.csv"
    write_csv(csv, "kiln K-19, start-up record %s, logger 50 Hz" % rec.name, tt, In, Wn, Rf, "%.2f", "%.3f")
    setup = default_params()
    setup.update(rec.setup)
    toml = folder / f"{rec.name}.toml"
    write_toml(toml, setup)
    base = {k: float(p[k]) for k in ["m_v", "mu_c", "mu_s", "J_v"]}
    truth = dict(
        name=rec.name, common=COMMON, effects=list(rec.effects), expected_diagnosis=rec.expected, form=rec.form,
        plant_effect_params=json.dumps(rec.fx) + ("; friction_law=torque" if rec.law == "torque" else ""),
        nuisance={k: "%+.1f %%" % (100 * v) for k, v in dev.items()} | {
            k + "_true": round(p[k], 5) for k in ["m_v", "mu_c", "mu_s", "J_v"]},
        base=base, noise=noise_text(rec),
        effect_size=dict(definition=EFFECT_SIZE_DEF, **rec.effect_size),
        record=dict(start_time_s=rec.t0, ramp_start_s=rec.t0 + 1.0, fs_Hz=50, n_samples=int(ts.size),
                    logger=rec.logger, setup_changes=rec.setup, burden_events=len(rw["events"]),
                    max_current_A=round(float(I.max()), 1), running_current_A=round(float(I[ts > 30].mean()), 1)))
    if rec.name in NOTES:
        truth["note"] = NOTES[rec.name]
    path = folder / f"{rec.name}.truth.json"
    path.write_text(json.dumps(truth, indent=1) + "\n")
    return dict(truth, csv=str(csv), toml=str(toml), truth=str(path), t=tt, i_clean=I, w_clean=W)


def main(argv=None) -> int:
    """Command line: list or write red team 19's records."""
    ap = argparse.ArgumentParser(prog="python -m benchmarks.red19_records",
                                 description="Write red team 19's start-up records of kiln K-19 (an independent "
                                             "plant), each with its setup TOML and truth JSON.")
    ap.add_argument("--list", action="store_true", help="list the records and their truth")
    ap.add_argument("--write", metavar="DIR", help="write the records into DIR")
    ap.add_argument("--only", metavar="A,B", help="only these records (e.g. N2,E1)")
    a = ap.parse_args(argv)
    recs = [_record(n) for n in a.only.split(",")] if a.only else list(RECORDS.values())
    if a.list or not a.write:
        for r in recs:
            print(f"{r.name:3s} start {r.t0:6.2f} s  logger {r.logger:14s} effects={list(r.effects)}  "
                  f"expected: {r.expected}")
        return 0
    for r in recs:
        tr = write_record(r, a.write)
        print(f"{r.name}: {tr['csv']} ({tr['record']['n_samples']} samples, {tr['record']['burden_events']} burden "
              f"mode switches); kilnctl diagnose --data {tr['csv']} --config {tr['toml']}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
