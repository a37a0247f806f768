"""Red team 20's start-up records: twelve records of kiln K-20 from an independent plant.

The plant is :mod:`benchmarks.red20_plant` (written apart from kilnctl by red team 20's helper; it imports
no kilnctl).  The record definitions, nuisance draws, logger, measuring chain, noise, outliers, file writing
and truth texts are the helper's (``/work/runs/red20/make_records.py`` and ``common.py``; the truth,
``truth.json`` and ``truth.md``, written with the records), gathered here.  Regenerating a record
gives the helper's CSV and TOML byte for byte: all twelve were checked (sha256 of every ``NAME.csv`` and
``NAME.toml`` against ``/work/runs/red20``) when the generator was moved here, and the truth JSONs equal the
entries of the helper's ``truth.json``, their effect sizes measured again from the plant with and without
the effects (``write_record(..., base=...)``) included (and :func:`truth_md` gives its ``truth.md`` but for
the line naming the files).

Every record: kiln K-20 (:data:`benchmarks.red20_plant.BASE`: mu_c R / L = 0.38 x 1.9 / 1.15 = 0.628 > mu_s
0.45, so under the paper's friction law the burden is held with the shell and then slides smoothly: one
burden mode switch, no stick-slip cycles), 1 s at rest before the ramp (the ramp starts at the record's first
time stamp + 1 s), 41 s in all, 50 Hz (E3 100 Hz), ``speed_ref_rpm`` logged; the setup (TOML) is the base
kiln's nominal values with the record's setup changes (ramp rate, set speed) and the gains stated (``gains =
"given"``), the paper's friction law; the plant differs from the setup by the record's effects and by
nuisance factors of 2-6 % on m_v, mu_c, mu_s and J_v (:func:`nuisance`, not in the TOML).  The plant's speed
loop runs from the start, so a kiln unbalance is held at rest by a current (E6: about +30 A before the ramp).

What a correct diagnosis says is in each record's ``expected`` (the helper's words); the catalogue effects the
plant holds in ``effects`` (X1's pinion pulsation is outside the catalogue).

``python -m benchmarks.red20_records --list`` lists them,
``python -m benchmarks.red20_records --write DIR [--only N2,E1]`` writes ``NAME.csv``, ``NAME.toml`` (the
setup) and ``NAME.truth.json`` into DIR (and ``truth.md`` for the records written); then ``kilnctl diagnose
--data DIR/NAME.csv --config DIR/NAME.toml``.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from benchmarks.red20_plant import BASE, KFB, simulate

__all__ = ["Red20Record", "RECORDS", "COMMON", "T_END", "R_O", "KEYS", "nuisance", "plant_params",
           "simulate_record", "ar1", "quant", "sample", "log_record", "worst_window", "effect_size", "write_toml",
           "write_csv", "write_record", "truth_md", "main"]

#: length of every simulation [s] (the logger keeps 0 .. T_END s: 2051 samples at 50 Hz, 4101 at 100 Hz)
T_END = 41.0
#: girth-gear pitch radius [m], only to express E4's backlash in mm
R_O = 3.5

#: what every record holds (the helper's truth.md head, without the line naming the files)
COMMON = ("Base kiln K-20 (every TOML states these nominal values, with the per-record ramp/set-speed changes "
          "listed): R_a 0.015, L_a 0.0009 H, k_i = k_b 5.0, J_m 16.0, B_m 0.01; PID k_p 0.5, k_I 4.0, k_D 0.012 "
          "(given); set 750.0 rpm, ramp 60.0 rpm/s, V_max 520.0 V, I_max 900.0 A; J_o 3400000.0, J_v 400000.0, m_v "
          "260000.0 kg, L 1.15 m, R 1.9 m, mu_c 0.38, mu_s 0.45, mu_brg 0.0012, P 8200000.0 N, l_brg 0.6, k_brg "
          "0.45; n 820.0. mu_c R/L = 0.628 > mu_s = 0.45: under the printed (paper) law the burden sticks to tan "
          "psi = mu_s, is held (Filippov) to the kinetic angle and then slides smoothly (one mode switch, no steady "
          "stick-slip); running current ~382 A (oscillating +-8 A at the 0.4 Hz burden pendulum). Every record: 1 s "
          "at rest before the ramp, 41 s in all (40 s after the ramp start); nuisance of 2-6 % on m_v, mu_c, mu_s, "
          "J_v not told by the TOML. Paper friction law in the plant unless stated. Base check (kilnctl compare, "
          "noise-free, effect-free, true values in the TOML): paper law current rms 0.0032 A against ~382 A "
          "running, speed 3.3e-5 rpm; torque law 0.030 A, 1.2e-3 rpm; a torque-law record against the paper-law "
          "setup 20.3 A, 0.32 rpm (the law matters).")

_NONE = "none"
_CHAIN = "measuring chain (chain output vs ideal sampling of the same signal + same noise)"
_EFFECT = "noise-free effect (plant with vs without the effect, same nuisance)"


@dataclass
class Red20Record:
    """One record of red team 20: plant effects, setup changes, logger, noise and truth."""

    name: str
    seed: int                       # the record's seed: nuisance draws; + 500 for the noise and outliers
    setup: dict                     # setup changes against K-20 (in the TOML and the plant; truth "setup_changes")
    fx: dict                        # the plant's effects (benchmarks.red20_plant.Plant's fx keys)
    effects: tuple                  # catalogue effects the plant holds (truth "catalogue_effects")
    expected: str                   # what a correct diagnosis says (truth "correct_diagnosis")
    form: str                       # the effects' form in the plant (truth "form")
    fs: int                         # logger rate [Hz]
    t0: float                       # the record's first time stamp [s]; the ramp starts 1 s later
    noise: dict                     # noise sizes (truth "noise"; see log_record)
    chain: str | None = None        # 'N2': encoder speed, current gain and offset, a held stretch
    measured: tuple | None = None   # the helper's effect (records with effects; see effect_size)


def _noise(iw, ia, iphi, iq, ww, wa, wphi, wq, out):
    return dict(iw=iw, ia=ia, iphi=iphi, iq=iq, ww=ww, wa=wa, wphi=wphi, wq=wq, out=out)


_RECORDS = [
    Red20Record(
        "N1", 2000, {}, {}, (),
        expected="nothing from the catalogue; residual at noise level after calibrating the nuisance",
        form="no physical effect; plain logger", fs=50, t0=0.0,
        noise=_noise(1.8, 1.5, 0.9, 0.1, 0.08, 0.06, 0.9, 0.01, 0)),
    Red20Record(
        "N2", 2001, dict(ramp_rate=70.0, omega_ref=720.0), {}, (),
        expected="nothing from the catalogue; measuring-chain artefacts only (encoder steps, 1.2 % current gain, "
                 "0.6 A offset, a held stretch of the logger, large time stamps)",
        form="no physical effect; speed from a 2048-ppr encoder counted over each 20 ms sample; current sensor gain "
             "+1.2 %, offset +0.6 A; logger held both channels for 0.56 s at ~24.3 s after the ramp start; time "
             "stamps start at 734512.36 s",
        fs=50, t0=734512.36, chain="N2", noise=_noise(2.0, 1.2, 0.85, 0.25, 0.0, 0.0, 0.9, 0.0, 0)),
    Red20Record(
        "E1", 2002, dict(ramp_rate=70.0), dict(J2=20.0, B2=0.04), ("second_motor",),
        expected="second_motor (J_m2 about 20 kg m^2, 1.25 x J_m)",
        form="second motor, electrically isolated, rigid on the pinion shaft: rotor J_m2 = 20 kg m^2 plus "
             "eddy-current drag of its excited but unloaded rotor 0.04 N m s/rad (3.1 N m at set speed)",
        fs=50, t0=12.34, noise=_noise(2.2, 1.0, 0.9, 0.1, 0.1, 0.05, 0.9, 0.01, 3),
        measured=(29.89700675680063, 561, 0.1546833531961132, 612)),
    Red20Record(
        "E2", 2003, dict(ramp_rate=150.0, omega_ref=800.0),
        dict(il0=600.0, il_n1=400.0, il_n2=800.0, il_f=0.63, kl=400.0, kpl=0.05), ("current_limit",),
        expected="current_limit (effective limit about 378-385 A near set speed, far below the stated I_max 900 A; "
                 "the drive cannot hold 800 rpm, runs about 15-20 rpm low)",
        form="converter commutation (power) limit: current limit 600 A up to 400 rpm, falling linearly to 0.63 x "
             "600 = 378 A at 800 rpm; realised by a limiter that takes voltage off the armature (integral 400 "
             "V/(A s) + proportional 0.05 V/A on the excess), speed integrator frozen while limiting",
        fs=50, t0=0.0, noise=_noise(1.5, 1.2, 0.93, 0.25, 0.1, 0.08, 0.9, 0.001, 0),
        measured=(7.468599328830891, 524, 23.62008600812113, 1084)),
    Red20Record(
        "E3", 2004, {}, dict(kc1=600.0, ph1=0.3, kc2=8000.0, cc=2.0, Jg=0.5), ("drivetrain_compliance",),
        expected="drivetrain_compliance (motor-side coupling: soft 600 N m/rad near zero twist = k_po ~4.0e8 N m/rad "
                 "kiln side, 8000 N m/rad = 5.4e9 kiln side beyond 0.3 rad; lightly damped; small, mostly at the "
                 "ramp start)",
        form="bilinear elastomer coupling between motor and gearbox: 600 N m/rad up to 0.3 rad twist (180 N m), "
             "8000 N m/rad beyond (elastomer blocks compressed), damping 2 N m s/rad, gearbox inertia 0.5 kg m^2 on "
             "the load side; logged at 100 Hz",
        fs=100, t0=3.0, noise=_noise(1.4, 0.7, 0.8, 0.1, 0.06, 0.03, 0.8, 0.001, 4),
        measured=(5.01503505076847, 469, 0.15711882111956893, 484)),
    Red20Record(
        "E4", 2005, {}, dict(gap=0.025 / R_O * 820.0, gap0=0.8, kt=6.0e4, ct=106.0, Jg=1.0), ("backlash",),
        expected="backlash (very large: 25 mm play at the girth gear, 20 mm of it open at start -- well outside the "
                 "usual 0-16 mm; the play is 7.14e-3 rad at the kiln = 5.86 rad at the motor, i.e. 28.3 mm if "
                 "expressed at kilnctl's default R_o = 3.96 m)",
        form="girth gear/pinion play 25 mm at R_o = 3.5 m (5.86 rad at the motor), 80 % open at start; linear tooth "
             "contact 6e4 N m/rad (motor side) with 106 N m s/rad damping (no pull); pinion/gearbox 1 kg m^2 on the "
             "motor side of the mesh",
        fs=50, t0=100.0, noise=_noise(2.0, 1.5, 0.9, 0.5, 0.1, 0.08, 0.9, 0.01, 0),
        measured=(93.24487072038745, 140, 3.610146203016236, 142)),
    Red20Record(
        "E5", 2006, {}, dict(Tw=0.05), ("speed_sensor_lag",),
        expected="speed_sensor_lag (about 25 ms equivalent delay / lag; small)",
        form="speed measured as encoder angle difference over a sliding 50 ms window, (theta(t)-theta(t-0.05))/0.05, "
             "used by the speed loop and logged (a pure-delay-like moving-average lag, ~25 ms)",
        fs=50, t0=7.5, noise=_noise(1.2, 0.8, 0.9, 0.05, 0.04, 0.03, 0.9, 0.001, 0),
        measured=(5.295126661877603, 701, 0.29180350197678695, 700)),
    Red20Record(
        "E6", 2007, dict(omega_ref=780.0), dict(U1=1.2e5, ph1u=2.0, U2=4.0e4, ph2u=0.7), ("kiln_unbalance",),
        expected="kiln_unbalance (first harmonic 1.2e5 N m, plus a smaller second harmonic the catalogue may not "
                 "have)",
        form="coating rings: gravity torque -U1 sin(theta_k + 2.0) - U2 sin(2 theta_k + 0.7), U1 = 1.2e5 N m, U2 = "
             "4e4 N m (two lumps); kiln turns ~0.45 rev in the record",
        fs=50, t0=0.0, noise=_noise(2.0, 2.0, 0.95, 0.1, 0.1, 0.1, 0.95, 0.01, 0),
        measured=(34.91631183219411, 1544, 0.23416507435625, 26)),
    Red20Record(
        "E7", 2008, dict(ramp_rate=55.0), dict(cd=1.2e5, ad=0.5), ("viscous_drag",),
        expected="viscous_drag (small; drag ~3.7e4 N m at set speed, equivalent linear B ~3.9e5 N m s/rad at set "
                 "speed)",
        form="kiln inlet/outlet seal drag growing as the square root of speed: T = 1.2e5 |w_o|^0.5 N m (w_o kiln "
             "rad/s): 3.7e4 N m at 750 rpm, steep at low speed",
        fs=50, t0=20.0, noise=_noise(1.5, 1.0, 0.9, 0.1, 0.06, 0.05, 0.9, 0.001, 0),
        measured=(9.05907741552024, 1713, 0.007773929396167557, 77)),
    Red20Record(
        "E8", 2009, {}, dict(law="aging", mus_inf=0.50, tau_age=1.5), ("torque_friction_law",),
        expected="torque_friction_law (torque-consistent breakaway; stick-slip cycles; mu_s as calibrated will be "
                 "somewhere between mu_c and 0.50)",
        form="torque-consistent burden breakaway (holding torque > mu_s_eff N R) with time-dependent static friction "
             "(contact ageing): mu_s_eff = mu_c + (0.50 - mu_c)(1 - exp(-t_stuck/1.5 s)); kinetic mu_c as usual",
        fs=50, t0=0.0, noise=_noise(2.5, 1.5, 0.9, 0.1, 0.12, 0.06, 0.9, 0.01, 2),
        measured=(78.17905644389403, 815, 0.9566840927840811, 782)),
    Red20Record(
        "P1", 2010, dict(ramp_rate=65.0, omega_ref=700.0), dict(tau_f=0.012, Tc=35.0, Ts=80.0, ws=2.0),
        ("motor_coulomb_friction", "speed_sensor_lag"),
        expected="motor_coulomb_friction (~35 N m, breakaway 80 N m) + speed_sensor_lag (~12 ms first-order)",
        form="tachogenerator with RC filter tau = 12 ms (loop and logger) + motor brush/bearing friction with "
             "Stribeck breakaway: T = [35 + 45 exp(-(w_m/2 rad/s)^2)] sgn(w_m) N m",
        fs=50, t0=0.0, noise=_noise(1.8, 1.2, 0.9, 0.1, 0.08, 0.05, 0.9, 0.01, 0),
        measured=(11.185210416090932, 77, 0.20824624016396212, 76)),
    Red20Record(
        "X1", 2011, dict(ramp_rate=60.0, omega_ref=760.0), dict(Ap=8.0e4, nr=120.0, php=0.3), (),
        expected="nothing from the catalogue; residual unexplained (a 0.105 Hz torque pulsation locked to the "
                 "pinion/gearbox-output rotation, 8e4 N m at the kiln ~ 19.5 A)",
        form="eccentric pinion / bent gearbox output shaft: torque -8e4 sin(theta_m/120 + 0.3) N m at the kiln axis, "
             "period = 120 motor revolutions (9.5 s at 760 rpm)",
        fs=50, t0=55.0, noise=_noise(2.0, 1.5, 0.9, 0.1, 0.1, 0.06, 0.9, 0.01, 3),
        measured=(19.40212607762266, 404, 0.04712458407030552, 1071)),
]

#: the twelve records by name, in the helper's order (N1 N2 E1..E8 P1 X1; seeds 2000..2011 in this order)
RECORDS = {r.name: r for r in _RECORDS}


def _record(name) -> Red20Record:
    if isinstance(name, Red20Record):
        return name
    try:
        return RECORDS[name]
    except KeyError:
        raise KeyError(f"no red team 20 record {name!r}; there are {', '.join(RECORDS)}") from None


# ---------------- plant values ----------------
def nuisance(name) -> dict:
    """The record's nuisance: relative deviations of the plant's m_v, mu_c, mu_s and J_v from the setup.

    The helper's draw, seeded by the record's :attr:`Red20Record.seed`: each deviation is +-2..6 %.

    Parameters
    ----------
    name : str or Red20Record
        The record (e.g. ``'N2'``).

    Returns
    -------
    dict
        ``m_v``, ``mu_c``, ``mu_s``, ``J_v``: the deviation [-] (the plant's value is the setup's times
        ``1 + deviation``).
    """
    rng = np.random.default_rng(_record(name).seed)
    out = {}
    for k in ("m_v", "mu_c", "mu_s", "J_v"):
        out[k] = float(rng.choice([-1, 1]) * rng.uniform(0.02, 0.06))
    return out


def plant_params(name) -> tuple:
    """The record's plant parameters: K-20 with the record's setup changes and nuisance.

    Parameters
    ----------
    name : str or Red20Record
        The record.

    Returns
    -------
    p : dict
        Parameters of :class:`benchmarks.red20_plant.Plant` (the friction law is an effect, ``fx["law"]``).
    dev : dict
        The nuisance deviations (:func:`nuisance`).
    """
    rec = _record(name)
    dev = nuisance(rec)
    p = dict(BASE)
    p.update(rec.setup)
    for k, v in dev.items():
        p[k] = p[k] * (1 + v)
    return p, dev


def simulate_record(name, effects=True) -> dict:
    """The record's plant (nuisance, and its effects unless ``effects`` is false) over :data:`T_END` s.

    About 5 s of CPU (E5, whose speed window interpolates the motor angle's history, a little more).

    Parameters
    ----------
    name : str or Red20Record
        The record.
    effects : bool, default True
        False: the same plant without the record's effects (the effect size's reference).

    Returns
    -------
    dict
        As :meth:`benchmarks.red20_plant.Plant.run`.
    """
    rec = _record(name)
    p, _ = plant_params(rec)
    return simulate(p, rec.fx if effects else {}, t_end=T_END)


# ---------------- logger and noise ----------------
def ar1(rng, n, sig, phi):
    """An AR(1) sequence of ``n`` samples, stationary standard deviation ``sig`` and coefficient ``phi``."""
    e = rng.normal(0, sig * math.sqrt(1 - phi * phi), n)
    x = np.zeros(n)
    x[0] = rng.normal(0, sig)
    for k in range(1, n):
        x[k] = phi * x[k - 1] + e[k]
    return x


def quant(x, q):
    """``x`` rounded to steps of ``q`` (unchanged for ``q`` 0)."""
    return np.round(x / q) * q if q > 0 else x


def sample(res, ts):
    """A plant run's current [A], speed [rpm] and reference [rpm] at the times ``ts`` (linear interpolation)."""
    return np.interp(ts, res["t"], res["i"]), np.interp(ts, res["t"], res["w"]), np.interp(ts, res["t"], res["r"])


