"""Write red team 8's records: python -m benchmarks.red8_records OUTDIR [--only R01,R03] [--no-visibility]

Each record: OUTDIR/NAME.csv (time_s,current_A,speed_rpm[,speed_ref_rpm]), OUTDIR/NAME.toml (the
setup an engineer would know: Table 1, the drive's gains and ramp, friction_law when known) and
OUTDIR/NAME.truth.json (plant values, effects, expected answer in kilnctl's catalogue names,
noise, and each effect's visibility measured on the noise-free plant).
"""
import json
import math
import os
import sys

import numpy as np

from benchmarks.red8_plant import Plant, TABLE1, fit_percent, ar1

FS = 50.0
T_END = 40.0
T0 = 1.0


def base_values(nuis):
    return {k: TABLE1[k] * f for k, f in nuis.items()}


SPECS = [
    dict(name="R01_nothing_spikes", seed=801, law="paper", setup_law=None,
         nuis=dict(m_v=1.03, mu_c=0.97, mu_s=1.04, J_v=0.96), eff={}, gains=(2.0, 5.0, 0.01),
         noise=dict(I_w=3.0, I_ar=3.0, I_tau=0.4, w_w=0.2, w_ar=0.2, w_tau=0.3, spikes=True, I_quant=2.0),
         expected=[], answer="nothing",
         note="no effect; current with impulsive two-sample spikes (contactor / thyristor EMI) every 2-6 s, "
              "40-180 A, both signs, a few on the speed too; current quantised to 2 A"),
    dict(name="R01b_nothing_spikes1", seed=801, law="paper", setup_law=None,
         nuis=dict(m_v=1.03, mu_c=0.97, mu_s=1.04, J_v=0.96), eff={}, gains=(2.0, 5.0, 0.01),
         noise=dict(I_w=3.0, I_ar=3.0, I_tau=0.4, w_w=0.2, w_ar=0.2, w_tau=0.3, spikes=True, I_quant=2.0,
                    spike_tail=0.0),
         expected=[], answer="nothing",
         note="probe variant of R01 (same plant, same noise draw): the spikes are one sample long (no 40 % tail)"),
    dict(name="R02_torque_ripple", seed=802, law="torque", setup_law="torque",
         nuis=dict(m_v=0.97, mu_c=1.03, mu_s=0.97, J_v=1.04), eff={}, gains=(2.0, 5.0, 0.01),
         noise=dict(I_w=2.5, I_ar=2.5, I_tau=0.3, w_w=0.2, w_ar=0.15, w_tau=0.2, ripple=dict(A=12.0, f=6 * 49.97,
                                                                                               jit=1e-4)),
         expected=[], answer="nothing",
         note="no effect, torque law stated in the setup; the current carries a six-pulse converter ripple "
              "(300 Hz of a 49.97 Hz grid, 12 A) sampled at 50 Hz with 0.1 ms clock jitter: an alias at "
              "0.18 Hz plus broadband noise"),
    dict(name="R03_torque_softlimit", seed=803, law="torque", setup_law="torque",
         nuis=dict(m_v=1.04, mu_c=0.98, mu_s=0.97, J_v=1.03),
         eff=dict(soft_limit=dict(I_lim_frac=0.92, kp=0.05, ki=5.0)), gains=(2.0, 5.0, 0.01),
         noise=dict(I_w=3.0, I_ar=3.0, I_tau=0.4, w_w=0.25, w_ar=0.2, w_tau=0.3),
         expected=["current_limit"], answer="current_limit",
         note="torque law stated; the drive's current limit is a PI regulator on the armature voltage "
              "(kp 0.05 V/A, ki 5 V/(A s), integrator >= 0, speed integrator frozen while it acts) set at 0.92 "
              "of the unlimited peak: no flat top, the current creeps up to 35 A above the set limit while the "
              "load rises before each breakaway, and the speed dips by up to 50 rpm"),
    dict(name="R04_motor_heating", seed=804, law="paper", setup_law=None,
         nuis=dict(m_v=0.96, mu_c=1.04, mu_s=1.02, J_v=0.97),
         eff=dict(warming=dict(dRa=0.3, tau_th=40.0), field=dict(deficit=0.35, tau_f=3.0)),
         gains=(1.5, 4.0, 0.008),
         noise=dict(I_w=3.0, I_ar=2.0, I_tau=0.5, w_w=0.2, w_ar=0.2, w_tau=0.3),
         expected=[], answer="nothing or unexplained (outside the catalogue)",
         note="outside the catalogue: armature resistance warming with i^2 (R_a -> +30 % x (i/840)^2 with "
              "40 s thermal lag) and a field still building up (field switched on with the logger, 1 s before "
              "the ramp; flux, so k_i and k_b, 35 % low at t = 0, recovering with tau 3 s: 25 % low at the ramp "
              "start, 2.5 % at its end)"),
    dict(name="R05_burden_viscous", seed=805, law="paper", setup_law=None, ramp_rate=60.0, omega_ref=450.0,
         nuis=dict(m_v=1.02, mu_c=0.96, mu_s=1.05, J_v=1.04), eff=dict(burden_visc=dict(c_b=6e6)),
         gains=(2.0, 5.0, 0.01),
         noise=dict(I_w=3.0, I_ar=3.0, I_tau=0.4, w_w=0.2, w_ar=0.2, w_tau=0.3),
         expected=[], answer="nothing or unexplained (outside: viscous friction between burden and wall)",
         note="outside the catalogue: the burden's wall friction has a viscous part c_b v_rel, c_b = 6e6 N m s/rad "
              "(2.1e5 N m at the set speed; damps the burden's pendulum on the wall, zeta ~0.8); "
              "ramp 60 rpm/s to 450 rpm (stated in the setup)"),
    dict(name="R06_torque_unb_big", seed=806, law="torque", setup_law=None,
         nuis=dict(m_v=0.97, mu_c=1.02, mu_s=1.03, J_v=0.95), eff=dict(unbalance=dict(T=1.5e6, phi=0.3)),
         gains=(2.0, 5.0, 0.01),
         noise=dict(I_w=3.0, I_ar=3.0, I_tau=0.4, w_w=0.25, w_ar=0.2, w_tau=0.3),
         expected=["torque_friction_law", "kiln_unbalance"], answer="torque_friction_law + kiln_unbalance",
         note="torque-law stick-slip (the setup does not say so) + a once-per-revolution kiln torque of 1.5e6 N m "
              "(5x the usual upper end; an eccentric accretion / shell crank), phase 0.3 rad"),
    dict(name="R07_coulomb_compliance", seed=807, law="paper", setup_law=None,
         nuis=dict(m_v=1.05, mu_c=0.98, mu_s=0.96, J_v=1.02),
         eff=dict(motor_coulomb=dict(T_c=150.0, w_eps=0.02), compliance=dict(k_po=1.2e8, C_po=3e6)),
         gains=(1.5, 4.0, 0.008),
         noise=dict(I_w=3.0, I_ar=3.0, I_tau=0.4, w_w=0.2, w_ar=0.2, w_tau=0.3),
         expected=["motor_coulomb_friction", "drivetrain_compliance"],
         variants={"vs_table1_compliance": ((), None, {"compliance": {"k_po": 7.012e8, "C_po": 19.9e6}})},
         answer="motor_coulomb_friction + drivetrain_compliance",
         note="motor Coulomb friction 150 N m (above the usual 10-100; tanh over 0.02 rad/s) + a soft, lightly "
              "damped drive train at the kiln axis k_po 1.2e8 N m/rad, C_po 3e6 N m s/rad"),
    dict(name="R08_motor2_backlash", seed=808, law="paper", setup_law=None,
         nuis=dict(m_v=0.98, mu_c=1.03, mu_s=1.04, J_v=0.96),
         eff=dict(motor2=dict(J=25.0, k=4.0e4, c=450.0, gap_mm=6.0, T_f=40.0)), gains=(3.0, 4.0, 0.005),
         noise=dict(I_w=3.0, I_ar=3.0, I_tau=0.4, w_w=0.2, w_ar=0.2, w_tau=0.3),
         expected=["second_motor", "backlash"], answer="second_motor + backlash",
         variants={"vs_no_gap": ((), None, {"motor2": {"gap": 0.0}}),
                   "vs_rigid_second_motor_25": (("motor2",), {"J_m": 25.0}, None)},
         note="second, electrically isolated motor J = 25 kg m^2 on its own pinion, whose 6 mm of backlash at the "
              "girth gear is open at the start: the measured motor and kiln accelerate without it, then hit it "
              "through its pinion and coupling (4e4 N m/rad, 450 N m s/rad motor side, ~8 Hz, damping ratio ~0.3); "
              "motor 2 has 40 N m of Coulomb friction"),
    dict(name="R09_torque_motor2_coupling", seed=809, law="torque", setup_law="torque",
         nuis=dict(m_v=1.03, mu_c=0.96, mu_s=0.98, J_v=1.05),
         eff=dict(motor2=dict(J=18.0, k=2.0e4, c=40.0, gap_mm=0.0)), gains=(2.0, 5.0, 0.01),
         noise=dict(I_w=3.0, I_ar=3.0, I_tau=0.4, w_w=0.2, w_ar=0.2, w_tau=0.3),
         expected=["second_motor"], answer="second_motor",
         variants={"vs_rigid_second_motor_18": (("motor2",), {"J_m": 18.0}, None)},
         note="torque law stated; second motor J = 18 kg m^2 behind an elastic coupling (2e4 N m/rad, 40 N m s/rad "
              "motor side: a ~7 Hz mode, damping ratio ~0.1) instead of rigidly on the shaft"),
    dict(name="R10_motor2_coulomb", seed=810, law="paper", setup_law=None,
         nuis=dict(m_v=0.97, mu_c=1.04, mu_s=0.98, J_v=1.03),
         eff=dict(motor2=dict(J=20.0, k=2.0e5, c=300.0, gap_mm=0.0), motor_coulomb=dict(T_c=60.0, w_eps=0.02)),
         gains=(2.0, 5.0, 0.01),
         noise=dict(I_w=3.0, I_ar=3.0, I_tau=0.4, w_w=0.2, w_ar=0.2, w_tau=0.3),
         expected=["second_motor", "motor_coulomb_friction"], answer="second_motor + motor_coulomb_friction",
         variants={"vs_rigid_second_motor_20_with_coulomb": (("motor2",), {"J_m": 20.0}, None)},
         note="two rivals at usual magnitudes: a second motor J = 20 kg m^2 behind a stiff coupling (2e5 N m/rad, "
              "300 N m s/rad, ~19 Hz) and a motor Coulomb friction of 60 N m (tanh over 0.02 rad/s)"),
    dict(name="R11_torque_burden_viscous", seed=811, law="torque", setup_law="torque",
         nuis=dict(m_v=1.02, mu_c=0.97, mu_s=1.03, J_v=0.96), eff=dict(burden_visc=dict(c_b=1.5e6)),
         gains=(2.0, 5.0, 0.01),
         noise=dict(I_w=3.0, I_ar=3.0, I_tau=0.4, w_w=0.2, w_ar=0.2, w_tau=0.3),
         expected=[], answer="nothing or unexplained (outside: viscous friction between burden and wall)",
         note="torque law stated; outside the catalogue: the slipping burden's wall friction has a viscous part "
              "c_b v_rel, c_b = 1.5e6 N m s/rad (up to ~4e5 N m at the slip speeds of the stick-slip cycles)"),
]


