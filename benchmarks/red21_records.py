"""Red team 21's start-up records: thirteen records of kiln K-21 from an independent plant.

The plant is :mod:`benchmarks.red21_plant` (written apart from kilnctl by red team 21's helper; it imports
no kilnctl, only numpy and scipy).  The record definitions, nuisance draws, sample times, effect sizes,
logger, noise, outliers, file writing and truth texts are the helper's (``/work/runs/red21/make_records.py``
and ``tomlio.py``; the truth, ``truth.json`` and ``truth.md``, written with the records before any diagnosis
was run), gathered here.  Regenerating a record gives the helper's CSV and TOML byte for byte: all thirteen
were checked (sha256 of every ``NAME.csv`` and ``NAME.toml`` against ``/work/runs/red21``) when the
generator was moved here; ``--write DIR`` of all thirteen also gives the helper's ``truth.json`` byte for
byte (the effect sizes measured again from the plant with and without the effects, as the helper did), and
its ``truth.md`` but for the line naming the helper's files (:func:`truth_md`).  The helper's texts are kept
as written, "twelve" records in truth.md's title included.

Every record: kiln K-21 (:data:`benchmarks.red21_plant.K21`: mu_c R / L = 0.36 x 2.55 / 1.62 = 0.567 > mu_s
0.46, so under the paper's friction law the burden breaks away at tan psi = mu_s, is held by kinetic friction
and then slides steadily: no stick-slip at the set speed), 1 s at rest before the ramp (the ramp starts at
1 s, the records' time stamps start at 0), 40 s after the ramp start (N1 60 s), 50 Hz (N1 100 Hz, N2 25 Hz
with jittered time stamps), ``speed_ref_rpm`` logged; the setup (TOML) is K-21's nominal values (E4 with its
200 rpm/s ramp) with the gains stated (``gains = "given"``) and the paper's friction law; the plant differs
from the setup by the record's effects (P1 also by its burden law) and by nuisance factors of 2-6 % on m_v,
mu_c, mu_s and J_v (:func:`nuisance`, not in the TOML).  Outliers (N2, E6, P2) are written in by hand at
the times the helper chose, one sample each.

What a correct diagnosis says is in each record's truth (``correct_diagnosis``, from its class: N nothing,
E and P its catalogue effects, X unexplained); the catalogue effects the plant holds in ``effects`` (X1's
field economy and X2's mains sag are outside the catalogue).

``python -m benchmarks.red21_records --list`` lists them,
``python -m benchmarks.red21_records --write DIR [--only N2,E1]`` writes ``NAME.csv``, ``NAME.toml`` (the
setup) and ``NAME.truth.json`` (the helper's ``truth.json`` entry) into DIR, and ``truth.json`` and
``truth.md`` for the records written; then ``kilnctl diagnose --data DIR/NAME.csv --config DIR/NAME.toml``.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from benchmarks.red21_plant import K21, Plant

__all__ = ["Red21Record", "RECORDS", "T0", "MU_CR_L", "SPEED_NOISE", "CORRECT", "SECTIONS", "EXTRA",
           "nuisance", "true_params", "sample_times", "simulate", "simulate_record", "ar1", "worst_window",
           "effect_size", "log_record", "fmt", "write_toml", "write_csv", "truth_entry", "regime_text",
           "truth_json", "truth_md", "write_record", "main"]

#: the ramp's start [s]: every record is 1 s at rest before it
T0 = 1.0
#: K-21's mu_c R / L (0.567), above its mu_s 0.46
MU_CR_L = K21["mu_c"] * K21["R"] / K21["L"]

# the usual ranges (Table 1) scaled to K-21, as docs/tutorial_diagnose.md says (the helper's)
_SCALE_JM = K21["J_m"] / 21.5
_SCALE_MVL = K21["m_v"] * K21["L"] / (580e3 * 1.353)
_W_O = K21["omega_ref"] / K21["n"] * 2 * math.pi / 60
_SCALE_DRAG = (K21["m_v"] * K21["L"] / _W_O) / (580e3 * 1.353 / (500 / 1076.5 * 2 * math.pi / 60))
_SCALE_TCM = K21["k_i"] * K21["I_max"] / (4.6 * 1500.0)
_SCALE_J = (K21["J_o"] + K21["J_v"]) / (6.978e6 + 1.678e6)

#: the speed channel's noise of every record but N2: white [rpm], AR(1) [rpm] and its time constant [s], step
#: [rpm]
SPEED_NOISE = dict(w=0.30, c=0.25, tau=0.3, q=0.05)

#: what a correct diagnosis says, by the record's class (``{e}``: its catalogue effects joined by " + ")
CORRECT = {
    "N": "nothing selected; no unexplained change",
    "E": "{e}",
    "P": "{e}",
    "X": "nothing selected; unexplained (a change outside the catalogue)",
}


@dataclass
class Red21Record:
    """One record of red team 21: plant effects and law, logger, noise, outliers and truth texts.

    The fields are the helper's record dict's (``make_records.py``), ``truth`` named ``effects`` here; the
    truth entry (:func:`truth_entry`) takes them as the helper's did.
    """

    name: str
    cls: str                        # 'N' nothing, 'E' one effect, 'P' two, 'X' outside the catalogue
    effects: tuple                  # catalogue effects the plant holds (truth "catalogue_truth")
    seed: int                       # one generator: nuisance, time-stamp jitter, then the noise
    fx: dict                        # the plant's effects (benchmarks.red21_plant.Plant's fx)
    law: str                        # the plant's burden law ('paper' or 'stribeck')
    noise: dict                     # current noise: w white, c AR(1) [A], tau [s], q step, offset [A]
    form: str | None = None         # the effects' form (truth "form"; the note when none)
    note: str = ""                  # the helper's note (truth "note")
    fs: float = 50.0                # logger rate [Hz]
    T: float = 40.0                 # length after the ramp start [s]
    jitter: float = 0.0             # time-stamp jitter [s] (uniform +-)
    speed_noise: dict | None = None  # the speed channel's noise (SPEED_NOISE when None)
    outliers: dict = field(default_factory=dict)     # {'current'/'speed': [(t [s], added value)]}
    p_override: dict = field(default_factory=dict)   # plant values that differ from the setup by construction
    stribeck: dict | None = None    # 'stribeck' law: frac (mu_st = mu_c + frac (mu_s - mu_c)), v_s [rad/s]
    size_excluding: tuple | None = None  # (a, b): the effect size also without the samples in a..b s
    catalogue: dict | None = None   # nearest catalogue parameters (truth)
    usual: str | None = None        # the magnitude against the usual ranges (truth)
    short: str = ""                 # the form in short (truth.md's table)


_RECORDS = [
    Red21Record(
        "N1", "N", (), 2101, {}, "paper", fs=100.0, T=60.0,
        noise=dict(w=3.0, c=2.5, tau=0.6, q=0.25, offset=1.2),
        note="no catalogue effect; logger at 100 Hz, 60 s after the ramp start, current sensor +1.2 A off",
        short="nothing; 100 Hz, 60 s, sensor +1.2 A"),
    Red21Record(
        "N2", "N", (), 2102, {}, "paper", fs=25.0, T=40.0, jitter=1e-3,
        noise=dict(w=2.5, c=3.0, tau=1.0, q=1.0, offset=0.0),
        speed_noise=dict(w=0.12, c=0.10, tau=0.3, q=0.5),
        outliers=dict(current=[(17.3, 260.0), (26.84, -190.0), (33.1, 320.0)]),
        note="no catalogue effect; logger at 25 Hz with +-1 ms time-stamp jitter, current in 1 A steps, "
             "speed in 0.5 rpm encoder steps, three one-sample current glitches",
        short="nothing; 25 Hz jittered, coarse steps, 3 glitches"),
    Red21Record(
        "E1", "E", ("second_motor",), 2111, dict(second_rotor_clutch=dict(J2=36.0, T_slip=250.0)), "paper",
        noise=dict(w=3.0, c=2.0, tau=0.4, q=0.5, offset=0.0),
        form="second (idle) motor of 36 kg m^2 on the motor shaft behind a torque-limiting friction "
             "(slip) coupling set to 250 N m: it slips from the ramp start, is dragged up at "
             "250 N m / 36 kg m^2 and locks only at ~14.6 s, 5.4 s after the ramp has ended",
        catalogue=dict(J_m2=36.0, note="locked it is a rigid J_m2 = 36 kg m^2; while slipping it takes "
                                       "250 N m, what a rigid J_m2 of 21.7 kg m^2 takes on the 110 rpm/s ramp"),
        usual="J_m2 usual 10-45 kg m^2 (Table 1), scaled with J_m: %.0f-%.0f: inside" % (10 * _SCALE_JM,
                                                                                           45 * _SCALE_JM),
        short="second motor behind a slip coupling (36 kg m^2, 250 N m)"),
    Red21Record(
        "E2", "E", ("drivetrain_compliance",), 2112,
        dict(three_mass=dict(k1=5.0e4, c1=100.0, J_g=9.0, k2=2.5e8, c2=0.9e6)), "paper",
        p_override=dict(J_m=21.0),
        noise=dict(w=2.5, c=2.5, tau=0.8, q=0.5, offset=0.0),
        form="three-mass drive train: motor rotor 21 kg m^2 - elastomer coupling 5e4 N m/rad, "
             "100 N m s/rad (motor side) - gearbox high-speed inertia 9 kg m^2 (motor speed; rotor + "
             "gearbox = the setup's J_m 30) - pinion shafts and mesh 2.5e8 N m/rad, 0.9e6 N m s/rad "
             "(kiln axis) - kiln. Modes 0.78 Hz (zeta 0.01) and 12 Hz (zeta 0.2)",
        catalogue=dict(k_po=2.49e8, C_po=0.9e6,
                       note="series stiffness at the kiln axis (coupling 5e4 n^2 = 1.05e11 in series with "
                            "2.5e8); the 12 Hz coupling mode has no catalogue counterpart"),
        usual="C_po 0.9e6 = 0.29x the scaled usual lower end %.2g (2e6 x %.2f); k 2.5e8 = 0.23x the "
              "setup's k_po 1.09e9 (Table 1 scaled)" % (2e6 * _SCALE_J, _SCALE_J),
        short="three-mass train, soft and lightly damped (0.29x C_po)"),
    Red21Record(
        "E3", "E", ("backlash",), 2113, dict(backlash_impact=dict(dx=0.010, e=0.5, v_lock=0.05)), "paper",
        size_excluding=(1.81, 1.89),
        note="seen with kilnctl compare: its reader takes the first impact (about +370 A at 1.82 s, the "
             "speed 6 rpm down in the same sample) for a logger glitch and leaves its two samples out; "
             "the free-turning first 0.8 s (current below the rigid plant's) stays",
        noise=dict(w=2.0, c=1.2, tau=0.3, q=0.5, offset=0.0),
        form="girth-gear backlash of 10 mm, whole gap open at the start, rigid teeth meeting with "
             "Newton restitution e = 0.5 (impulse between motor side and kiln shell; the burden, held by "
             "friction, takes no impulse), four impacts 1.81-1.88 s, then a rigid mesh",
        catalogue=dict(delta_x=0.010, gap_0=1.0),
        usual="paper: 0-16 mm, normal about 8 mm: inside",
        short="10 mm backlash, rigid impacts, restitution 0.5 (ratio 4.4 without the two impact samples)"),
    Red21Record(
        "E4", "E", ("speed_sensor_lag",), 2114, dict(lag3=dict(tau=0.005)), "paper",
        p_override=dict(ramp_rate=200.0),
        noise=dict(w=1.5, c=1.2, tau=0.5, q=0.1, offset=0.0),
        form="speed feedback through three equal first-order lags of 5 ms (tacho RC, drive input "
             "filter, anti-alias filter), seen by the speed controller and logged; this start-up "
             "ramps at 200 rpm/s (stated in the setup)",
        catalogue=dict(tau_s=0.015, note="same low-frequency delay as a 15 ms first-order lag; a "
                                         "second-order filter with tau_s 15 ms, zeta_s ~ 1.2 is closer"),
        usual="lag usual about 2-6 ms: 15 ms total is 2.5x the top",
        short="three cascaded 5 ms lags (15 ms), 200 rpm/s ramp"),
    Red21Record(
        "E5", "E", ("kiln_unbalance",), 2115, dict(thermal_bow=dict(T0=1.6e6, phi=2.4, theta_r=1.5)), "paper",
        noise=dict(w=3.0, c=2.0, tau=0.5, q=0.5, offset=0.0),
        form="thermal bow of the hot shell (kiln stopped hot, held by its brake, released at the "
             "ramp start): once-per-turn torque T0 exp(-theta_o/theta_r) sin(theta_o + phi) on the "
             "kiln, T0 1.6e6 N m, phi 2.4 rad, relaxing with theta_r 1.5 rad of kiln rotation "
             "(to 0.21 T0 by the end of the record)",
        catalogue=dict(T_unb=1.6e6, phi_unb=2.4, note="kilnctl's sign: torque -T_unb sin(theta_o + phi_unb) "
                                                      "on the kiln; here its amplitude decays"),
        usual="usual 1e5-3e5 N m (Table 1), scaled with m_v L: %.2g-%.2g: 1.6e6 is 3.5x the top"
              % (1e5 * _SCALE_MVL, 3e5 * _SCALE_MVL),
        short="relaxing thermal bow, 1.6e6 N m (3.5x)"),
    Red21Record(
        "E6", "E", ("viscous_drag",), 2116, dict(maxwell_drag=dict(B=9.0e6, tau=2.5)), "paper",
        noise=dict(w=3.0, c=3.0, tau=1.0, q=0.5, offset=0.0),
        outliers=dict(current=[(21.46, 210.0), (35.02, -260.0)], speed=[(29.3, 14.0)]),
        form="viscoelastic seal/grease drag (Maxwell element): dT/dt = (B omega_o - T)/tau on the kiln, "
             "B 9e6 N m s/rad, tau 2.5 s: the drag lags the speed by 2.5 s and reaches B omega_o "
             "(5.9e5 N m, 56 A) at the set speed",
        catalogue=dict(B_o=9.0e6),
        usual="drag usual lower end 2e6 N m s/rad (Table 1), scaled %.2g: 9e6 is 3.9x it" % (2e6 * _SCALE_DRAG),
        short="Maxwell (lagging) drag 9e6 N m s/rad, tau 2.5 s"),
    Red21Record(
        "E7", "E", ("motor_coulomb_friction",), 2117, dict(dahl_motor_friction=dict(Tc=420.0, sigma=600.0)),
        "paper",
        noise=dict(w=2.0, c=2.0, tau=0.3, q=0.5, offset=-0.6),
        form="Dahl friction on the motor shaft (brushes, bearings, seals): dF/dt = sigma (omega_m - "
             "|omega_m| F/T_c), T_c 420 N m, pre-sliding stiffness sigma 600 N m/rad: no stiction, the "
             "friction builds over the first ~0.7 rad of motor rotation; current sensor -0.6 A off",
        catalogue=dict(T_cm=420.0),
        usual="T_cm usual 10-100 N m (Table 1), scaled with k_i I_max: %.1f-%.0f: 420 is 3.4x the top"
              % (10 * _SCALE_TCM, 100 * _SCALE_TCM),
        short="Dahl motor friction 420 N m (3.4x)"),
    Red21Record(
        "P1", "P", ("torque_friction_law", "current_limit"), 2121,
        dict(i2t_limit=dict(I_hi=780.0, I_lo=630.0, I_n=600.0, E1=0.8, E2=1.0, k_l=8.0)),
        "stribeck", stribeck=dict(frac=0.7, v_s=0.03),
        noise=dict(w=3.0, c=2.5, tau=0.6, q=0.5, offset=0.0),
        form="(1) torque-consistent burden friction (breakaway when the holding torque exceeds "
             "mu_s N R) with a Stribeck kinetic law mu(v) = mu_c + (mu_st - mu_c) exp(-(v/v_s)^2), "
             "mu_st = mu_c + 0.7 (mu_s - mu_c), v_s 0.03 rad/s: stick-slip cycles of ~5.2 s; "
             "(2) overload (I^2 t) current limit: 780 A while the budget lasts, folding back to 630 A "
             "(smoothstep between budgets E 0.8 and 1.0, E' = max(i^2 - 600^2, 0)/600^2 in s), a "
             "proportional limiter of 8 V/A taking voltage off the armature, speed integrator frozen "
             "while limiting: the first two stick peaks (~745 and 715 A) pass, the later ones are held "
             "near 630 A (the P limiter's droop lets 20-25 A more through as the speed error grows) "
             "and the drive falls up to ~90 rpm (10 %) behind its set speed before each breakaway",
        catalogue=dict(friction_law="torque", I_max="780 A (not reached), then about 630-655 A from about 22 s"),
        usual="I_max of the setup 1250 A; the limit that acts (630 A) is 0.5x it",
        short="Stribeck torque law + I^2t current foldback 780->630 A"),
    Red21Record(
        "P2", "P", ("second_motor", "drivetrain_compliance"), 2122,
        dict(dual_pinion=dict(J_m2=30.0, kA=3.0e9, cA=1.5e7, kB=3.0e9, cB=1.5e7)), "paper",
        noise=dict(w=3.0, c=2.0, tau=0.4, q=0.5, offset=0.0),
        outliers=dict(current=[(15.62, -220.0), (31.18, 300.0)]),
        form="dual-pinion drive: the second motor (30 kg m^2, electrically isolated, idle) drives the "
             "girth gear through its own gearbox and pinion; each pinion train a spring-damper at the "
             "kiln axis (3e9 N m/rad, 1.5e7 N m s/rad). The logged motor's train and the idle motor's "
             "train are in parallel on the kiln: modes 0.76 Hz (zeta 0.02) and 3.9 Hz (zeta 0.06)",
        catalogue=dict(J_m2=30.0, k_po="3e9 (one train) to 6e9 (both)", C_po="1.5e7-3e7",
                       note="in the catalogue the second motor sits rigidly on the logged motor; here "
                            "it hangs on the kiln behind its own train"),
        usual="J_m2 inside (14-63 scaled); k_po 3e9 is 2.8x the setup's 1.09e9",
        short="dual-pinion drive: idle 2nd motor on its own train"),
    Red21Record(
        "X1", "X", (), 2131, dict(field_buildup=dict(a=0.45, tau=1.6)), "paper",
        noise=dict(w=2.5, c=2.0, tau=0.5, q=0.5, offset=0.0),
        form="outside the catalogue: field economy at standstill: the motor's field (flux) is at 55 % "
             "when the ramp starts and is restored with the field time constant 1.6 s, "
             "Phi(t) = 1 - 0.45 exp(-(t - t0)/1.6 s); torque k_i Phi i_a, back-emf k_b Phi omega_m",
        catalogue=None, usual="-",
        short="field economy: flux 55 % at start, tau 1.6 s"),
    Red21Record(
        "X2", "X", (), 2132, dict(supply_sag=dict(t_on=24.0, t_off=25.6, V_sag=680.0, T_aw=0.05)), "paper",
        noise=dict(w=3.0, c=2.5, tau=0.7, q=0.5, offset=0.0),
        form="outside the catalogue: a mains voltage sag: the converter's ceiling falls from V_max 820 V "
             "to 680 V (83 %) from 24.0 to 25.6 s, below the 695 V the running drive needs; the "
             "converter's own back-calculation anti-windup (T_aw 50 ms)",
        catalogue=None, usual="-",
        short="mains sag: V ceiling 820->680 V for 1.6 s"),
]

#: the thirteen records by name, in the helper's order (N1 N2 E1..E7 P1 P2 X1 X2; truth.json's order)
RECORDS = {r.name: r for r in _RECORDS}


def _record(name) -> Red21Record:
    if isinstance(name, Red21Record):
        return name
    try:
        return RECORDS[name]
    except KeyError:
        raise KeyError(f"no red team 21 record {name!r}; there are {', '.join(RECORDS)}") from None


# ---------------------------------------------------------------- plant values
def nuisance(name, rng=None) -> dict:
    """The record's nuisance: factors on the plant's m_v, mu_c, mu_s and J_v (each 1 +- 0.02..0.06).

    The helper's draw: the record's generator (``numpy.random.default_rng(seed)``) draws these first, then
    the time-stamp jitter and the noise (:func:`write_record`).

    Parameters
    ----------
    name : str or Red21Record
        The record (e.g. ``'E3'``).
    rng : numpy.random.Generator, optional
        The generator to draw from (a new one seeded with the record's seed by default).

    Returns
    -------
    dict
        ``m_v``, ``mu_c``, ``mu_s``, ``J_v``: the factor [-] on the setup's value.
    """
    if rng is None:
        rng = np.random.default_rng(_record(name).seed)
    out = {}
    for k in ("m_v", "mu_c", "mu_s", "J_v"):
        sign = 1.0 if rng.random() < 0.5 else -1.0
        out[k] = 1.0 + sign * rng.uniform(0.02, 0.06)
    return out


def true_params(name, nuis=None) -> dict:
    """The record's plant parameters: K-21 with the nuisance, the plant's own values and its Stribeck values.

    Parameters
    ----------
    name : str or Red21Record
        The record.
    nuis : dict, optional
        Its nuisance factors (:func:`nuisance` by default).

    Returns
    -------
    dict
        Parameters of :class:`benchmarks.red21_plant.Plant` (``mu_st`` and ``v_s`` too under the Stribeck law).
    """
    rec = _record(name)
    nuis = nuisance(rec) if nuis is None else nuis
    p = dict(K21)
    for k, f in nuis.items():
        p[k] = K21[k] * f
    p.update(rec.p_override)
    if rec.law == "stribeck":
        s = rec.stribeck
        p["mu_st"] = p["mu_c"] + s["frac"] * (p["mu_s"] - p["mu_c"])
        p["v_s"] = s["v_s"]
    return p


def sample_times(name, rng=None) -> np.ndarray:
    """The record's time stamps [s]: ``(T + 1 s) fs + 1`` samples from 0, jittered (N2) and rounded to 0.1 ms.

    Parameters
    ----------
    name : str or Red21Record
        The record.
    rng : numpy.random.Generator, optional
        The record's generator after its nuisance draw (needed for a jittered record; by default a new one,
        the nuisance drawn first).

    Returns
    -------
    numpy.ndarray
        The times [s]; the first is 0.
    """
    rec = _record(name)
    fs = rec.fs
    n = int(round((rec.T + T0) * fs)) + 1
    ts = np.arange(n) / fs
    if rec.jitter:
        if rng is None:
            rng = np.random.default_rng(rec.seed)
            nuisance(rec, rng)
        ts = ts + rng.uniform(-rec.jitter, rec.jitter, n)
        ts[0] = 0.0
        ts = np.round(ts, 4)
    return ts


def simulate(p, law, fx, ts, T_end):
    """The plant from the ramp start :data:`T0` to ``T_end``, sampled at ``ts``.

    Returns
    -------
    out : dict
        :meth:`benchmarks.red21_plant.Plant.sample`'s outputs.
    events : list
        The plant's mode switches, ``(t, name)``.
    """
    pl = Plant(p, law=law, fx=fx, t0=T0).simulate(T_end)
    return pl.sample(ts), pl.events_log


def simulate_record(name, effects=True) -> tuple:
    """The record's plant (nuisance, and its effects and law unless ``effects`` is false) at its time stamps.

    About half a second of CPU for most records.

    Parameters
    ----------
    name : str or Red21Record
        The record.
    effects : bool, default True
        False: the effect-free counterpart the helper measured the effect against (same nuisance, the
        paper's law, no effect, the setup's J_m, the record's ramp rate).

    Returns
    -------
    out : dict
        :meth:`benchmarks.red21_plant.Plant.sample`'s outputs.
    events : list
        The plant's mode switches, ``(t, name)``.
    ts : numpy.ndarray
        The time stamps [s].
    """
    rec = _record(name)
    rng = np.random.default_rng(rec.seed)
    p = true_params(rec, nuisance(rec, rng))
    ts = sample_times(rec, rng)
    T_end = float(ts[-1]) + 1e-6
    if effects:
        return (*simulate(p, rec.law, rec.fx, ts, T_end), ts)
    return (*simulate(_base_params(rec, p), "paper", {}, ts, T_end), ts)


def _base_params(rec, p):
    """The effect-free counterpart's parameters (the helper's ``p0``)."""
    p0 = dict(p)
    p0["J_m"] = K21["J_m"]
    if "ramp_rate" in rec.p_override:
        p0["ramp_rate"] = rec.p_override["ramp_rate"]
    return p0


# ---------------------------------------------------------------- effect size, noise
def ar1(rng, n, dt, sigma, tau):
    """An AR(1) sequence of ``n`` samples ``dt`` apart, stationary standard deviation ``sigma``, time constant
    ``tau`` (zeros for ``sigma`` 0)."""
    if sigma <= 0:
        return np.zeros(n)
    a = math.exp(-dt / tau)
    e = rng.standard_normal(n) * sigma * math.sqrt(1 - a * a)
    x = np.empty(n)
    x[0] = rng.standard_normal() * sigma
    for k in range(1, n):
        x[k] = a * x[k - 1] + e[k]
    return x


def worst_window(d, ts, width=1.0):
    """Largest RMS of d over windows of `width` s (step 0.1 s) and its start."""
    best, tb = 0.0, float(ts[0])
    t = float(ts[0])
    while t + width <= ts[-1] + 1e-9:
        sel = (ts >= t) & (ts < t + width)
        if sel.any():
            r = float(np.sqrt(np.mean(d[sel] ** 2)))
            if r > best:
                best, tb = r, t
        t += 0.1
    return best, tb


def effect_size(name, out, base, ts, p=None) -> dict:
    """The record's effect on the current against its noise, as the helper measured it (truth "effect_size").

    ``all``: the worst 1 s window RMS of the noise-free current of the record's plant minus its effect-free
    counterpart, its start, the largest difference (and in the speed) and the ratio to the current noise's
    RMS; for E3 the same without the impact samples; for P1 and P2 each effect's part (P1: the Stribeck
    torque law alone, the current limit alone under the paper law, the current limit beside the torque law;
    P2: a rigid second motor alone, the logged motor's train alone, the trains beside a rigid second motor).
    P1 and P2 simulate their parts (two more plant runs).

    Parameters
    ----------
    name : str or Red21Record
        The record.
    out, base : dict
        The record's plant and its effect-free counterpart at ``ts`` (:func:`simulate_record`).
    ts : numpy.ndarray
        The time stamps [s].
    p : dict, optional
        The record's plant parameters (:func:`true_params`), for P1 and P2's parts.

    Returns
    -------
    dict
        ``all`` and the parts by name: ``worst_1s_rms_A``, ``window_start_s``, ``ratio`` (and for ``all``
        ``max_abs_A``, ``max_abs_speed_rpm``).
    """
    rec = _record(name)
    p = true_params(rec) if p is None else p
    T_end = float(ts[-1]) + 1e-6
    sizes = {}
    noise = rec.noise
    noise_rms = math.hypot(noise["w"], noise["c"])
    d = out["i_a"] - base["i_a"]
    w, tw = worst_window(d, ts)
    sizes["all"] = dict(worst_1s_rms_A=round(w, 2), window_start_s=round(tw, 1),
                        max_abs_A=round(float(np.max(np.abs(d))), 1),
                        ratio=round(w / noise_rms, 1),
                        max_abs_speed_rpm=round(float(np.max(np.abs(out["speed_rpm"] - base["speed_rpm"]))), 2))
    if rec.size_excluding:
        a, b = rec.size_excluding
        keep = (ts < a) | (ts > b)
        w2, tw2 = worst_window(np.where(keep, d, 0.0), ts)
        sizes[f"without the samples in {a}-{b} s"] = dict(worst_1s_rms_A=round(w2, 2), window_start_s=round(tw2, 1),
                                                          ratio=round(w2 / noise_rms, 1))
    if rec.cls == "P":
        parts = {}
        if rec.name == "P1":
            o1, _ = simulate(p, "stribeck", {}, ts, T_end)
            parts["torque_friction_law"] = o1
            o2, _ = simulate(p, "paper", rec.fx, ts, T_end)
            parts["current_limit (alone, under the paper law: never reached)"] = o2
            parts["current_limit"] = ("rel", o1)          # what it adds beside the torque law
        else:
            # the second motor alone (rigid on the motor shaft) and the compliance alone
            ps = dict(p)
            ps["J_m"] = p["J_m"] + rec.fx["dual_pinion"]["J_m2"]
            o1, _ = simulate(ps, "paper", {}, ts, T_end)
            parts["second_motor"] = o1                     # a rigid second motor alone
            fxa = dict(dual_pinion=dict(rec.fx["dual_pinion"]))
            fxa["dual_pinion"].update(J_m2=1.0, kB=0.0, cB=0.0)     # the idle motor uncoupled
            o2, _ = simulate(p, "paper", fxa, ts, T_end)
            parts["drivetrain_compliance (logged motor's train alone)"] = o2
            parts["drivetrain_compliance"] = ("rel", o1)  # what the trains add beside a rigid 2nd motor
        for k, o in parts.items():
            if isinstance(o, tuple):
                dd = out["i_a"] - o[1]["i_a"]
            else:
                dd = o["i_a"] - base["i_a"]
            ww, tww = worst_window(dd, ts)
            sizes[k] = dict(worst_1s_rms_A=round(ww, 2), window_start_s=round(tww, 1), ratio=round(ww / noise_rms, 1))
    return sizes


def log_record(name, out, ts, rng) -> dict:
    """The logger's channels: the plant's outputs with noise, in steps, the outliers written in.

    Current: the plant's plus the sensor offset, white noise and AR(1) noise, rounded to its step; speed:
    the logged (fed-back) speed plus white and AR(1) noise, rounded to its step; then each outlier added to
    the sample nearest its time.  The reference is the plant's, as it is.

    Parameters
    ----------
    name : str or Red21Record
        The record.
    out : dict
        The record's plant at ``ts`` (:func:`simulate_record`).
    ts : numpy.ndarray
        The time stamps [s].
    rng : numpy.random.Generator
        The record's generator after its nuisance and jitter draws.

    Returns
    -------
    dict
        ``current`` [A], ``speed`` [rpm], ``ref`` [rpm] (numpy arrays), ``outliers`` (the record's, as
        written into the truth) and ``speed_noise`` (the speed channel's noise dict).
    """
    rec = _record(name)
    n = len(ts)
    fs = rec.fs
    noise = rec.noise
    dt = 1.0 / fs
    cur = out["i_a"] + noise["offset"] + rng.standard_normal(n) * noise["w"] + ar1(rng, n, dt, noise["c"], noise["tau"])
    sn = rec.speed_noise if rec.speed_noise is not None else SPEED_NOISE
    spd = out["speed_rpm"] + rng.standard_normal(n) * sn["w"] + ar1(rng, n, dt, sn["c"], sn["tau"])
    cur = np.round(cur / noise["q"]) * noise["q"]
    spd = np.round(spd / sn["q"]) * sn["q"]
    outl = rec.outliers
    for (tt, a) in outl.get("current", []):
        k = int(np.argmin(np.abs(ts - tt)))
        cur[k] += a
    for (tt, a) in outl.get("speed", []):
        k = int(np.argmin(np.abs(ts - tt)))
        spd[k] += a
    return dict(current=cur, speed=spd, ref=out["ref_rpm"], outliers=outl, speed_noise=sn)


# ---------------------------------------------------------------- files
#: the TOML's sections and keys, in the helper's order (``tomlio.py``)
SECTIONS = {
    "motor": ["R_a", "L_a", "k_i", "k_b", "J_m", "B_m"],
    "controller": ["gains", "k_p", "k_I", "k_D"],
    "drive": ["omega_ref", "ramp_rate", "V_max", "I_max"],
    "kiln": ["J_o", "J_v", "J_e_mode", "m_v", "L", "R", "mu_c", "mu_s", "friction_law",
             "mu_brg", "P", "l_brg", "k_brg", "psi_0", "g"],
    "gear": ["n", "R_o", "R_p", "k_po", "C_po", "J_p", "k_o", "k_pi", "C_e", "delta_x", "gap_0",
             "module", "face_width"],
    "coupling": ["k_c", "c_c"],
}

#: what every TOML states beside :data:`~benchmarks.red21_plant.K21`: the gains given, J_e_mode, the paper's
#: friction law and K-21's micro-model and effect values (used only by kilnctl's candidates)
EXTRA = dict(gains="given", J_e_mode="sum", friction_law="paper",
             k_po=1.09e9, C_po=3.08e7, J_p=2000.0, k_o=3.3e10, k_pi=3.3e10, C_e=1.0e6,
             delta_x=0.008, gap_0=1.0, module=0.04, face_width=0.7, k_c=1.5e5, c_c=250.0)


def fmt(v):
    """A TOML value: a string quoted, a bool as ``true``/``false``, an int as is, a number as ``repr(float)``."""
    if isinstance(v, str):
        return f'"{v}"'
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    return repr(float(v))


def write_toml(path, p, header="", friction_law="paper", measurement=None):
    """Write the setup ``p`` (with :data:`EXTRA`) as kilnctl's TOML: ``header``'s lines as comments, then
    :data:`SECTIONS`' keys present, and a ``[measurement]`` section when given."""
    vals = dict(EXTRA)
    vals.update(p)
    vals["friction_law"] = friction_law
    lines = []
    for h in header.splitlines():
        lines.append("# " + h if h else "#")
    for sec, keys in SECTIONS.items():
        lines.append("")
        lines.append(f"[{sec}]")
        for k in keys:
            if k in vals:
                lines.append(f"{k} = {fmt(vals[k])}")
    if measurement:
        lines.append("")
        lines.append("[measurement]")
        for k, v in measurement.items():
            lines.append(f"{k} = {fmt(v)}")
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")


def write_csv(path, name, log, ts):
    """Write the record: a comment line, the header, then time, current, speed and reference.

    Time with 4 decimals, the current and speed with one decimal more than their step has, the reference
    with 3.
    """
    rec = _record(name)
    noise, sn = rec.noise, log["speed_noise"]
    cur, spd, ref = log["current"], log["speed"], log["ref"]
    with open(path, "w") as f:
        f.write(f"# kiln K-21, start-up record {rec.name}, logger at {rec.fs:g} Hz\n")
        f.write("time_s,current_A,speed_rpm,speed_ref_rpm\n")
        qd = max(0, int(-math.floor(math.log10(noise["q"]))) + 1)
        sd = max(0, int(-math.floor(math.log10(sn["q"]))) + 1)
        for k in range(len(ts)):
            f.write(f"{ts[k]:.4f},{cur[k]:.{qd}f},{spd[k]:.{sd}f},{ref[k]:.3f}\n")


# ---------------------------------------------------------------- truth
def _fmt_events(ev):
    return [f"{t:.3f} {k}" for t, k in ev]


def truth_entry(name, nuis, p, ts, sizes, events, outliers, speed_noise) -> dict:
    """The record's truth, as the helper's ``truth.json`` holds it (``records[NAME]``)."""
    rec = _record(name)
    eff = list(rec.effects)
    noise = rec.noise
    sn = speed_noise
    correct = CORRECT[rec.cls].format(e=" + ".join(eff))
    return dict(
        record=rec.name, csv=f"{rec.name}.csv", toml=f"{rec.name}.toml", cls=rec.cls,
        catalogue_truth=eff, correct_diagnosis=correct,
        form=rec.form if rec.form is not None else rec.note,
        plant_effects=rec.fx,
        burden_law=rec.law + (" (Stribeck: %s)" % rec.stribeck if rec.law == "stribeck" else ""),
        nearest_catalogue_parameters=rec.catalogue,
        usual_range=rec.usual,
        plant_overrides=rec.p_override,
        nuisance_factors={k: round(v, 4) for k, v in nuis.items()},
        nuisance_values={k: float("%.6g" % p[k]) for k in nuis},
        extra_plant_values=({"mu_st": round(p["mu_st"], 4), "v_s": p["v_s"]} if rec.law == "stribeck" else {}),
        sampling=dict(fs_Hz=rec.fs, duration_s=float("%.4f" % ts[-1]), samples=len(ts), ramp_start_s=T0,
                      ramp_rate_rpm_s=p["ramp_rate"], jitter_s=rec.jitter),
        noise=dict(current=dict(white_A=noise["w"], ar1_A=noise["c"], ar1_tau_s=noise["tau"],
                                quantum_A=noise["q"], offset_A=noise["offset"],
                                rms_A=round(math.hypot(noise["w"], noise["c"]), 3)),
                   speed=dict(white_rpm=sn["w"], ar1_rpm=sn["c"], ar1_tau_s=sn["tau"], quantum_rpm=sn["q"]),
                   outliers=outliers, seed=rec.seed),
        effect_size=sizes,
        plant_events=_fmt_events(events)[:40],
        note=rec.note,
    )


def regime_text() -> str:
    """K-21's burden regime under the two laws (truth.json's ``regime``, truth.md's third paragraph)."""
    return (f"K-21 burden: mu_c R/L = {MU_CR_L:.3f}; mu_s = {K21['mu_s']} < mu_c R/L, so under the paper's "
            f"printed law the burden breaks away at tan psi = mu_s ({math.degrees(math.atan(K21['mu_s'])):.1f} deg), "
            f"is held by kinetic friction until tan psi = mu_c R/L ({math.degrees(math.atan(MU_CR_L)):.1f} deg) and "
            f"then slides steadily with the undamped sliding oscillation of eqs. 22-25 (no stick-slip at set speed). "
            f"Under the torque-consistent law it breaks away at tan psi = mu_s R/L "
            f"({math.degrees(math.atan(K21['mu_s'] * K21['R'] / K21['L'])):.1f} deg): "
            f"stick-slip cycles of about 5.1 s.")


def truth_json(truths) -> str:
    """The helper's ``truth.json`` for the records in ``truths`` (a list of :func:`truth_entry`'s, in order):
    byte for byte the helper's for all thirteen."""
    doc = dict(kiln="K-21", setup_values=K21, regime=regime_text(), ramp_start_s=T0,
               records={tr["record"]: tr for tr in truths})
    return json.dumps(doc, indent=1, default=float)


def truth_md(truths) -> str:
    """The helper's ``truth.md`` for the records in ``truths`` (a list of :func:`truth_entry`'s, in order).

    Byte for byte the helper's but for its second paragraph's first sentences, which named the helper's files.
    """
    L = []
    L.append("# Red team 21: truth of the twelve K-21 start-up records\n")
    L.append("Generated by `python -m benchmarks.red21_records --write DIR` (do not edit). Plant: "
             "`benchmarks/red21_plant.py` (independent, numpy/scipy). "
             "Every setup TOML states the nominal K-21 values with `gains = \"given\"` and `friction_law = \"paper\"`; "
             "the records' plants differ by the nuisance below (not told) and by the hidden effect.\n")
    L.append(regime_text() + "\n")
    L.append("Size ratio: the noise-free effect on the current (record's plant minus the same plant without "
             "the effect, same nuisance), its RMS over the worst 1 s window, divided by the current noise RMS "
             "(white and AR(1) together).\n")
    L.append("| record | catalogue truth | what a correct diagnosis says | size ratio (worst 1 s) | form (short) |")
    L.append("|---|---|---|---|---|")
    for t in truths:
        r = t["effect_size"]["all"]["ratio"]
        ratio = "-" if t["cls"] == "N" else f"{r:.1f}"
        if t["cls"] == "P":
            parts = [f"{k.split(' ')[0]} {v['ratio']:.1f}" for k, v in t["effect_size"].items()
                     if k != "all" and "(" not in k]
            ratio += " (" + ", ".join(parts) + ")"
        truth = ", ".join(t["catalogue_truth"]) or "-"
        L.append(f"| {t['record']} | {truth} | {t['correct_diagnosis']} | {ratio} | {_record(t['record']).short} |")
    L.append("")
    for t in truths:
        L.append(f"## {t['record']}\n")
        L.append(f"* catalogue truth: {', '.join(t['catalogue_truth']) or 'none'}; a correct diagnosis: "
                 f"**{t['correct_diagnosis']}**")
        L.append(f"* form: {t['form']}")
        if t["nearest_catalogue_parameters"]:
            L.append(f"* nearest catalogue parameters: {json.dumps(t['nearest_catalogue_parameters'])}")
        if t["usual_range"] and t["usual_range"] != "-":
            L.append(f"* magnitude: {t['usual_range']}")
        L.append(f"* burden law of the plant: {t['burden_law']}")
        if t["plant_overrides"]:
            L.append(f"* plant values that differ from the setup by construction: {t['plant_overrides']}")
        nv = ", ".join(f"{k} {t['nuisance_values'][k]:.6g} ({(t['nuisance_factors'][k] - 1) * 100:+.1f} %)"
                       for k in t["nuisance_values"])
        L.append(f"* nuisance (not in the TOML): {nv}")
        if t["extra_plant_values"]:
            L.append(f"* Stribeck values: {t['extra_plant_values']}")
        s = t["sampling"]
        c = t["noise"]["current"]
        sp = t["noise"]["speed"]
        L.append(f"* sampling: {s['fs_Hz']:g} Hz, {s['samples']} samples to {s['duration_s']:g} s, ramp from "
                 f"{s['ramp_start_s']:g} s at {s['ramp_rate_rpm_s']:g} rpm/s"
                 + (f", time stamps jittered +-{s['jitter_s'] * 1e3:g} ms" if s["jitter_s"] else ""))
        L.append(f"* current noise: white {c['white_A']} A + AR(1) {c['ar1_A']} A (tau {c['ar1_tau_s']} s), "
                 f"RMS {c['rms_A']} A, steps {c['quantum_A']} A, offset {c['offset_A']:+g} A; speed noise: "
                 f"white {sp['white_rpm']} rpm + AR(1) {sp['ar1_rpm']} rpm (tau {sp['ar1_tau_s']} s), steps "
                 f"{sp['quantum_rpm']} rpm; seed {t['noise']['seed']}")
        if t["noise"]["outliers"]:
            L.append(f"* outliers (one sample each, added): {t['noise']['outliers']}")
        for k, v in t["effect_size"].items():
            if k == "all":
                L.append(f"* effect size: worst 1 s RMS {v['worst_1s_rms_A']} A from {v['window_start_s']} s "
                         f"(max {v['max_abs_A']} A; speed up to {v['max_abs_speed_rpm']} rpm): ratio {v['ratio']}")
            else:
                L.append(f"  * {k}: worst 1 s RMS {v['worst_1s_rms_A']} A from {v['window_start_s']} s, "
                         f"ratio {v['ratio']}")
        if t["note"] and t["cls"] != "N":
            L.append(f"* note: {t['note']}")
        L.append(f"* plant events: {'; '.join(t['plant_events'][:14])}{' ...' if len(t['plant_events']) > 14 else ''}")
        L.append("")
    return "\n".join(L) + "\n"


# ---------------------------------------------------------------- one record
def write_record(name, folder) -> dict:
    """Write ``NAME.csv``, ``NAME.toml`` (the setup) and ``NAME.truth.json`` into ``folder``.

    The CSV and TOML are the helper's byte for byte, the JSON its ``truth.json`` entry.  The record's plant,
    its effect-free counterpart and (P1, P2) the parts' plants are simulated: about 1-2 s of CPU a record
    (P2 2.3 s, N1 2.1 s; P1 about 12 s, four runs through its stick-slip cycles and current limit).

    Parameters
    ----------
    name : str or Red21Record
        The record (e.g. ``'E3'``).
    folder : str or Path
        Output folder (created).

    Returns
    -------
    dict
        The truth as in the JSON (:func:`truth_entry`: ``record``, ``cls``, ``catalogue_truth``,
        ``correct_diagnosis``, ``form``, ``plant_effects``, ``burden_law``, ``nuisance_factors``,
        ``nuisance_values``, ``sampling``, ``noise`` with the ``outliers``, ``effect_size``,
        ``plant_events``, ...), but ``csv`` and ``toml`` the paths written, with ``truth`` (the JSON's path),
        ``entry`` (the truth entry itself, for :func:`truth_json` and :func:`truth_md`), the time stamps
        ``t`` [s] and the noise-free current ``i_clean`` [A] and speed ``w_clean`` [rpm] (not in the JSON).
    """
    rec = _record(name)
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    # one generator, as the helper's: nuisance, jitter, then (after the plant runs) the noise
    rng = np.random.default_rng(rec.seed)
    nuis = nuisance(rec, rng)
    p = true_params(rec, nuis)
    ts = sample_times(rec, rng)
    T_end = float(ts[-1]) + 1e-6
    out, events = simulate(p, rec.law, rec.fx, ts, T_end)
    base, _ = simulate(_base_params(rec, p), "paper", {}, ts, T_end)
    sizes = effect_size(rec, out, base, ts, p)
    log = log_record(rec, out, ts, rng)
    csv = folder / f"{rec.name}.csv"
    write_csv(csv, rec, log, ts)
    setup = dict(K21)
    setup.update({k: v for k, v in rec.p_override.items() if k in ("ramp_rate",)})
    toml = folder / f"{rec.name}.toml"
    write_toml(toml, setup, header=f"kiln K-21: setup for start-up record {rec.name} (nominal values; gains as run)")
    entry = truth_entry(rec, nuis, p, ts, sizes, events, log["outliers"], log["speed_noise"])
    path = folder / f"{rec.name}.truth.json"
    path.write_text(json.dumps(entry, indent=1, default=float) + "\n")
    return dict(entry, csv=str(csv), toml=str(toml), truth=str(path), entry=entry, t=ts,
                i_clean=out["i_a"], w_clean=out["speed_rpm"])


def main(argv=None) -> int:
    """Command line: list or write red team 21's records."""
    ap = argparse.ArgumentParser(prog="python -m benchmarks.red21_records",
                                 description="Write red team 21's start-up records of kiln K-21 (an independent "
                                             "plant), each with its setup TOML and truth JSON.")
    ap.add_argument("--list", action="store_true", help="list the records and their truth")
    ap.add_argument("--write", metavar="DIR", help="write the records into DIR (and truth.json, truth.md for them)")
    ap.add_argument("--only", metavar="A,B", help="only these records (e.g. N2,E1)")
    a = ap.parse_args(argv)
    recs = [_record(n) for n in a.only.split(",")] if a.only else list(RECORDS.values())
    if a.list or not a.write:
        for r in recs:
            exp = CORRECT[r.cls].format(e=" + ".join(r.effects))
            print(f"{r.name:3s} {r.cls}  {r.fs:5.1f} Hz  {r.T + T0:4.0f} s  law={r.law:8s}  "
                  f"effects={list(r.effects)}  expected: {exp}")
        return 0
    entries = []
    for r in recs:
        tr = write_record(r, a.write)
        entries.append(tr["entry"])
        print(f"{r.name}: {tr['csv']} ({tr['sampling']['samples']} samples, {len(tr['plant_events'])} plant "
              f"events, effect ratio {tr['effect_size']['all']['ratio']}); kilnctl diagnose --data {tr['csv']} "
              f"--config {tr['toml']}")
    folder = Path(a.write)
    (folder / "truth.json").write_text(truth_json(entries))
    (folder / "truth.md").write_text(truth_md(entries))
    return 0


if __name__ == "__main__":
    sys.exit(main())