def log_record(name, res) -> dict:
    """The record's logger output: the plant run sampled, noise added, the measuring chain, quantised, outliers.

    At the record's rate from 0 to :data:`T_END` s: white plus AR(1) noise on each channel (the speed's AR(1)
    only when its size is above zero), for N2 the chain (speed from a 2048-ppr encoder counted over each
    sample period, the current 1.2 % high and 0.6 A off, both channels held for 28 samples from 25.3 s), each
    channel quantised, then the record's number of outliers of 25-60 A added to the current.  One generator
    seeded by the record's seed + 500 draws the noise, then the outliers.

    Parameters
    ----------
    name : str or Red20Record
        The record.
    res : dict
        The record's plant run (:func:`simulate_record`).

    Returns
    -------
    dict
        ``ts`` [s from 0], ``t`` (the logged time stamps, ``ts`` + the record's start), ``i``, ``w``, ``ref``
        (noise-free samples), ``current``, ``speed`` (logged), ``ni``, ``nw`` (the noise drawn), ``outliers``
        (``(ts, A)`` pairs, as the helper's truth) and for N2 ``held`` (the held samples' slice).
    """
    rec = _record(name)
    rng = np.random.default_rng(rec.seed + 500)
    fs = rec.fs
    ts = np.arange(0, T_END + 1e-9, 1.0 / fs)
    n = len(ts)
    i, w, ref = sample(res, ts)
    nz = rec.noise
    ni = rng.normal(0, nz["iw"], n) + ar1(rng, n, nz["ia"], nz["iphi"])
    nw = rng.normal(0, nz["ww"], n) + (ar1(rng, n, nz["wa"], nz["wphi"]) if nz["wa"] > 0 else 0)
    im = i + ni
    wm = w + nw
    held = None
    if rec.chain == "N2":
        # encoder: angle from the motor speed, counted each sample period
        th = np.concatenate([[0], np.cumsum(0.5 * (res["wm"][1:] + res["wm"][:-1]) * np.diff(res["t"]))]) / KFB
        cnt = np.floor(np.interp(ts, res["t"], th) * 2048 / (2 * math.pi))
        wm = np.concatenate([[0], np.diff(cnt)]) / 2048 * fs * 60.0
        im = 1.012 * im + 0.6
        k0 = int(round((1.0 + 24.3) * fs))
        k1 = k0 + 28
        im[k0:k1] = im[k0 - 1]
        wm[k0:k1] = wm[k0 - 1]
        held = slice(k0, k1)
    im = quant(im, nz["iq"])
    wm = quant(wm, nz["wq"])
    outl = []
    for _ in range(nz["out"]):
        k = int(rng.integers(int(2 * fs), n - 5))
        amp = float(rng.choice([-1, 1]) * rng.uniform(25, 60))
        im[k] += amp
        outl.append((round(float(ts[k]), 3), round(amp, 1)))
    return dict(ts=ts, t=ts + rec.t0, i=i, w=w, ref=ref, current=im, speed=wm, ni=ni, nw=nw, outliers=outl,
                held=held)