def gap_rad(mm, P=TABLE1):
    return mm * 1e-3 / 3.96 * P["n"]


def plant_effects(spec, base, drop=()):
    """Effects dict for the plant (resolving the soft limit's fraction), without those in drop."""
    eff = {}
    for k, v in spec["eff"].items():
        if k in drop:
            continue
        v = dict(v)
        if k == "motor2":
            v["gap"] = gap_rad(v.pop("gap_mm"))
        if k == "soft_limit":
            free = make_plant(spec, base, drop=("soft_limit",)).simulate(T_END)
            v["I_lim"] = float(v.pop("I_lim_frac") * free["i"].max())
            v["I_peak_free"] = float(free["i"].max())
        eff[k] = v
    return eff


def make_plant(spec, base, drop=(), p_over=None, eff_over=None):
    eff = plant_effects(spec, base, drop)
    for k, v in (eff_over or {}).items():
        eff[k] = dict(eff[k], **v)
    p = dict(base, **(p_over or {}))
    return Plant(p=p, eff=eff, law=spec["law"], gains=spec["gains"],
                 ramp_rate=spec.get("ramp_rate", 74.0), omega_ref=spec.get("omega_ref", 500.0), t0=T0)


def add_noise(spec, o):
    rng = np.random.default_rng(spec["seed"])
    nz = spec["noise"]
    n = len(o["t"])
    dt = 1.0 / FS
    I = o["i"] + rng.normal(0, nz["I_w"], n) + ar1(rng, n, nz["I_ar"], nz["I_tau"], dt)
    w = o["rpm"] + rng.normal(0, nz["w_w"], n) + ar1(rng, n, nz["w_ar"], nz["w_tau"], dt)
    extra = {}
    if "ripple" in nz:
        r = nz["ripple"]
        tj = o["t"] + rng.normal(0, r["jit"], n)
        on = np.clip((o["t"] - T0) / 1.0, 0, 1)  # converter conducts from the start-up on
        I = I + on * r["A"] * np.sin(2 * math.pi * r["f"] * tj + 0.7)
    if nz.get("spikes"):
        t = 0.5
        spikes = []
        while True:
            t += rng.uniform(2.0, 6.0)
            if t > T_END - 0.5:
                break
            k = int(round(t * FS))
            a = rng.uniform(40, 180) * rng.choice([-1, 1])
            I[k] += a
            I[k + 1] += nz.get("spike_tail", 0.4) * a
            spikes.append((round(k / FS, 2), round(float(a), 1)))
            if rng.uniform() < 0.3:
                w[k] += rng.uniform(3, 8) * rng.choice([-1, 1])
        extra["spikes_t_A"] = spikes
    if nz.get("I_quant"):
        q = nz["I_quant"]
        I = np.round(I / q) * q
    return I, w, extra


