"""Residual statistics, compare and calibrate, each checked against an independent truth."""

import argparse
import json
import math

import numpy as np
import pytest

from kilnctl import Parameters
from kilnctl.errors import KilnctlError, NotFittedError
from kilnctl.measure import Measurement
from kilnctl.measure.calibrate import Calibration, _covariance, bic, holdout_masks
from kilnctl.measure.compare import compare
from kilnctl.measure.stats import autocorr, crosscorr, failing_intervals, fit_percent, residual_spectrum
from kilnctl.simulate import simulate

GIVEN = Parameters(gains="given", k_p=2.0, k_I=5.0, k_D=0.01)
T_END = 24.0
FS = 50.0


def _sampled(resp, t):
    tt, idx = np.unique(resp.t, return_index=True)
    return {k: np.interp(t, tt, np.asarray(resp.outputs[k])[idx]) for k in ("i_a", "speed_rpm", "speed_ref_rpm")}


def _record(params, effects=(), noise=(5.0, 0.3), seed=0):
    t = np.arange(0, T_END, 1 / FS)
    y = _sampled(simulate(params, "macro", t_end=T_END, effects=effects), t)
    rng = np.random.default_rng(seed)
    return Measurement.from_arrays(t, y["i_a"] + noise[0] * rng.standard_normal(t.size),
                                   y["speed_rpm"] + noise[1] * rng.standard_normal(t.size), y["speed_ref_rpm"])


# --- statistics -------------------------------------------------------------------
def test_fit_percent_by_hand():
    # hand: ||y - yhat|| = 1, ||y - mean y|| = sqrt(2.25 + 0.25 + 0.25 + 2.25) = sqrt(5)
    assert fit_percent([1, 2, 3, 4], [1, 2, 3, 5]) == pytest.approx(100 * (1 - 1 / math.sqrt(5)))
    assert fit_percent([1, 2, 3], [1, 2, 3]) == 100.0
    assert fit_percent([1, 2, 3], [2, 2, 2]) == pytest.approx(0.0)  # the mean scores 0


def test_whiteness_of_true_white_noise_and_of_coloured_noise():
    rng = np.random.default_rng(1)
    e = rng.standard_normal(20000)
    w = autocorr(e, 100)
    # truth: white noise leaves about 1 % of lags outside the 99 % band (binomial: P(>6 of 100) < 0.1 %)
    assert w["band"] == pytest.approx(2.5758 / math.sqrt(20000), rel=1e-4)
    assert w["n_outside"] <= 6
    ar = np.zeros_like(e)
    for k in range(1, e.size):
        ar[k] = 0.9 * ar[k - 1] + e[k]
    wa = autocorr(ar, 100)
    # truth: AR(1) autocorrelation 0.9^k: lags up to ~log(0.02)/log(0.9) = 37 are far outside
    assert wa["n_outside"] > 30 and wa["r"][1] == pytest.approx(0.9, abs=0.02)


def test_crosscorr_independent_and_delayed():
    rng = np.random.default_rng(2)
    u = rng.standard_normal(5000)
    e = rng.standard_normal(5000)
    assert crosscorr(e, u, 50)["n_outside"] <= 4
    d = np.roll(u, 7)  # e lags u by 7 samples: peak at lag +7
    c = crosscorr(d, u, 20)
    assert c["lags"][int(np.argmax(c["r"]))] == 7


def test_spectrum_finds_the_burden_frequency():
    # truth: a 0.34 Hz sine (the paper's burden pendulum, eq. 25) in white noise
    t = np.arange(0, 60, 0.02)
    rng = np.random.default_rng(3)
    s = residual_spectrum(10 * np.sin(2 * np.pi * 0.34 * t) + rng.standard_normal(t.size), 50.0, seconds=20)
    assert s["dominant_hz"] == pytest.approx(0.34, abs=0.05) and s["peak_ratio"] > 100


def test_failing_interval_found_where_the_bump_is():
    t = np.arange(0, 20, 0.02)
    rng = np.random.default_rng(4)
    e = rng.standard_normal(t.size)
    e[(t >= 2) & (t < 4)] += 30.0
    iv = failing_intervals(t, e)
    assert len(iv) == 1
    a, b = iv[0]
    assert t[a] == pytest.approx(2.0, abs=0.05) and t[b] == pytest.approx(3.98, abs=0.05)


