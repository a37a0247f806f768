"""A logged channel clipped at the end of its range: found on reading, and its clipped samples left out."""

import numpy as np
import pytest

from kilnctl import Parameters
from kilnctl.errors import DataError
from kilnctl.measure import Measurement
from kilnctl.measure.calibrate import Calibration, holdout_masks
from kilnctl.measure.clipping import clipped_levels
from kilnctl.measure.compare import compare_run
from kilnctl.measure.runner import run_model
from kilnctl.measure.stats import fit_percent
from kilnctl.measure.synthetic import DEFAULT_GAINS, make_record

SETUP = Parameters(DEFAULT_GAINS)


@pytest.fixture(scope="module")
def record():
    """A noisy 20 s start-up of kilnctl's own plant (white and coloured noise of 4 A and 0.3 rpm)."""
    m, _ = make_record(seed=4, t_end=20.0, mismatch=())
    return m


def _with_current(m, current):
    return Measurement.from_arrays(m.t, current, m.speed, m.speed_ref, params=SETUP)


def test_a_current_clipped_at_its_converter_range_is_found_and_its_samples_named(record):
    # truth by construction: the current clipped at 95 % of its peak, every sample at or above the level
    # counted by hand
    level = round(0.95 * float(record.current.max()), 3)
    m = _with_current(record, np.minimum(record.current, level))
    n_at = int(np.sum(record.current >= level))
    assert n_at >= 20
    assert len(m.clipped) == 1
    c = m.clipped[0]
    assert (c.channel, c.side, c.level, c.n) == ("current_A", "upper", level, n_at)
    assert np.array_equal(m.unclipped, record.current < level)
    note = next(n for n in m.notes if "clipped" in n)
    assert f"{n_at} samples" in note and f"{level:.6g} A" in note and "leave those samples out" in note
    # the record as measured, and the same one on a coarse converter's 10 A steps, are not clipped
    assert record.clipped == ()
    assert _with_current(record, 10.0 * np.round(record.current / 10.0)).clipped == ()


def test_a_record_without_noise_that_settles_at_one_value_is_not_clipped():
    # truth (the rule's premise): measured noise never repeats a value; a record without noise, logged to
    # 0.01 A and 0.01 rpm, holds its settled speed and current exactly, which is no clipped range
    m, _ = make_record(seed=4, t_end=20.0, mismatch=(), white=(0.0, 0.0), coloured=(0.0, 0.0))
    arrays = {"current_A": np.round(m.current, 2), "speed_rpm": np.round(m.speed, 2)}
    assert np.max(np.unique(arrays["speed_rpm"], return_counts=True)[1]) >= 10
    assert clipped_levels(arrays, SETUP.I_max) == []
    # nor is a current held at the drive's own limit I_max
    flat = np.minimum(m.current + np.random.default_rng(1).normal(0, 4.0, m.n), SETUP.I_max)
    flat[100:160] = SETUP.I_max
    assert clipped_levels({"current_A": flat}, SETUP.I_max) == []
    assert clipped_levels({"current_A": flat}, 2 * SETUP.I_max)[0].level == SETUP.I_max


def test_clipped_samples_are_left_out_of_fits_evidence_and_fit_percent(record):
    # truth (a second route): the calibration of the clipped record equals that of the unclipped record with
    # the same samples left out by a hand-made mask; the hold-out parts hold none of them; the comparison's
    # fit % is the one computed by hand over the samples not clipped
    level = round(0.95 * float(record.current.max()), 3)
    clipped = _with_current(record, np.minimum(record.current, level))
    keep = record.current < level
    kw = dict(parameters=("mu_c", "m_v"), max_nfev=8, scales={"current_A": 100.0, "speed_rpm": 10.0})
    a = Calibration(SETUP, **kw).fit(clipped)
    b = Calibration(SETUP, **kw).fit(record, mask=keep)
    for name in ("mu_c", "m_v"):
        assert a.values_[name] == pytest.approx(b.values_[name], rel=1e-9)
    assert a.n_ == b.n_
    train, test = holdout_masks(clipped)
    assert not np.any((train | test) & ~keep) and np.array_equal(train | test, keep)
    exp = clipped.experiment(SETUP)
    run = run_model(a.params_, clipped, exp)
    comp = compare_run(clipped, run, exp)
    active = clipped.t >= exp.t0 - 1e-9
    ok = keep[active]
    assert comp.channels["current_A"].fit == pytest.approx(
        fit_percent(clipped.current[active][ok], run.outputs["current_A"][ok]), rel=1e-12)
    assert np.all(comp.channels["current_A"].residual[~ok] == 0.0)


def test_a_record_clipped_almost_everywhere_is_refused_with_the_column_named(record):
    level = float(np.quantile(record.current, 0.04))  # 40 of 1001 samples below it, at rest and on the early ramp
    with pytest.raises(DataError, match=r"column 'current_A' at .*fewer than 50 samples .*wider range"):
        _with_current(record, np.minimum(record.current, level))


def test_a_converter_off_at_rest_is_no_clipped_range(record):
    # truth by construction: the current reads exactly 0 A on the 40 samples at rest before the start (a
    # converter that is off), its smallest value and held 40 times; that stretch from the first sample is not
    # a clipped range, while the same zeros in the middle of the running record would be
    cur = record.current.copy()
    cur[:40] = 0.0
    assert cur.min() == 0.0 and np.sum(cur == 0.0) == 40
    assert clipped_levels({"current_A": cur}, SETUP.I_max) == []
    moved = np.roll(cur, 400)
    (c,) = clipped_levels({"current_A": moved}, SETUP.I_max)
    assert (c.side, c.level, c.n) == ("lower", 0.0, 40)


def test_a_speed_counted_in_steps_that_holds_its_set_point_is_not_clipped(record):
    # truth (red team 13's enc_B): an encoder counted over each sample reads the speed in whole steps; while the
    # speed's ripple stays inside one step it reads the set point exactly, on most of the record.  That is the
    # speed loop holding 500 rpm, not a logger's range: nothing is left out, and the staircase of the ramp is
    # no "noise-free straight ramp" of a reference.  A speed cut below its set point is still clipped.
    m, _ = make_record(seed=4, t_end=40.0, mismatch=(), white=(4.0, 0.0), coloured=(4.0, 0.0))
    steps = 2.0 * np.round(m.speed / 2.0)
    counted = Measurement.from_arrays(m.t, m.current, steps, m.speed_ref, params=SETUP)
    at_top = np.mean(steps == steps.max())
    assert steps.max() == SETUP.omega_ref and at_top > 0.6, at_top  # seen: 0.805 of the record at 500 rpm
    assert counted.clipped == () and counted.unclipped.all()
    assert not any("noise-free straight ramp" in n for n in counted.notes)
    assert any("logged in steps of 2 rpm" in n for n in counted.notes)
    # without a logged reference the setup's set speed says the same
    assert clipped_levels({"speed_rpm": steps}, SETUP.I_max, (SETUP.omega_ref,)) == []
    # a logger's range of 480 rpm, below the set point, is a clipped range
    cut = np.minimum(record.speed, 480.0)
    (c,) = clipped_levels({"speed_rpm": cut}, SETUP.I_max, (SETUP.omega_ref,))
    assert (c.channel, c.level) == ("speed_rpm", 480.0)