def write_csv(path, spec, t, I, w, ref):
    with open(path, "w") as f:
        f.write("# red team 8 record %s: start-up of a kiln drive, logger at 50 Hz\n" % spec["name"])
        f.write("time_s,current_A,speed_rpm,speed_ref_rpm\n")
        for a, b, c, d in zip(t, I, w, ref):
            f.write("%.2f,%.2f,%.3f,%.3f\n" % (a, b, c, d))


def write_toml(path, spec):
    kp, kI, kD = spec["gains"]
    lines = ["# Setup for red team 8 record %s: the drive's gains and ramp, the rest the paper's Table 1" % spec["name"],
             "[controller]", 'gains = "given"', "k_p = %g" % kp, "k_I = %g" % kI, "k_D = %g" % kD, "",
             "[drive]", "ramp_rate = %.1f" % spec.get("ramp_rate", 74.0), "omega_ref = %.1f" % spec.get("omega_ref", 500.0),
             "", "[kiln]", "m_v = 580000.0", "mu_c = 0.4", "mu_s = 0.51"]
    if spec["setup_law"]:
        lines.append('friction_law = "%s"' % spec["setup_law"])
    open(path, "w").write("\n".join(lines) + "\n")


def vis(y_with, y_without, w_with, w_without):
    d = y_with - y_without
    return dict(rms_dI_A=round(float(np.sqrt(np.mean(d[int(T0 * FS):] ** 2))), 2),
                max_abs_dI_A=round(float(np.abs(d).max()), 1),
                fit_current_without_percent=round(fit_percent(y_with, y_without), 2),
                rms_dw_rpm=round(float(np.sqrt(np.mean((w_with - w_without)[int(T0 * FS):] ** 2))), 3),
                max_abs_dw_rpm=round(float(np.abs(w_with - w_without).max()), 2))