def test_bic_by_hand():
    # hand: 100 ln(4/100) + 50 ln(1/50) + 2 ln(150)
    v = bic({"a": 4.0, "b": 1.0}, {"a": 100, "b": 50}, 2)
    assert v == pytest.approx(100 * math.log(0.04) + 50 * math.log(0.02) + 2 * math.log(150))


def test_covariance_of_a_linear_fit():
    # truth: ordinary least squares, cov = s^2 (X^T X)^-1, the sandwich with the meat of white noise s^2 X^T X
    rng = np.random.default_rng(5)
    X = rng.standard_normal((200, 3))
    cov, singular = _covariance(X, 0.25 * X.T @ X, np.eye(3))
    assert np.allclose(cov, 0.25 * np.linalg.inv(X.T @ X)) and not singular.any()
    X[:, 2] = X[:, 1]  # two identical columns: not identifiable
    _, singular = _covariance(X, 0.25 * X.T @ X, np.eye(3))
    assert singular[1] and singular[2] and not singular[0]


def test_holdout_blocks_cover_every_phase():
    t = np.arange(0, 30, 0.02)
    m = Measurement.from_arrays(t, 100 + t, np.minimum(74 * t, 500))
    train, test = holdout_masks(m, "blocks", 0.3)
    assert not (train & test).any() and (train | test).all()
    assert 0.25 < test.mean() < 0.4 and test[t < 7].any()  # part of the ramp is held out
    train, test = holdout_masks(m, "tail", 0.3)
    assert t[test].min() == pytest.approx(21.0, abs=0.05)


# --- compare ----------------------------------------------------------------------
def test_compare_fit_matches_a_hand_computation_and_finds_the_ramp_failure():
    m = _record(GIVEN, effects=("second_motor",))
    c = compare(m, GIVEN)
    # independent: the base model sampled by hand, fit % computed by hand
    y = _sampled(simulate(GIVEN, "macro", t_end=T_END), m.t)
    hand = 100 * (1 - np.linalg.norm(m.current - y["i_a"]) / np.linalg.norm(m.current - m.current.mean()))
    assert c.fit["current_A"] == pytest.approx(hand, abs=0.05)
    # truth: J_m2 = 21.5 kg m^2 at 74 rpm/s = 7.75 rad/s^2 needs 167 N m = 36 A more during the ramp (0-6.76 s)
    fails = [f for f in c.failing if f["channel"] == "current_A"]
    assert fails and fails[0]["t_start"] < 0.5 and 6.0 < fails[0]["t_end"] < 7.5
    assert fails[0]["mean_residual"] == pytest.approx(36.2, abs=6)
    assert "model low" in fails[0]["text"] and "ramp" in fails[0]["text"]
    json.dumps(c.to_dict(), allow_nan=False)


def test_compare_of_the_true_model_leaves_white_residuals():
    m = _record(GIVEN, noise=(5.0, 0.3), seed=7)
    c = compare(m, GIVEN)
    for ch in c.channels.values():
        # truth: the residual is the white noise added, so ~1 % of lags fall outside the 99 % band
        assert ch.whiteness["fraction_outside"] < 0.05
        assert not ch.failing


@pytest.mark.parametrize("channel, factor", [("current_A", 1 / 16.0), ("speed_rpm", 0.2)])
def test_a_column_in_other_units_gets_a_caution_that_names_the_factor(channel, factor):
    # truth: the record of the model itself, one column then logged in other units (a current in per cent of a
    # 1600 A rating; a speed in per cent of a rated 500 rpm), so the model spans 1/factor times the
    # record.  (kA, a speed in rad/s or at the kiln shell: refused when the record is read.)
    m = _record(GIVEN, effects=("second_motor",))
    assert compare(m, GIVEN).cautions == []  # an effect missing from the model is not a unit slip
    cur = m.current * factor if channel == "current_A" else m.current
    spd = m.speed * factor if channel == "speed_rpm" else m.speed
    c = compare(Measurement.from_arrays(m.t, cur, spd, m.speed_ref), GIVEN)
    assert len(c.cautions) == 1 and c.cautions[0].startswith(f"{channel}: fit ")
    spans = float(c.cautions[0].split("signal spans ")[1].split(" times")[0])
    assert spans == pytest.approx(1 / factor, rel=0.15)
    assert "unit" in c.cautions[0]
    assert c.to_dict()["cautions"] == c.cautions
    assert any(line.startswith("  caution: ") for line in c.summary_lines())


