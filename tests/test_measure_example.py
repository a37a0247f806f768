"""The shipped example record: readable, aligned, and failing where its hidden effect acts."""

import pytest

from kilnctl.measure import Calibration, compare, example_paths, load_setup, read_csv


def test_example_record_reads_and_fails_on_the_ramp():
    rec_path, setup_path = example_paths()
    setup = load_setup(setup_path)
    rec = read_csv(rec_path, setup.params)
    assert rec.n == 2050 and setup.params.gains == "given"
    cal = Calibration(setup.params, ["mu_c", "m_v"]).fit(rec)
    c = compare(rec, cal.params_)
    # truth (synthetic/write_example): the ramp starts after 1 s of pre-trigger samples
    assert c.experiment.t0 == pytest.approx(1.0, abs=0.01)
    # truth: the plant has a second motor (21.5 kg m^2): the current is above the model during the ramp
    ramp = [f for f in c.failing if f["channel"] == "current_A" and f["t_start"] < 3.0]
    assert ramp and ramp[0]["mean_residual"] > 0 and ramp[0]["t_end"] > 6.0