def worst_window(d, fs):
    """The worst 1 s window of a difference ``d`` sampled at ``fs``: its rms and its centre sample."""
    n = int(round(fs))
    c = np.convolve(d * d, np.ones(n) / n, mode="valid")
    k = int(np.argmax(c))
    return float(math.sqrt(c[k])), k + n // 2


def effect_size(name, log, base=None) -> dict:
    """The record's effect size against its noise, as the helper measured it (truth "effect_size").

    The worst 1 s window rms of the difference and where it lies (its centre, as a logged time), against the
    rms of the noise drawn: for the records with effects the noise-free plant with its effects against the same
    plant (same nuisance) without them; for N2 the measuring chain's output against ideal sampling of the same
    signal and noise (the speed's noise: the rms of that difference after 2 s); N1 none.

    Parameters
    ----------
    name : str or Red20Record
        The record.
    log : dict
        Its logger output (:func:`log_record`).
    base : dict, optional
        The plant run without the effects (``simulate_record(name, effects=False)``): the difference is then
        measured; without it the helper's measurement (:attr:`Red20Record.measured`) is taken.

    Returns
    -------
    dict
        ``kind``, ``current_worst_1s_rms`` [A], ``current_at_t`` [s], ``current_noise_rms``,
        ``current_ratio``, and the same for the speed [rpm].
    """
    rec = _record(name)
    fs, ts, tl = rec.fs, log["ts"], log["t"]
    i, w, ni, nw = log["i"], log["w"], log["ni"], log["nw"]
    noise_i = float(np.std(ni))
    noise_w = float(np.std(nw)) if np.ndim(nw) else 0.0
    if rec.fx:
        kind = _EFFECT
        if base is not None:
            i0, w0, _ = sample(base, ts)
            (ci, ki), (cw, kw) = worst_window(i - i0, fs), worst_window(w - w0, fs)
        else:
            ci, ki, cw, kw = rec.measured
    elif rec.chain == "N2":
        h = log["held"]
        di = (1.012 * (i + ni) + 0.6)
        di[h] = di[h.start - 1]
        di = di - (i + ni)
        dw = log["speed"] - w
        noise_w = float(np.std(dw[ts > 2.0]))
        kind = _CHAIN
        (ci, ki), (cw, kw) = worst_window(di, fs), worst_window(dw, fs)
    else:
        kind = _NONE
        (ci, ki), (cw, kw) = worst_window(np.zeros(ts.size), fs), worst_window(np.zeros(ts.size), fs)
    return dict(kind=kind, current_worst_1s_rms=ci, current_at_t=float(tl[ki]), current_noise_rms=noise_i,
                current_ratio=ci / noise_i if noise_i > 0 else None,
                speed_worst_1s_rms=cw, speed_at_t=float(tl[kw]), speed_noise_rms=noise_w,
                speed_ratio=cw / noise_w if noise_w > 0 else None)