def test_compare_cli_json(tmp_path, capsys):
    from kilnctl.cli import compare_cmd

    m = _record(GIVEN, effects=("second_motor",))
    data = tmp_path / "rec.csv"
    m.to_csv(data)
    cfg = tmp_path / "setup.toml"
    cfg.write_text('[controller]\ngains = "given"\nk_p = 2.0\nk_I = 5.0\nk_D = 0.01\n')
    ap = argparse.ArgumentParser()
    compare_cmd.register(ap.add_subparsers())
    args = ap.parse_args(["compare", "--data", str(data), "--config", str(cfg), "--effects", "second_motor",
                          "--json", "--report", str(tmp_path / "rep")])
    assert args.func(args) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["effects"] == ["second_motor"] and d["fit_percent"]["current_A"] > 95
    html = (tmp_path / "rep" / "compare.html").read_text()
    assert "data:image/png;base64," in html
    # how the file was read goes into the report files too (red team 7: on the terminal only); truth: two rows
    # cut out of the record by hand, which the reader notes as missing samples
    rows = data.read_text().splitlines(keepends=True)
    k = next(i for i, r in enumerate(rows) if r[:1].isdigit()) + 500
    (tmp_path / "gap.csv").write_text("".join(rows[:k] + rows[k + 2:]))
    args = ap.parse_args(["compare", "--data", str(tmp_path / "gap.csv"), "--config", str(cfg), "--json",
                          "--report", str(tmp_path / "rep2")])
    assert args.func(args) == 0
    capsys.readouterr()
    notes = json.loads((tmp_path / "rep2" / "compare.json").read_text())["record_notes"]
    assert any("missing samples" in n for n in notes)
    assert "Note: record: " in (tmp_path / "rep2" / "compare.html").read_text()


# --- calibrate ---------------------------------------------------------------------
def test_calibration_recovers_the_generating_parameters():
    truth = GIVEN.replace(mu_c=0.37, m_v=620e3)
    m = _record(truth, seed=11)
    cal = Calibration(GIVEN, ["mu_c", "m_v"]).fit(m)
    # truth: the values used to generate the record
    assert cal.values_["mu_c"] == pytest.approx(0.37, rel=0.01)
    assert cal.values_["m_v"] == pytest.approx(620e3, rel=0.01)
    for k, v in (("mu_c", 0.37), ("m_v", 620e3)):
        assert abs(cal.values_[k] - v) < 5 * cal.stderr_[k]
    assert cal.fit_percent_["current_A"] > 97 and not cal.on_bound_
    assert cal.score() > 95


def test_mu_s_is_not_identifiable_under_the_papers_law():
    # truth (NOTES): with the printed law, breakaway at tan(psi) = mu_s is followed at once by the held
    # (Filippov) mode until the kinetic angle tan(psi) = mu_c R / L, so mu_s below mu_c R/L = 0.64 leaves
    # no trace in the current
    m = _record(GIVEN.replace(mu_s=0.55), seed=12)
    cal = Calibration(GIVEN, ["mu_c", "mu_s"]).fit(m)
    assert "mu_s" in cal.not_identifiable_


def test_unfitted_calibration_refuses_to_predict():
    with pytest.raises(NotFittedError, match="fit"):
        Calibration(GIVEN).predict()