def make(spec, outdir, visibility=True):
    base = base_values(spec["nuis"])
    pl = make_plant(spec, base)
    o = pl.simulate(T_END)
    I, w, extra = add_noise(spec, o)
    name = spec["name"]
    write_csv(os.path.join(outdir, name + ".csv"), spec, o["t"], I, w, o["ref"])
    write_toml(os.path.join(outdir, name + ".toml"), spec)
    truth = dict(name=name, plant="red team 8 plant.py (own numpy RK4, 0.5 ms; checked with kilnctl compare)",
                 law_plant=spec["law"], law_setup=spec["setup_law"] or "paper (not stated)",
                 gains=spec["gains"], ramp_rate=spec.get("ramp_rate", 74.0), omega_ref=spec.get("omega_ref", 500.0),
                 start_s=T0, fs_Hz=FS, length_s=T_END, seed=spec["seed"], nuisance=spec["nuis"],
                 base={k: float(v) for k, v in base.items()}, effects=pl.eff, expected=spec["expected"],
                 answer=spec["answer"], note=spec["note"], noise=spec["noise"], noise_extra=extra,
                 burden_switches=len(o["events"]), peak_current_A=round(float(o["i"].max()), 1))
    truth["fit_noisefree_vs_noisy"] = dict(current=round(fit_percent(I, o["i"]), 2),
                                           speed=round(fit_percent(w, o["rpm"]), 2))
    if visibility:
        v = {}
        keys = list(spec["eff"].keys())
        if keys:
            o0 = make_plant(spec, base, drop=keys).simulate(T_END)
            v["all"] = vis(o["i"], o0["i"], o["rpm"], o0["rpm"])
            if len(keys) > 1:
                for k in keys:
                    ok = make_plant(spec, base, drop=(k,)).simulate(T_END)
                    v["without_" + k] = vis(o["i"], ok["i"], o["rpm"], ok["rpm"])
        for vname, (drop, p_over, eff_over) in spec.get("variants", {}).items():
            p_over = {k: (TABLE1[k] * spec["nuis"].get(k, 1.0) + val) for k, val in (p_over or {}).items()}
            ov = make_plant(spec, base, drop=drop, p_over=p_over, eff_over=eff_over).simulate(T_END)
            v[vname] = vis(o["i"], ov["i"], o["rpm"], ov["rpm"])
        truth["visibility"] = v
        truth["visibility_definition"] = ("noise-free record minus the same plant (same base values) without the "
                                          "effect(s): rms (after the start) and max |difference| of current and "
                                          "speed; fit_current_without_percent = kilnctl's fit % of the record's "
                                          "noise-free current by the plant without the effect")
    json.dump(truth, open(os.path.join(outdir, name + ".truth.json"), "w"), indent=1, default=float)
    np.savez(os.path.join(outdir, name + "_clean.npz"), **{k: v for k, v in o.items() if k != "events"})
    return truth


if __name__ == "__main__":
    if len(sys.argv) < 2 or sys.argv[1].startswith("-"):
        sys.exit("usage: python -m benchmarks.red8_records OUTDIR [--only R01,R08] [--no-visibility]: writes the "
                 "records' CSV, TOML and truth into OUTDIR (made if missing)")
    outdir = sys.argv[1]
    os.makedirs(outdir, exist_ok=True)
    only = None
    if "--only" in sys.argv:
        only = sys.argv[sys.argv.index("--only") + 1].split(",")
    visb = "--no-visibility" not in sys.argv
    for spec in SPECS:
        if only and not any(spec["name"].startswith(o) for o in only):
            continue
        tr = make(spec, outdir, visb)
        print(tr["name"], "peak %.0f A" % tr["peak_current_A"], "switches", tr["burden_switches"],
              json.dumps(tr.get("visibility", {})), "noisy fit", tr["fit_noisefree_vs_noisy"])