# ---------------- files ----------------
#: the TOML's sections and keys, in the helper's order
KEYS = dict(motor=["R_a", "L_a", "k_i", "k_b", "J_m", "B_m"], controller=["k_p", "k_I", "k_D"],
            drive=["omega_ref", "ramp_rate", "V_max", "I_max"],
            kiln=["J_o", "J_v", "m_v", "L", "R", "mu_c", "mu_s", "mu_brg", "P", "l_brg", "k_brg"], gear=["n"])


def write_toml(path, p, title="kiln K-20 start-up", extra=None):
    """Write the setup ``p`` as kilnctl's TOML: a comment line ``# title``, the gains given, ``extra`` keys
    (``{section: {key: value}}``) at the end of their sections."""
    L = ["# %s" % title]
    for sec, keys in KEYS.items():
        L.append("[%s]" % sec)
        if sec == "controller":
            L.append('gains = "given"')
        for k in keys:
            L.append("%s = %r" % (k, float(p[k])))
        if extra and sec in extra:
            for k, v in extra[sec].items():
                L.append("%s = %r" % (k, v))
        L.append("")
    with open(path, "w") as fh:
        fh.write("\n".join(L))


def write_csv(path, title, t, i, w, r, fmt_t="%.4f", fmt_i="%.2f", fmt_w="%.3f", fmt_r="%.2f"):
    """Write a record: a comment line ``# title``, the header, then time, current, speed and reference."""
    with open(path, "w") as fh:
        fh.write("# %s\n" % title)
        fh.write("time_s,current_A,speed_rpm,speed_ref_rpm\n")
        fmt = ",".join([fmt_t, fmt_i, fmt_w, fmt_r]) + "\n"
        for row in zip(t, i, w, r):
            fh.write(fmt % row)