def test_best_step_against_brute_force():
    # truth: a step of +3 at t = 6.2 s in noise, and the same fit by a brute-force least-squares solve at every split
    from kilnctl.measure.stats import best_step

    rng = np.random.default_rng(2)
    t = np.arange(0.0, 10.0, 0.02)
    e = 0.5 + 3.0 * (t >= 6.2) + 0.3 * rng.standard_normal(t.size)
    s = best_step(t, e, t_min=2.0, t_max=9.0)
    brute = []
    for k in range(3, t.size - 2):
        if not 2.0 <= t[k] <= 9.0:
            continue
        X = np.column_stack([np.ones(t.size), (np.arange(t.size) >= k).astype(float)])
        beta, *_ = np.linalg.lstsq(X, e, rcond=None)
        brute.append((float(np.sum((e - X @ beta) ** 2)), t[k], beta[1]))
    rss, tk, size = min(brute)
    assert s["t"] == pytest.approx(tk) and s["t"] == pytest.approx(6.2, abs=0.05)
    assert s["rss"] == pytest.approx(rss, rel=1e-9) and s["size"] == pytest.approx(size, rel=1e-9)
    assert s["rss_constant"] == pytest.approx(float(np.sum((e - e.mean()) ** 2)), rel=1e-12)
    assert best_step(t, e, t_min=20.0) is None  # no allowed step time


def test_time_limit_ends_the_fit_at_the_best_values_found_even_in_a_thread():
    # truth: with a budget smaller than one simulation no trial after the first can run, so the fit must return
    # the values it started from (a signal-based limit could not run in a thread at all); without a budget the
    # same fit moves to the generating value mu_c = 0.37
    from concurrent.futures import ThreadPoolExecutor

    m = _record(GIVEN.replace(mu_c=0.37), seed=13)

    def fit(limit):
        return Calibration(GIVEN, ["mu_c"], time_limit_s=limit).fit(m, init={"mu_c": 0.40}, starts=[], n_local=1)

    with ThreadPoolExecutor(max_workers=1) as ex:
        cut = ex.submit(fit, 1e-6).result()
    assert cut.values_["mu_c"] == pytest.approx(0.40, rel=1e-9)
    assert cut.n_failed_ >= 1
    full = fit(None)
    assert full.values_["mu_c"] == pytest.approx(0.37, rel=0.01)
    assert full.cost_ < cut.cost_


def test_strategies_schedule_horizons_and_widths():
    # truth: the documented schedules, by hand
    from kilnctl.measure.calibrate import Horizons, Smoothing, Starts

    assert Horizons((0.5, 0.3)).schedule() == [0.3, 0.5, 1.0]
    sm = Smoothing((0.1, 0.4), later_s=(0.1,))
    assert sm.schedule() == [0.4, 0.1, 0.0]
    assert sm.schedule(first=False, last=False) == [0.1]
    assert Smoothing().schedule(first=False, last=False) == [0.0]
    u = [np.array([0.0]), np.array([0.5]), np.array([3.0]), np.array([0.6])]
    # the given point, the best of the rest however close (0.5), then the next that lies apart (3.0, not 0.6)
    assert [float(x[0]) for x in Starts(None, 3, 1.0).choose(u, [9.0, 1.0, 3.0, 2.0])] == [0.0, 0.5, 3.0]
    # a grid point equal to the given one is not chosen again (its local fit would repeat the given one's):
    # the best of the rest is then the next point, 0.5
    u2 = [np.array([0.0]), np.array([0.0]), np.array([0.5]), np.array([3.0])]
    assert [float(x[0]) for x in Starts(None, 3, 1.0).choose(u2, [9.0, 1.0, 2.0, 3.0])] == [0.0, 0.5, 3.0]


def test_starts_spread_over_decades_add_the_best_point_of_each_decade_not_covered():
    # truth: the documented rule, by hand.  The given point 3e9 (decade 9) and the best by cost, 1e9, are chosen
    # as without a spread; the spread adds the best point of each other decade: 2e10 (cost 2) and, in decade 7,
    # 5e7 (cost 3) rather than 2e7 (cost 8)
    from kilnctl.measure.calibrate import Starts

    pts = [{"k_po": 3e9}, {"k_po": 2e7}, {"k_po": 1e9}, {"k_po": 2e10}, {"k_po": 5e7}]
    u = [np.array([np.log(p["k_po"])]) for p in pts]
    costs = [9.0, 8.0, 1.0, 2.0, 3.0]
    plain = Starts(None, 2, 1.0)
    assert plain.decades(pts) is None
    assert [float(np.exp(x[0])) for x in plain.choose(u, costs)] == pytest.approx([3e9, 1e9])
    spread = Starts(None, 2, 1.0, spread="k_po")
    assert spread.decades(pts) == [9, 7, 9, 10, 7]
    assert spread.decades([{"k_po": 0.0}, {}]) == [None, None]
    chosen = spread.choose(u, costs, spread.decades(pts))
    assert [float(np.exp(x[0])) for x in chosen] == pytest.approx([3e9, 1e9, 2e10, 5e7])


