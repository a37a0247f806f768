"""Red team 8's independent plant and records (benchmarks/red8_plant.py, benchmarks/red8_records.py).

The plant was written apart from kilnctl (numpy RK4, its own stick-slip and limiter code).  Truths: kilnctl's
model at the record's true values (a second plant of the same physics), and the spikes the red team wrote into
its record (their times and sizes, in its truth file).
"""

import json

import numpy as np
import pytest

from benchmarks import red8_records as rr
from kilnctl.measure import load_setup, read_record
from kilnctl.simulate import simulate


def _spec(name):
    return next(s for s in rr.SPECS if s["name"] == name)


def test_the_pi_limiter_is_the_red_teams_soft_limit(tmp_path):
    """R03: the torque law and a PI current limiter at 0.92 of the unlimited peak (k_p 0.05 V/A, k_i 5 V/(A s),
    integrator >= 0, speed integrator frozen while it acts), written by the red team.  kilnctl's
    ``current_limit_pi`` at the same values follows its noise-free current to 0.03 A rms (measured when
    written); the clamp at the same I_max misses by 35 A rms."""
    spec = _spec("R03_torque_softlimit")
    truth = rr.make(spec, str(tmp_path), visibility=False)
    clean = np.load(tmp_path / "R03_torque_softlimit_clean.npz")
    sl = truth["effects"]["soft_limit"]
    p = load_setup(str(tmp_path / "R03_torque_softlimit.toml")).params.replace(
        **truth["base"], I_max=sl["I_lim"], k_pl=sl["kp"], k_il=sl["ki"])
    t = clean["t"]
    on = t >= rr.T0
    for effects, lo, hi in ((("current_limit_pi",), 0.0, 0.2), ((), 20.0, np.inf)):
        r = simulate(p, "macro", float(t[-1] - rr.T0), effects=effects, dt=0.02)
        model = np.interp(t[on] - rr.T0, r.t, r.outputs["i_a"])
        rms = float(np.sqrt(np.mean((model - clean["i"][on]) ** 2)))
        assert lo <= rms < hi, (effects, rms)


def test_the_spikes_written_into_the_record_are_found_and_an_impact_is_not(tmp_path):
    """R01: two-sample spikes of 41-174 A (the second sample 40 % of the first), at times the truth file lists;
    every one above 90 A (20 noise standard deviations of this record's current is about 70 A) is found at its
    time, and nothing else.  R08: a second motor meeting its gear, a +585 A impact over two samples that the
    speed answers, is kept."""
    rr.make(_spec("R01_nothing_spikes"), str(tmp_path), visibility=False)
    truth = json.load(open(tmp_path / "R01_nothing_spikes.truth.json"))
    m = read_record(str(tmp_path / "R01_nothing_spikes.csv"),
                    load_setup(str(tmp_path / "R01_nothing_spikes.toml")).params)
    big = sorted(t for t, a in truth["noise_extra"]["spikes_t_A"] if abs(a) > 90.0)
    found = sorted(float(m.t[g.peak]) for g in m.glitches if g.channel == "current_A")
    assert found == pytest.approx(big, abs=0.021)
    assert all(len(g.at) == 2 for g in m.glitches if g.channel == "current_A")
    rr.make(_spec("R08_motor2_backlash"), str(tmp_path), visibility=False)
    m8 = read_record(str(tmp_path / "R08_motor2_backlash.csv"),
                     load_setup(str(tmp_path / "R08_motor2_backlash.toml")).params)
    assert m8.glitches == () and np.max(m8.current) > 1000.0