def write_record(name, folder, sim=None, base=None) -> dict:
    """Write ``NAME.csv``, ``NAME.toml`` (the setup) and ``NAME.truth.json`` into ``folder``.

    The CSV and TOML are the helper's byte for byte, the JSON its ``truth.json`` entry.

    Parameters
    ----------
    name : str or Red20Record
        The record (e.g. ``'E6'``).
    folder : str or Path
        Output folder (created).
    sim : dict, optional
        The record's plant run (:func:`simulate_record`), when already at hand.
    base : dict, optional
        The plant run without the record's effects: the effect size is then measured again
        (:func:`effect_size`), else the helper's measurement is taken.

    Returns
    -------
    dict
        The truth as in the JSON: ``catalogue_effects``, ``correct_diagnosis``, ``form``,
        ``plant_effect_params``, ``setup_changes``, ``nuisance_rel``, ``nuisance_true`` (the plant's m_v [kg],
        mu_c, mu_s, J_v [kg m^2]), ``noise``, ``outliers_t_rel_A``, ``record`` (rate, first time stamp, ramp
        start, samples, burden mode switches, peak and running current of the plant), ``effect_size``; with the
        paths written (``csv``, ``toml``, ``truth``), the logged times ``t`` [s], the noise-free current
        ``i_clean`` [A] and speed ``w_clean`` [rpm] (not in the JSON).
    """
    rec = _record(name)
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    p, nu = plant_params(rec)
    r = simulate_record(rec) if sim is None else sim
    lg = log_record(rec, r)
    tl = lg["t"]
    csv = folder / f"{rec.name}.csv"
    write_csv(csv, "kiln K-20, start-up record %s, logger %d Hz" % (rec.name, rec.fs), tl, lg["current"],
              lg["speed"], lg["ref"], "%.4f" if rec.t0 < 1e5 else "%.3f", "%.2f", "%.3f", "%.2f")
    ptoml = dict(BASE)
    ptoml.update(rec.setup)
    toml = folder / f"{rec.name}.toml"
    write_toml(toml, ptoml, title="kiln K-20 start-up %s" % rec.name)
    run = r["t"] > 30.0
    truth = dict(
        catalogue_effects=list(rec.effects), correct_diagnosis=rec.expected, form=rec.form,
        plant_effect_params=rec.fx, setup_changes=rec.setup,
        nuisance_rel={k: round(v, 4) for k, v in nu.items()},
        nuisance_true={k: float(p[k]) for k in nu},
        noise=rec.noise, outliers_t_rel_A=lg["outliers"],
        record=dict(fs_hz=rec.fs, t_first=float(tl[0]), ramp_start=float(tl[0] + 1.0), samples=int(tl.size),
                    burden_switches=len(r["events"]), peak_current=float(r["i"].max()),
                    running_current=float(r["i"][run].mean())),
        effect_size=effect_size(rec, lg, base))
    path = folder / f"{rec.name}.truth.json"
    path.write_text(json.dumps(truth, indent=1) + "\n")
    return dict(truth, csv=str(csv), toml=str(toml), truth=str(path), t=tl, i_clean=lg["i"], w_clean=lg["w"])