def test_report_folder_below_a_file_is_refused_before_the_work(tmp_path, capsys, monkeypatch):
    """``--report`` (compare, diagnose) and ``--out`` (split-startups) below a file: a clear error, before any work.

    Truth: the file system; no folder can be made below a file (the run ended in a NotADirectoryError traceback
    after the work).  Reading the record is replaced by a function that fails the test: the refusal comes before it.
    """
    from kilnctl.cli import main
    from kilnctl.measure import example_paths

    data = tmp_path / "rec.csv"
    data.write_bytes(example_paths()[0].read_bytes())
    monkeypatch.setattr("kilnctl.measure.io.read_record", lambda *a, **k: pytest.fail("the record was read"))
    for argv in (["compare", "--data", str(data), "--report", str(data / "rep")],
                 ["diagnose", "--data", str(data), "--report", str(data / "rep" / "deeper")],
                 ["split-startups", str(data), "--out", str(data / "records")]):
        assert main(argv) == 2
        err = capsys.readouterr().err
        assert f"{data} is a file, so no folder can be made below it" in err and "Traceback" not in err


def test_a_report_file_that_cannot_be_written_is_a_clear_error(tmp_path, monkeypatch):
    """A write that fails (full disk, read-only folder) ends in a ConfigFileError naming the folder and file.

    Truth: the OSError the test makes the writer raise (ENOSPC); before, it reached the user as a traceback.
    """
    import errno

    from kilnctl.errors import ConfigFileError
    from kilnctl.measure import report

    def full(path, data):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(report, "write_atomic", full)
    with pytest.raises(ConfigFileError, match=r"--report .*rep: cannot write a.json \(No space left on device\)"):
        report.write_report_files(tmp_path / "rep", {"a.json": {"x": 1}})


def test_report_folder_holding_an_input_of_a_report_name_is_refused_before_the_work(tmp_path, capsys, monkeypatch):
    """``--report DIR`` where the ``--data`` file is ``DIR/diagnose.json`` or ``DIR/compare.json``: the report would
    overwrite it (the writer refused that only after the work).

    Truth: the names the report writes (``<command>.html``, ``<command>.json``); reading the record is replaced by a
    function that fails the test, so the refusal must come before it, and the input must be untouched.
    """
    from kilnctl.cli import main
    from kilnctl.measure import example_paths

    raw = example_paths()[0].read_bytes()
    monkeypatch.setattr("kilnctl.measure.io.read_record", lambda *a, **k: pytest.fail("the record was read"))
    for command in ("compare", "diagnose"):
        data = tmp_path / f"{command}.json"
        data.write_bytes(raw)
        assert main([command, "--data", str(data), "--report", str(tmp_path)]) == 2
        err = capsys.readouterr().err
        assert f"holds the --data file {command}.json, which the report would overwrite" in err
        assert "Traceback" not in err and data.read_bytes() == raw


