"""Spikes of one or two samples in a record (kilnctl/measure/glitches.py): found, noted, left out.

Truths by construction: a start-up of kilnctl's generator (4 + 4 A of current noise) with spikes written into
known samples, against the same record without them; a current kick that the speed answers (a backlash impact
jolting the shaft, as in red team 8's record of a second motor meeting its gear) is no glitch.
"""

import numpy as np
import pytest

from kilnctl import Parameters
from kilnctl.measure import Measurement
from kilnctl.measure.breakaways import breakaways
from kilnctl.measure.compare import compare_run
from kilnctl.measure.glitches import glitch_mask, glitches
from kilnctl.measure.runner import run_model
from kilnctl.measure.synthetic import DEFAULT_GAINS, make_record

SPIKES = {300: (140.0, 0.4), 700: (-120.0, 0.0), 1200: (180.0, 0.4)}  # sample: (size [A], second sample's share)


@pytest.fixture(scope="module")
def record():
    m, truth = make_record((), seed=3, t_end=30.0)
    cur = m.current.copy()
    for k, (size, share) in SPIKES.items():
        cur[k] += size
        cur[k + 1] += share * size
    spiked = Measurement.from_arrays(m.t, cur, m.speed, m.speed_ref)
    return m, spiked, truth


def test_spikes_of_one_and_two_samples_are_found_and_noted(record):
    clean, spiked, _ = record
    assert clean.glitches == ()
    found = {g.peak: g for g in spiked.glitches}
    assert sorted(found) == sorted(SPIKES)
    for k, (size, share) in SPIKES.items():
        assert found[k].at == ((k, k + 1) if share else (k,))
        assert found[k].size == pytest.approx(size, abs=15.0)  # the neighbours' median is noise from the true level
    (note,) = [n for n in spiked.notes if "spike" in n]
    assert note.startswith("column 'current_A': 3 isolated spike(s) of one or two samples (2 of two)")
    assert "Their 5 sample(s) are left out of fits, evidence and fit %" in note
    # the record's own step (make_record samples at 50 Hz), not another record's (the note had said "a backlash
    # impact sampled at 10 Hz" on red team 17's 100 Hz record)
    assert "shorter than the sample step of 20 ms (a backlash's impact lasts a few milliseconds)?" in note
    kept = spiked.kept
    assert kept.sum() == spiked.n - 5 and not kept[[300, 301, 700, 1200, 1201]].any()


def test_left_out_of_the_fit_percent(record):
    # the plant's own model compared with the record: over the kept samples the spiked record scores what the
    # clean one scores there (the spikes are the only difference), and within 0.1 point of the clean record's whole
    clean, spiked, truth = record
    plant = Parameters(DEFAULT_GAINS).replace(**truth["plant"])
    exp = clean.experiment(plant)
    run = run_model(plant, clean, exp)
    a = compare_run(clean, run, exp).channels["current_A"].fit
    b = compare_run(spiked, run, exp).channels["current_A"].fit
    assert b == pytest.approx(a, abs=0.1)


def test_a_kick_the_speed_answers_is_no_glitch(record):
    clean, _, _ = record
    cur, w = clean.current.copy(), clean.speed.copy()
    cur[500] += 500.0
    cur[501] += 250.0
    w[500:506] += np.array([-6.0, -2.0, 2.0, 1.5, 1.0, 0.5])  # the shaft jolted and back, over five samples
    m = Measurement.from_arrays(clean.t, cur, w, clean.speed_ref)
    assert m.glitches == ()
    # the same kick with the speed left alone is a glitch
    m2 = Measurement.from_arrays(clean.t, cur, clean.speed, clean.speed_ref)
    assert [g.at for g in m2.glitches] == [(500, 501)]


def test_a_kick_with_the_speed_jolted_in_its_own_sample_is_no_glitch(record):
    """Truth by construction, after red team 21's rigid teeth meeting (four impacts within 70 ms at 50 Hz: +374 A
    and the speed 6 rpm down in the same sample, back above its line in the next): the speed leaping against
    the current's spike in the spike's own sample is the shaft jolted within a sample step, not interference.
    The same leap with the current's sign (both up) is no jolt (a speed that rises lowers the current): a
    glitch."""
    from kilnctl.measure.glitches import JOLT_SIGMAS, _noise_sigma

    clean, _, _ = record
    cur, w = clean.current.copy(), clean.speed.copy()
    leap = 1.5 * JOLT_SIGMAS * _noise_sigma(clean.speed)  # 4.6 rpm here (red team 21's: 6.4 rpm, 19 sigma)
    cur[500] += 370.0
    w[500] -= leap
    w[501] += 0.3 * leap
    m = Measurement.from_arrays(clean.t, cur, w, clean.speed_ref)
    assert m.glitches == ()
    w[500] += 2.0 * leap  # now up with the current
    w[501] = clean.speed[501]
    m2 = Measurement.from_arrays(clean.t, cur, w, clean.speed_ref)
    assert [(g.channel, g.at) for g in m2.glitches] == [("current_A", (500,))]


def test_spikes_are_no_stick_slip_falls(record):
    # a spike falls back as sharply as a breakaway; read across its samples there are none (the record is the
    # paper's friction law: no stick-slip at the set speed)
    _, spiked, _ = record
    exp = spiked.experiment(Parameters(DEFAULT_GAINS))
    act = spiked.t >= exp.t0
    keep = glitch_mask(glitches(spiked.channels), spiked.n)[act]
    assert breakaways(spiked.t[act], spiked.current[act], t_from=exp.steady_from).size >= 1
    assert breakaways(spiked.t[act], spiked.current[act], t_from=exp.steady_from, keep=keep).size == 0


def test_three_samples_are_an_event_not_a_glitch(record):
    # truth by construction: a bump of three samples (150, 120, 90 A) is wider than a glitch of one or two
    clean, _, _ = record
    cur = clean.current.copy()
    cur[600:603] += np.array([120.0, 150.0, 90.0])
    m = Measurement.from_arrays(clean.t, cur, clean.speed, clean.speed_ref)
    assert m.glitches == ()