def truth_md(truths) -> str:
    """The helper's ``truth.md`` for the records in ``truths`` (name -> :func:`write_record`'s truth).

    Byte for byte the helper's but for its third line, which named the helper's files.
    """
    b = BASE
    L = ["# Red team 20 - truth for the 12 K-20 start-up records", "",
         "Plant: `benchmarks/red20_plant.py` (own, from the paper eqs. 1-21 + NOTES.md; fixed-step RK4 0.25 ms, "
         "bisection-located burden mode switches). `python -m benchmarks.red20_records --write DIR` regenerates "
         "all CSV/TOML, the truth JSONs and this file. Base check: benchmarks/red20_plant.py's docstring.", "",
         "Base kiln K-20 (every TOML states these nominal values, with the per-record ramp/set-speed changes listed): "
         "R_a %(R_a)s, L_a %(L_a)s H, k_i = k_b %(k_i)s, J_m %(J_m)s, B_m %(B_m)s; PID k_p %(k_p)s, k_I %(k_I)s, "
         "k_D %(k_D)s (given); set %(omega_ref)s rpm, ramp %(ramp_rate)s rpm/s, V_max %(V_max)s V, I_max %(I_max)s A; "
         "J_o %(J_o)s, J_v %(J_v)s, m_v %(m_v)s kg, L %(L)s m, R %(R)s m, mu_c %(mu_c)s, mu_s %(mu_s)s, "
         "mu_brg %(mu_brg)s, P %(P)s N, l_brg %(l_brg)s, k_brg %(k_brg)s; n %(n)s. " % b
         + "mu_c R/L = %.3f > mu_s = 0.45: under the printed (paper) law the burden sticks to tan psi = mu_s, is held "
           "(Filippov) to the kinetic angle and then slides smoothly (one mode switch, no steady stick-slip); "
           "running current ~382 A (oscillating +-8 A at the 0.4 Hz burden pendulum)." % (b["mu_c"] * b["R"] / b["L"]),
         "Every record: 1 s at rest before the ramp, 41 s in all (40 s after the ramp start); nuisance of 2-6 % on "
         "m_v, mu_c, mu_s, J_v not told by the TOML. Paper friction law in the plant unless stated.", "",
         "## Summary", "",
         "| record | catalogue truth | correct diagnosis | size: current worst-1s rms / noise rms | speed |",
         "|---|---|---|---|---|"]
    for k, t in truths.items():
        e = t["effect_size"]
        ri = "%.1f / %.2f A = **%.1f x**" % (e["current_worst_1s_rms"], e["current_noise_rms"], e["current_ratio"] or 0)
        rw = "%.3f / %.3f rpm = %.1f x" % (e["speed_worst_1s_rms"], e["speed_noise_rms"], e["speed_ratio"] or 0)
        L.append("| %s | %s | %s | %s | %s |" % (k, ", ".join(t["catalogue_effects"]) or "none", t["correct_diagnosis"],
                                                 ri, rw))
    L.append("")
    for k, t in truths.items():
        e = t["effect_size"]
        rc = t["record"]
        nz = t["noise"]
        L += ["## %s" % k, "",
              "- **truth (catalogue effects):** %s" % (", ".join(t["catalogue_effects"]) or "none"),
              "- **a correct diagnosis says:** %s" % t["correct_diagnosis"],
              "- **form:** %s" % t["form"],
              "- **plant effect parameters:** `%s`" % json.dumps(t["plant_effect_params"]),
              "- **setup changes (stated in the TOML):** %s" % (t["setup_changes"] or "none"),
              "- **nuisance (not in the TOML):** %s; true values %s" % (
                  ", ".join("%s %+.1f %%" % (a, 100 * v) for a, v in t["nuisance_rel"].items()),
                  ", ".join("%s %.5g" % (a, v) for a, v in t["nuisance_true"].items())),
              "- **record:** first sample %.3f s, ramp starts %.3f s, %d samples at %d Hz, %d burden mode switches, "
              "peak current %.0f A, running current (t>30 s) %.0f A" % (
                  rc["t_first"], rc["ramp_start"], rc["samples"], rc["fs_hz"], rc["burden_switches"],
                  rc["peak_current"], rc["running_current"]),
              "- **noise:** current white %.2f A + AR(1) %.2f A (phi %.2f), quantised %.2f A, %d outliers %s; speed "
              "white %.3f + AR(1) %.3f rpm (phi %.2f), quantised %.3f rpm" % (
                  nz["iw"], nz["ia"], nz["iphi"], nz["iq"], nz["out"], t["outliers_t_rel_A"],
                  nz["ww"], nz["wa"], nz["wphi"], nz["wq"]),
              "- **effect size** (%s): current worst 1 s window rms %.2f A at %.2f s vs noise rms %.2f A -> "
              "**%.1f x**; speed %.3f rpm at %.2f s vs %.3f rpm -> %.1f x" % (
                  e["kind"], e["current_worst_1s_rms"], e["current_at_t"], e["current_noise_rms"],
                  e["current_ratio"] or 0, e["speed_worst_1s_rms"], e["speed_at_t"], e["speed_noise_rms"],
                  e["speed_ratio"] or 0), ""]
    return "\n".join(L)