def test_a_failing_interval_is_said_by_its_largest_miss():
    """Truth: a constructed speed record at 500 rpm with a dip of 90 rpm (cosine-shaped, 19-21 s) that the model
    (500 rpm throughout) lacks.  The measured signal's extreme in the interval is its edge (about 500 rpm), so
    the sentence gives the largest miss instead: 90 rpm at 20.00 s, measured 410 rpm, model 500 rpm."""
    from kilnctl.measure.compare import _describe

    t = np.arange(0.0, 40.0, 0.02)
    dip = np.where(np.abs(t - 20.0) < 1.0, 45.0 * (1.0 + np.cos(np.pi * (t - 20.0))), 0.0)
    y, yhat = 500.0 - dip, np.full(t.size, 500.0)
    e = y - yhat
    (a, b), = failing_intervals(t, e + 0.01 * np.random.default_rng(0).standard_normal(t.size))
    d = _describe(t, y, yhat, e, a, b, "rpm", [{"name": "hold", "t_start": 10.0, "t_end": 40.0}])
    assert d["t_worst"] == pytest.approx(20.0) and d["measured_worst"] == pytest.approx(410.0)
    assert d["measured_peak"] > 490.0  # the edge: what the sentence gave before
    assert "model high by" in d["text"]
    assert "by 90.0 rpm at 20.00 s (measured 410.0 rpm, model 500.0 rpm)" in d["text"]


def test_a_largest_miss_on_the_other_side_of_the_mean_is_named_with_its_own_side():
    """Red team 6's soft backlash: "model high by 4 A on average, by 300 A at 2.32 s (measured 358 A, model 58 A)"
    where the model is 300 A *low* there.  Truth: a constructed current the model overshoots by 20 A over 2-6 s
    except for a 0.2 s spike of +300 A the model lacks (the mean over the interval stays below zero)."""
    from kilnctl.measure.compare import _describe

    t = np.arange(0.0, 10.0, 0.02)
    yhat = np.full(t.size, 400.0)
    y = yhat - 20.0 * ((t >= 2.0) & (t <= 6.0)) + 320.0 * (np.abs(t - 3.0) < 0.1)
    e = y - yhat
    a, b = int(np.searchsorted(t, 2.0)), int(np.searchsorted(t, 6.0))
    d = _describe(t, y, yhat, e, a, b, "A", [{"name": "ramp", "t_start": 0.0, "t_end": 10.0}])
    assert d["mean_residual"] < 0 and d["measured_worst"] - d["model_worst"] == pytest.approx(300.0)
    assert "model high by" in d["text"] and "but low by 300 A at " in d["text"]


def test_compare_and_calibration_given_a_file_name_or_a_dict_say_what_they_need(tmp_path):
    # truth: the wrong arguments built here by hand -- the record's file name where the record belongs, a dict of
    # values where the Parameters belong (were AttributeErrors: "'str' object has no attribute 'experiment'")
    from kilnctl.errors import ParameterError
    from kilnctl.measure import read_csv

    t = np.arange(0, 10, 0.02)
    speed = np.clip(74.0 * (t - 2.0), 0.0, 500.0)
    rec = tmp_path / "rec.csv"
    rec.write_text("time_s,current_A,speed_rpm\n" + "".join(
        f"{a:.2f},{100.0 + 0.5 * w + 3 * math.sin(7 * a):.3f},{w + 0.1 * math.sin(13 * a):.3f}\n"
        for a, w in zip(t, speed)))
    with pytest.raises(ParameterError, match=r"compare: measurement must be a kilnctl.measure.Measurement.*read_record"):
        compare(str(rec))
    with pytest.raises(ParameterError, match=r"Calibration.fit: measurement .*not str"):
        Calibration(Parameters(), ["mu_c"]).fit(str(rec))
    with pytest.raises(ParameterError, match=r"params must be a kilnctl.Parameters.*not dict"):
        compare(read_csv(rec), {"m_v": 5e5})


def test_one_string_of_effects_is_named_not_read_letter_by_letter():
    # truth: effects typed by hand as one string (was "unknown component 's'")
    from kilnctl.errors import ModelError

    with pytest.raises(ModelError, match=r"effects = 'second_motor' must be a list of names"):
        Calibration(Parameters(), ["mu_c"], effects="second_motor")
    with pytest.raises(KilnctlError, match=r"parameters = 'mu_c' must be a list"):
        Calibration(Parameters(), "mu_c")
    from kilnctl.measure import example_paths, load_setup, read_record

    rec, setup = example_paths()
    with pytest.raises(ModelError, match=r"effects = 'second_motor' must be a list of names"):
        compare(read_record(rec), load_setup(setup).params, effects="second_motor")