def main(argv=None) -> int:
    """Command line: list or write red team 20's records."""
    ap = argparse.ArgumentParser(prog="python -m benchmarks.red20_records",
                                 description="Write red team 20's start-up records of kiln K-20 (an independent "
                                             "plant), each with its setup TOML and truth JSON.")
    ap.add_argument("--list", action="store_true", help="list the records and their truth")
    ap.add_argument("--write", metavar="DIR", help="write the records into DIR (and truth.md for them)")
    ap.add_argument("--only", metavar="A,B", help="only these records (e.g. N2,E1)")
    a = ap.parse_args(argv)
    recs = [_record(n) for n in a.only.split(",")] if a.only else list(RECORDS.values())
    if a.list or not a.write:
        for r in recs:
            print(f"{r.name:3s} start {r.t0:9.2f} s  {r.fs:3d} Hz  effects={list(r.effects)}  expected: {r.expected}")
        return 0
    truths = {}
    for r in recs:
        tr = write_record(r, a.write)
        truths[r.name] = tr
        print(f"{r.name}: {tr['csv']} ({tr['record']['samples']} samples, {tr['record']['burden_switches']} burden "
              f"mode switches); kilnctl diagnose --data {tr['csv']} --config {tr['toml']}")
    (Path(a.write) / "truth.md").write_text(truth_md(truths))
    return 0


if __name__ == "__main__":
    sys.exit(main())
