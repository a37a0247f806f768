"""Records laid out as a plant historian writes them (red team, issue 12): reading, hints and notes.

Each test writes a small record whose true values are known because the test
wrote them (motor speed, current, the column names), and checks what kilnctl
reads or tells the user against them.
"""

import math
import re
import subprocess
import sys

import numpy as np
import pytest

from kilnctl import Parameters
from kilnctl.errors import DataError
from kilnctl.measure import read_record

N_GEAR = 1076.5  # paper, Table 1: total reduction motor to kiln


def _sliding_current_by_hand(p, mu):
    """Steady current of the foreign plant with the burden sliding at friction mu (mu_s = mu_c: it creeps at the
    kinetic angle tan psi = mu R / L): (mu m g R cos psi + T_brg) / (n k_i) [A] (NOTES.md worked steady state)."""
    psi = math.atan(mu * p["R"] / p["L"])
    t_brg = p["mu_brg"] * p["P"] * math.cos(math.pi / 6) * (p["l_brg"] + p["k_brg"]) / 2
    return (mu * p["m_v"] * p["g"] * p["R"] * math.cos(psi) + t_brg) / (p["n"] * p["k_i"])


def _start_up(n=600, dt=0.05, seed=1):
    """A plausible start-up: ramp at 74 rpm/s to 500 rpm from t = 1 s, current rising to about 800 A."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) * dt
    ref = np.clip(74.0 * (t - 1.0), 0.0, 500.0)
    speed = np.clip(74.0 * (t - 1.1), 0.0, 500.0) + rng.normal(0, 0.3, n)
    current = 100.0 + 700.0 * np.clip((t - 1.0) / 10.0, 0, 1) + rng.normal(0, 4.0, n)
    return t, current, speed, ref


def _write(path, header, rows, sep=","):
    path.write_text("# exported from the historian\n" + sep.join(header) + "\n"
                    + "\n".join(sep.join(str(c) for c in r) for r in rows) + "\n")
    return path


@pytest.mark.parametrize("header, expected", [
    # German names with units in parentheses and ISO timestamps: the time is recognised by its cells
    (("Timestamp", "Ankerstrom (A)", "Drehzahl (1/min)"), "time_s=Timestamp,current_A=Ankerstrom,speed_rpm=Drehzahl"),
    # units only at the end of the names; the kiln speed must not be taken for the motor speed
    (("time", "motor_current_A", "kiln_speed_rpm", "motor_speed_rpm"),
     "time_s=time,current_A=motor_current_A,speed_rpm=motor_speed_rpm"),
    # ms in the name (converted, so the unit goes into the hint), camelCase reference column
    (("t_ms", "Ia", "nM", "nRef"), "'time_s=t_ms [ms],current_A=Ia,speed_rpm=nM,speed_ref_rpm=nRef'"),
])
def test_missing_channels_hint_names_every_column(tmp_path, header, expected):
    # truth: the test wrote the columns; the hint must give the whole mapping, not only the first channel
    t, i, w, r = _start_up()
    if header[0] == "Timestamp":
        base = np.datetime64("2026-03-01T06:15:00.000")
        rows = [(str(base + np.timedelta64(int(round(tt * 1e3)), "ms")), a, b) for tt, a, b in zip(t, i, w)]
    elif header[0] == "time":
        rows = list(zip(t, i, w / N_GEAR, w))
    else:
        rows = list(zip(t * 1e3, i, w, r))
    p = _write(tmp_path / "rec.csv", header, rows)
    with pytest.raises(DataError, match="missing column 'time_s'") as e:
        read_record(p)
    assert "--columns " + expected + " " in str(e.value)
    # and the hint, followed, reads the record with the values the test wrote
    cols = expected.strip("'")
    m = read_record(p, columns=cols)
    np.testing.assert_allclose(m.current, i, atol=1e-9)
    np.testing.assert_allclose(m.speed, w, atol=1e-9)
    np.testing.assert_allclose(m.t - m.t[0], t - t[0], atol=1e-9)


def test_kiln_side_speed_is_multiplied_by_the_reduction(tmp_path):
    # truth: the file holds the motor speed too; the kiln speed times n (Table 1) must give it back
    t, i, w, _ = _start_up()
    p = _write(tmp_path / "kiln.csv", ("t [s]", "I [A]", "n_kiln [rpm]", "n_motor [rpm]"),
               [(a, b, f"{c / N_GEAR:.9g}", c) for a, b, c in zip(t, i, w)])
    with pytest.raises(DataError, match=r"looks like the kiln speed.*--columns 'speed_rpm=n_kiln \[kiln rpm\]'"):
        read_record(p, columns="time_s=t,current_A=I,speed_rpm=n_kiln")
    m = read_record(p, Parameters(), columns="time_s=t,current_A=I,speed_rpm=n_kiln [kiln rpm]")
    np.testing.assert_allclose(m.speed, w, atol=1e-5)
    assert any("kiln-side speed" in n and "1076.5" in n for n in m.notes)
    # rad/s at the kiln: 2*pi/60 per rpm, then times n
    p2 = _write(tmp_path / "kiln2.csv", ("t", "I", "w_kiln"),
                [(a, b, f"{c / N_GEAR * 2 * math.pi / 60:.9g}") for a, b, c in zip(t, i, w)])
    m2 = read_record(p2, Parameters(), columns="time_s=t,current_A=I,speed_rpm=w_kiln [rad/s @ kiln]")
    np.testing.assert_allclose(m2.speed, w, atol=1e-5)


def test_reference_and_speed_mix_ups_are_noted(tmp_path):
    t, i, w, r = _start_up()
    p = _write(tmp_path / "ref.csv", ("t [s]", "I_arm [A]", "n_mot [rpm]", "n_ref [rpm]"), list(zip(t, i, w, r)))
    # the reference left out of the mapping: said, with the mapping that uses it
    m = read_record(p, columns="time_s=t,current_A=I_arm,speed_rpm=n_mot")
    assert any("'n_ref [rpm]' looks like the speed reference" in n and "speed_ref_rpm=n_ref" in n for n in m.notes)
    # the reference (a noise-free straight ramp, as the test wrote it) read as the measured speed: said
    m = read_record(p, columns="time_s=t,current_A=I_arm,speed_rpm=n_ref")
    assert any("noise-free straight ramp" in n for n in m.notes)
    # the measured speed (noisy) is not taken for a reference
    m = read_record(p, columns="time_s=t,current_A=I_arm,speed_rpm=n_mot,speed_ref_rpm=n_ref")
    assert not any("reference" in n for n in m.notes)


def test_foreign_plant_record_reads_back_its_truth(tmp_path):
    # truth: the plant's own logged values (benchmarks/foreign_records.py), written in kA, rad/s and ISO
    # timestamps with a UTC offset; the reader must return them in A, rpm and seconds
    from benchmarks import foreign_records as fr

    spec = fr.PlantSpec("t_iso", 4.0, 50.0, base=dict(fr._NUIS), layout="iso_uneven", pre_s=1.0)
    truth = fr.write_record(spec, tmp_path)
    logged = fr.logged(spec)
    m = read_record(truth["csv"], Parameters(), columns=truth["columns"])
    assert m.n == truth["n_samples"] == logged["t"].size - 2  # two samples dropped on purpose
    t_log = logged["t"] - logged["t"][0]
    k = np.abs(t_log[None, :] - m.t[:, None]).argmin(axis=1)  # each read sample's logged sample (us stamps)
    np.testing.assert_allclose(m.t, t_log[k], atol=2e-6)
    np.testing.assert_allclose(m.current, logged["i"][k], rtol=1e-5, atol=1e-3)
    np.testing.assert_allclose(m.speed, logged["n"][k], rtol=1e-5, atol=1e-4)


def test_foreign_plant_steady_sliding_matches_the_hand_balance():
    # truth (NOTES.md, worked steady state): with a burden that slides at constant speed the kiln torque is
    # mu_c*N*R + bearing torque, so the current is (mu_c m g R cos psi + T_brg)/(n k_i); with mu_s = mu_c the
    # burden creeps at the kinetic angle tan psi = mu_c R / L
    from benchmarks import foreign_records as fr

    spec = fr.PlantSpec("t_slide", 24.0, 50.0, base=dict(mu_s=0.4, mu_c=0.4))
    sim = fr.simulate_plant(spec, h=1e-3)
    i_hand = _sliding_current_by_hand(fr.TABLE1, 0.4)
    late = sim["t"] > 19.0
    assert np.mean(sim["i_a"][late]) == pytest.approx(i_hand, rel=0.01)


def test_benchmark_script_help():
    out = subprocess.run([sys.executable, "-m", "benchmarks.foreign_records", "--help"], capture_output=True,
                         text=True, timeout=60)
    assert out.returncode == 0 and "--write DIR" in out.stdout


def test_missing_samples_and_jitter_are_noted(tmp_path):
    # truth: the test drops samples 100, 101 and 300 (steps of 3 and 2 medians) and, in a second file,
    # jitters every time by up to +-30 % of the step; neither is a gap (> 5 medians), both are said
    t, i, w, _ = _start_up()
    keep = np.ones(t.size, bool)
    keep[[100, 101, 300]] = False
    p = _write(tmp_path / "drop.csv", ("time_s", "current_A", "speed_rpm"), list(zip(t[keep], i[keep], w[keep])))
    m = read_record(p)
    note = next(n for n in m.notes if "missing samples" in n)
    # longest step 3 x 0.05 s from t = 4.95 s to 5.1 s; sample 102 is the file's line 102 - 2 + 3 (two dropped,
    # comment and header before sample 0 on line 3)
    assert note.startswith("2 step(s)") and "the longest 0.15 s between t = 4.95 s and 5.1 s (line 103)" in note
    assert not any("uneven" in n for n in m.notes)
    tj = t + np.random.default_rng(3).uniform(-0.3, 0.3, t.size) * 0.05
    p2 = _write(tmp_path / "jitter.csv", ("time_s", "current_A", "speed_rpm"), list(zip(tj, i, w)))
    m2 = read_record(p2)
    assert any(n.startswith("uneven time base") for n in m2.notes)
    assert not any("missing samples" in n for n in m2.notes)  # jitter alone is not taken for missing samples


def test_diagnose_says_how_the_record_was_read_before_the_search(tmp_path, monkeypatch, capsys):
    # truth: the file is in kA with its reference left unmapped; both notes must be on stderr before the
    # (minutes-long) search starts, so a mix-up is seen at once.  The search itself is replaced by a stop.
    import argparse

    from kilnctl.cli import diagnose_cmd
    from kilnctl.measure import diagnose

    t, i, w, r = _start_up()
    p = _write(tmp_path / "rec.csv", ("t [s]", "I [kA]", "n_mot [rpm]", "n_ref [rpm]"),
               list(zip(t, i / 1e3, w, r)))

    class Stop(Exception):
        pass

    seen = {}

    def fake_fit(self, measurement, progress=None):
        seen["stderr"] = capsys.readouterr().err
        raise Stop

    monkeypatch.setattr(diagnose.Diagnosis, "fit", fake_fit)
    ap = argparse.ArgumentParser()
    diagnose_cmd.register(ap.add_subparsers())
    args = ap.parse_args(["diagnose", "--data", str(p), "--columns", "time_s=t,current_A=I,speed_rpm=n_mot"])
    with pytest.raises(Stop):
        args.func(args)
    assert "record: current_A converted from kA to A (x 1000)" in seen["stderr"]
    assert "record: 'n_ref [rpm]' looks like the speed reference" in seen["stderr"]


@pytest.mark.parametrize("layout", ["units_row", "decimal_comma_cp1252", "trailing_separator", "excel_sep_line",
                                    "excel_sep_line_tab"])
def test_european_and_spreadsheet_csv_exports(tmp_path, layout):
    # truth: the values the test wrote; each layout is a common export of a historian or of Excel
    t, i, w, _ = _start_up(n=300)
    rows = [(f"{a:.3f}", f"{b:.4f}", f"{c:.4f}") for a, b, c in zip(t, i, w)]
    p = tmp_path / "rec.csv"
    if layout == "units_row":  # names on line 1, units on line 2 (kA: converted)
        p.write_text("Zeit;Strom;Drehzahl\ns;kA;1/min\n" + "\n".join(
            f"{a};{float(b) / 1e3:.7f};{c}" for a, b, c in rows) + "\n")
        m = read_record(p, columns="time_s=Zeit,current_A=Strom,speed_rpm=Drehzahl")
        assert "units read from line 2 (under the header)" in m.notes
    elif layout == "decimal_comma_cp1252":  # German Windows export: ';', decimal commas, an umlaut in a name
        text = "Zeit [s];Strom Läufer [A];Drehzahl [1/min]\n" + "\n".join(
            ";".join(x.replace(".", ",") for x in r) for r in rows) + "\n"
        p.write_bytes(text.encode("cp1252"))
        m = read_record(p, columns="time_s=Zeit,current_A=Strom Läufer,speed_rpm=Drehzahl")
        assert any("Windows-1252" in n for n in m.notes) and any("decimal commas" in n for n in m.notes)
    elif layout.startswith("excel_sep_line"):  # Excel's 'sep=;' first line names the separator (it was the header)
        sep = "\t" if layout.endswith("tab") else ";"
        p.write_text(f"sep={sep}\ntime_s{sep}current_A{sep}speed_rpm\n" + "\n".join(
            sep.join(x.replace(".", ",") for x in r) for r in rows) + "\n")
        m = read_record(p)
    else:  # a separator at the end of every line: an empty last column
        p.write_text("time_s,current_A,speed_rpm,\n" + "\n".join(",".join(r) + "," for r in rows) + "\n")
        m = read_record(p)
    np.testing.assert_allclose(m.t, t, atol=1e-3)
    np.testing.assert_allclose(m.current, i, atol=1e-3)
    np.testing.assert_allclose(m.speed, w, atol=1e-3)


def test_comma_separated_file_with_decimal_commas_is_still_refused(tmp_path):
    # with ',' as the separator a decimal comma cannot be told from a separator: the message says so
    p = tmp_path / "rec.csv"
    p.write_text("time_s,current_A,speed_rpm\n" + "\n".join(f'{k * 0.05:.2f},"1,5",{k}' for k in range(100)))
    with pytest.raises(DataError, match=r"line 2, column 'current_A': '1,5' is not a number \(decimal comma"):
        read_record(p)


def test_ramp_start_from_the_speed_of_a_foreign_drive(tmp_path):
    # truth: the foreign plant's ramp starts 1.5 s into its record (no reference logged).  Its speed lags the
    # reference (about 45 ms at 2 % of omega_ref); the start taken where the speed rises, less the ramp's own
    # time, came out that much late, and 45 ms cost 8 points of current fit with the true model
    from benchmarks import foreign_records as fr

    spec = fr.PlantSpec("t_start", 2.5, 50.0, base=dict(fr._NUIS), layout="iso", pre_s=1.5)
    truth = fr.write_record(spec, tmp_path)
    params = Parameters(gains="given", k_p=2.0, k_I=5.0, k_D=0.01)
    m = read_record(truth["csv"], params, columns=truth["columns"])
    exp = m.experiment(params)
    assert exp.t0 == pytest.approx(1.5, abs=0.015)
    assert "from the first rise of the measured speed" in exp.notes[0]


def test_a_setup_that_states_the_torque_law_is_fitted_as_stick_slip(tmp_path):
    # truth: the foreign plant's own parameters (benchmarks/foreign_records.py, record f1: no effect, the setup
    # states friction_law = 'torque'); kilnctl's model with those values reaches the fit compared below.  The
    # diagnosis gave the stick-slip handling (phase-free stage, fine mu_s grid) only when it added the law
    # itself, so a user who stated the law got a base fit of 71 % on this record (97 % with the true values)
    from benchmarks import foreign_records as fr
    from kilnctl.measure import Diagnosis, compare, load_setup

    spec = next(s for s in fr.RECORDS if s.name == "f1_free_torque")
    truth = fr.write_record(spec, tmp_path)
    setup = load_setup(tmp_path / "f1_free_torque.toml")
    m = read_record(truth["csv"], setup.params, columns=truth["columns"])
    true_fit = compare(m, setup.params.replace(**truth["base"])).fit["current_A"]
    d = Diagnosis(setup.params, candidates=(), workers=1).fit(m)
    assert d.baseline_["current_A"] > true_fit - 1.0


def test_a_file_mixing_decimal_commas_and_points_names_the_clash(tmp_path):
    """A ';' file with decimal commas and one column written with decimal points: the message names both.

    Truth: the test writes the time and current with decimal commas and the speed with points (one column
    formatted apart, as a spreadsheet does); the error was "line 2, column 'time_s': '0,000' is neither a number of
    seconds nor an ISO 8601 timestamp", which hid the cause (the points turn off the reading of decimal commas).
    """
    t, i, w, _ = _start_up(n=300)
    p = tmp_path / "rec.csv"
    p.write_text("time_s;current_A;speed_rpm\n" + "\n".join(
        f"{a:.3f};{b:.2f};{c:.3f}".replace(".", ",", 2) for a, b, c in zip(t, i, w)) + "\n")
    with pytest.raises(DataError, match=r"rec.csv: line 2, column 'time_s': '0,000' is not a number; decimal commas "
                                        r"are not read, because line 2, column 'speed_rpm' has a decimal point "
                                        r"\('-?0.\d+'\): give every number of the file with one decimal sign"):
        read_record(p)


def test_a_thousands_separator_is_named_as_such(tmp_path):
    """A current written with a thousands separator ('1.000,08', German spreadsheet format) names that cause.

    Truth: the test writes currents above 1000 A in the format '#.##0,00'; the message suggested only 'decimal
    comma? write 1.5, not 1,5', though the file's decimal commas are fine.
    """
    t, i, w, _ = _start_up(n=300)
    de = [f"{1.5 * b:,.2f}".replace(",", " ").replace(".", ",").replace(" ", ".") for b in i]
    p = tmp_path / "rec.csv"
    p.write_text("time_s;current_A;speed_rpm\n" + "\n".join(
        ";".join([f"{a:.3f}".replace(".", ","), b, f"{c:.3f}".replace(".", ",")]) for a, b, c in zip(t, de, w)) + "\n")
    first = next(k for k, c in enumerate(de) if "." in c)
    with pytest.raises(DataError, match=rf"line {first + 2}, column 'current_A': '{re.escape(de[first])}' is not a "
                                        r"number \(a thousands separator\? export the numbers without one"):
        read_record(p)


# --- third red team: the plant's new effect forms, each against a truth derived by hand -------------------------

def _plant():
    from benchmarks import foreign_records as fr

    return fr


def test_scurve_reference_is_jerk_limited_and_ends_with_the_ramp():
    # truth (hand): rate r = W / (T - T_j) with T = W / ramp_rate; W/2 at T/2 by symmetry; r T_j / 2 at T_j;
    # the full value from T on; rate continuous (no step at the corners)
    fr = _plant()
    c = fr.plant_constants(fr.PlantSpec("t_s", 10.0, 50.0, effects={"scurve": {"T_j": 2.0}}))
    W, T = 500.0, 500.0 / 74.0
    r = W / (T - 2.0)
    assert fr._reference(T / 2, c) == pytest.approx(W / 2, rel=1e-12)
    assert fr._reference(2.0, c) == pytest.approx(r * 2.0 / 2, rel=1e-12)
    assert fr._reference(T, c) == pytest.approx(W) and fr._reference(T + 3.0, c) == W
    ts = np.linspace(0.0, T + 1.0, 20001)
    rate = np.gradient([fr._reference(x, c) for x in ts], ts)
    assert rate.max() == pytest.approx(r, rel=1e-3) and np.abs(np.diff(rate)).max() < 0.05


def test_stribeck_and_gear_ripple_torques_in_the_right_hand_side():
    # truth (hand): sliding burden: J_v a_b = mu(v) m g R cos psi - m g L sin psi with
    # mu(v) = mu_c + (mu_s - mu_c) exp(-(v / v_s)^2), v the slip speed; stuck burden with mesh ripple:
    # (J_o + J_v + J_m n^2) a_k = n k_i i (1 + a sin(Z theta_k)) - m g L sin psi - T_brg (B_m w = 0 at rest)
    fr = _plant()
    p = fr.TABLE1
    c = fr.plant_constants(fr.PlantSpec("t_r", 1.0, 50.0, effects={"stribeck": {"v_s": 0.003}}))
    psi, w_k, v = 0.3, 0.04, 0.003
    x = np.array([0, 0, w_k * p["n"], 0, w_k, 0, psi, w_k - v, 0, 0], float)
    d = fr._rhs(x, 1.0, c, 1)[0]
    mu = p["mu_c"] + (p["mu_s"] - p["mu_c"]) / math.e
    mg = p["m_v"] * p["g"]
    assert d[7] == pytest.approx((mu * mg * p["R"] * math.cos(psi) - mg * p["L"] * math.sin(psi)) / p["J_v"], rel=1e-9)
    c = fr.plant_constants(fr.PlantSpec("t_r", 1.0, 50.0, effects={"gear_ripple": {"a": 0.03, "Z": 180}}))
    th_k = 0.5 / 180 * math.pi  # sin(Z theta_k) = 1
    x = np.array([800.0, 0, 0, 0, 0, th_k, 0.2, 0, 0, 0])
    d, i_a, _, _ = fr._rhs(x, 0.0, c, 0)
    J = p["J_o"] + p["J_v"] + p["J_m"] * p["n"] ** 2
    assert d[4] == pytest.approx((p["n"] * p["k_i"] * i_a * 1.03 - mg * p["L"] * math.sin(0.2)) / J, rel=1e-9)


def test_gear_ripple_shows_at_the_tooth_passing_frequency():
    # truth (hand): at the set speed the kiln turns at 500 / n rpm, so 180 teeth pass at 180 * 500 / n / 60 Hz
    fr = _plant()
    spec = fr.PlantSpec("t_g", 16.0, 50.0, base=dict(mu_s=0.4, mu_c=0.4),
                        effects={"gear_ripple": {"a": 0.03, "Z": 180}})
    sim = fr.simulate_plant(spec, h=2e-3)
    spec.effects = {}
    smooth = fr.simulate_plant(spec, h=2e-3)  # the same plant without the ripple: the difference is the ripple's
    late = sim["t"] > 9.0
    i = sim["i_a"][late] - smooth["i_a"][late]
    i = i - np.mean(i)
    f = np.fft.rfftfreq(i.size, 2e-3)
    peak = f[np.argmax(np.abs(np.fft.rfft(i * np.hanning(i.size)))[1:]) + 1]
    assert peak == pytest.approx(180 * 500.0 / fr.TABLE1["n"] / 60.0, abs=1.0 / 7.0)  # the window's resolution


def test_field_weakening_raises_the_sliding_current_by_the_flux_ratio():
    # truth (NOTES.md worked steady state, as above): torque k_i phi i with phi = w_base / w above base speed, so
    # the steady sliding current is i_hand * 500 / 350
    fr = _plant()
    spec = fr.PlantSpec("t_fw", 24.0, 50.0, base=dict(mu_s=0.4, mu_c=0.4), effects={"field_weak": {"w_base": 350.0}})
    sim = fr.simulate_plant(spec, h=1e-3)
    i_hand = _sliding_current_by_hand(fr.TABLE1, 0.4)
    late = sim["t"] > 19.0
    assert np.mean(sim["i_a"][late]) == pytest.approx(i_hand * 500.0 / 350.0, rel=0.01)


def test_current_limiter_holds_the_hand_derived_level():
    # truth (hand, k_D = 0, L_a neglected): while the limiter acts and the kiln decelerates at a_m, the speed
    # loop's command rises at (k_p K + k_b)|a_m| V/s, which the limiter's integral k_il (i - I_lim) must match;
    # with a_m = k_i (i - i_hand) / J_eq (J_eq = J_m + (J_o + J_v) / n^2, burden still held) the current is
    # i = (I_lim + g i_hand) / (1 + g), g = (k_p K + k_b) k_i / (k_il J_eq)
    fr = _plant()
    p = fr.TABLE1
    spec = fr.PlantSpec("t_lim", 16.2, 50.0, gains=(2.0, 5.0, 0.0), base=dict(mu_s=0.4, mu_c=0.4),
                        effects={"ilimit": {"I": 700.0, "k_p": 0.1, "k_i": 20.0}})
    sim = fr.simulate_plant(spec, h=1e-3)
    psi = math.atan(0.4 * p["R"] / p["L"])
    t_brg = p["mu_brg"] * p["P"] * math.cos(math.pi / 6) * (p["l_brg"] + p["k_brg"]) / 2
    i_hand = (0.4 * p["m_v"] * p["g"] * p["R"] * math.cos(psi) + t_brg) / (p["n"] * p["k_i"])
    g = (2.0 * fr.K_FB + p["k_b"]) * p["k_i"] / (20.0 * (p["J_m"] + (p["J_o"] + p["J_v"]) / p["n"] ** 2))
    win = (sim["t"] > 15.8) & (sim["t"] < 16.2)
    assert np.mean(sim["i_a"][win]) == pytest.approx((700.0 + g * i_hand) / (1 + g), rel=0.005)
    assert np.all(sim["w_m"][win] > 0)  # the kiln still turns forward (the derivation's premise)


def test_encoder_speed_is_whole_counts_per_window():
    # truth (hand): the encoder reports (whole counts) * 2 pi / (ppr T_w): every logged speed is a multiple of it,
    # and over many windows the counts average to the true speed
    fr = _plant()
    spec = fr.PlantSpec("t_e", 10.0, 50.0, base=dict(mu_s=0.4, mu_c=0.4),
                        effects={"encoder": {"T_w": 0.006, "ppr": 4096}})
    sim = fr.simulate_plant(spec, h=1e-3)
    q = 2 * math.pi / (4096 * 0.006)
    k = sim["w_s"] / q
    np.testing.assert_allclose(k, np.round(k), atol=1e-6)
    late = sim["t"] > 8.0
    assert np.mean(sim["w_s"][late]) == pytest.approx(np.mean(sim["w_m"][late]), abs=q / 10)


def test_logged_drift_quantisation_and_dropout():
    # truth (hand): the drift adds rate * (time since the trigger) to the same noisy samples; the ADC leaves
    # multiples of q; the dropout repeats the sample before it
    fr = _plant()
    kw = dict(base=dict(mu_s=0.4, mu_c=0.4), pre_s=0.5, h=2e-3)
    plain = fr.logged(fr.PlantSpec("t_log", 3.0, 50.0, **kw))
    drift = fr.logged(fr.PlantSpec("t_log", 3.0, 50.0, effects={"idrift": {"rate": 0.75}}, **kw))
    np.testing.assert_allclose(drift["i"] - plain["i"], 0.75 * (plain["t"] + 0.5), atol=1e-9)
    q = fr.logged(fr.PlantSpec("t_log", 3.0, 50.0, effects={"adc": {"q": 10.0}, "dropout": {"t": 1.0, "dur": 0.5}},
                               **kw))
    np.testing.assert_allclose(q["i"] / 10.0, np.round(q["i"] / 10.0), atol=1e-9)
    held = (plain["t"] >= 1.0) & (plain["t"] < 1.5)
    k0 = np.flatnonzero(held)[0] - 1
    assert np.all(q["n"][held] == plain["n"][k0]) and np.all(q["i"][held] == q["i"][k0])
    assert held.sum() == 25


# --- fourth red team: further forms of catalogue effects, each against a truth derived by hand --------------------

_SOFT = (0.2, 1.5, 0.0)  # gains the delayed or filtered sensor's loop is stable with (the paper's diverge)


def test_delay_logs_the_motor_speed_shifted_by_the_delay():
    # truth (hand): the sensor reads w_m(t - T_d): with T_d a whole number of steps the logged speed is the motor
    # speed T_d / h steps earlier, and zero (at rest) before T_d
    fr = _plant()
    spec = fr.PlantSpec("t_d", 5.0, 50.0, gains=_SOFT, base=dict(mu_s=0.4, mu_c=0.4), effects={"delay": {"T_d": 0.03}})
    sim = fr.simulate_plant(spec, h=1e-3)
    np.testing.assert_allclose(sim["w_s"][30:], sim["w_m"][:-30], rtol=0, atol=1e-9)
    assert np.all(sim["w_s"][:30] == 0.0) and sim["w_m"][29] > 0
    # substeps: linear between the stored steps
    c = fr.plant_constants(spec)
    c.update(h=1e-3, buf=np.array([0.0, 0.0, 2.0, 4.0, 0.0]))  # slots 2 and 3 hold the speeds at steps 2 and 3
    assert fr._delayed(c, 0.0325) == pytest.approx(3.0, rel=1e-9)  # t - T_d = 2.5 steps


def test_second_order_filter_step_and_ramp_responses():
    # truth (hand): y'' = w_n^2 (u - y) - 2 zeta w_n y'. For a step the peak is 1 + exp(-zeta pi / sqrt(1 - zeta^2))
    # (16.3 % overshoot at zeta 0.5) at t = pi / (w_n sqrt(1 - zeta^2)), the DC gain 1; on a ramp u = a t the output
    # lags by a 2 zeta / w_n (the u'' term, (4 zeta^2 - 1) / w_n^2, vanishes at zeta 0.5)
    fr = _plant()
    w_n, zeta = 2 * math.pi * 10.0, 0.5
    spec = fr.PlantSpec("t_f", 5.0, 50.0, gains=_SOFT, base=dict(mu_s=0.4, mu_c=0.4),
                        effects={"filter2": {"w_n": w_n, "zeta": zeta}})
    c = fr.plant_constants(spec)
    x = np.zeros(14)
    x[2] = 50.0  # the motor speed steps to 50 rad/s; only the filter's two states are integrated
    h, ys = 2e-4, [0.0]

    def f(y):
        return fr._rhs(np.concatenate([x[:10], y, x[12:]]), 0.0, c, 0)[0][10:12]

    for _ in range(1500):
        y = x[10:12]
        k1 = f(y)
        k2 = f(y + h / 2 * k1)
        k3 = f(y + h / 2 * k2)
        k4 = f(y + h * k3)
        x[10:12] = y + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        ys.append(x[10])
    ys = np.array(ys)
    wd = w_n * math.sqrt(1 - zeta ** 2)
    assert ys.max() == pytest.approx(50.0 * (1 + math.exp(-zeta * math.pi / math.sqrt(1 - zeta ** 2))), rel=1e-5)
    assert np.argmax(ys) * h == pytest.approx(math.pi / wd, abs=h)
    assert ys[-1] == pytest.approx(50.0, rel=2e-4)  # 0.3 s = 9.4 time constants 1 / (zeta w_n): exp(-9.4) = 8e-5
    sim = fr.simulate_plant(spec, h=1e-3)
    ramp = (sim["t"] > 3.0) & (sim["t"] < 6.0)
    a = np.gradient(sim["w_m"], sim["t"])
    assert np.mean(sim["w_m"][ramp] - sim["w_s"][ramp]) == pytest.approx(np.mean(a[ramp]) * 2 * zeta / w_n, rel=0.01)


def test_quadratic_drag_torque_in_the_right_hand_side():
    # truth (hand): burden held, the drag c_q w_k |w_k| opposes the kiln's motion:
    # (J_o + J_v + J_m n^2) da_k = -c_q w_k |w_k|, for either direction
    fr = _plant()
    p = fr.TABLE1
    c0 = fr.plant_constants(fr.PlantSpec("t_q", 1.0, 50.0))
    c = fr.plant_constants(fr.PlantSpec("t_q", 1.0, 50.0, effects={"quad_drag": {"c_q": 1.03e8}}))
    J = p["J_o"] + p["J_v"] + p["J_m"] * p["n"] ** 2
    for w_k in (0.0486, -0.02):
        x = np.array([700.0, 0, w_k * p["n"], 0, w_k, 0, 0.3, w_k, 0, 0])
        da = fr._rhs(x, 1.0, c, 0)[0][4] - fr._rhs(x, 1.0, c0, 0)[0][4]
        assert da == pytest.approx(-1.03e8 * w_k * abs(w_k) / J, rel=1e-6)
    assert 1.03e8 * 0.0486 == pytest.approx(5.0e6, rel=0.01)  # as a viscous B_o at the set speed (record f23)


def test_ovality_load_has_the_two_harmonics():
    # truth (hand): the load T1 sin(th + phi1) + T2 sin(2 th + phi2) has sin / cos coefficients T cos(phi) / T sin(phi)
    # at orders 1 and 2 and nothing at order 3; it is read from the burden-held kiln's acceleration
    fr = _plant()
    p = fr.TABLE1
    ov = {"T1": 2.0e5, "phi1": 0.6, "T2": 1.0e5, "phi2": 2.0}
    c0 = fr.plant_constants(fr.PlantSpec("t_o", 1.0, 50.0))
    c = fr.plant_constants(fr.PlantSpec("t_o", 1.0, 50.0, effects={"ovality": ov}))
    J = p["J_o"] + p["J_v"] + p["J_m"] * p["n"] ** 2
    th = np.arange(64) * 2 * math.pi / 64
    load = []
    for a in th:
        x = np.array([700.0, 0, 0.02 * p["n"], 0, 0.02, a, 0.3, 0.02, 0, 0])
        load.append(-(fr._rhs(x, 1.0, c, 0)[0][4] - fr._rhs(x, 1.0, c0, 0)[0][4]) * J)
    load = np.array(load)
    for order, T, phi in ((1, 2.0e5, 0.6), (2, 1.0e5, 2.0), (3, 0.0, 0.0)):
        assert np.mean(load * np.sin(order * th)) * 2 == pytest.approx(T * math.cos(phi), abs=1.0)
        assert np.mean(load * np.cos(order * th)) * 2 == pytest.approx(T * math.sin(phi), abs=1.0)


def test_coupled_second_motor_resonance_and_stiff_limit():
    # truth (hand): without motor torque (k_i = k_b -> 0), friction and gravity (mu_brg = 0, L = 0) the drive is two
    # masses, J_eq = J_m + (J_o + J_v) / n^2 (burden held) and the coupled rotor J, on a spring k: one mode at
    # sqrt(k (1 / J_eq + 1 / J)); and a stiff coupling carries the rotor along: the speeds coincide and the current
    # is the rigid second motor's (J2 form)
    fr = _plant()
    p = fr.TABLE1
    base = dict(k_i=1e-9, k_b=1e-9, mu_brg=0.0, L=0.0, B_m=0.0)
    spec = fr.PlantSpec("t_c", 1.0, 50.0, base=base, effects={"coupling_j2": {"J": 25.0, "k": 4.0e4, "c": 0.0}})
    c = fr.plant_constants(spec)
    x0, eps = np.zeros(14), 1e-6
    jac = np.empty((14, 14))
    for j in range(14):
        dx = np.zeros(14)
        dx[j] = eps
        jac[:, j] = (fr._rhs(x0 + dx, 0.0, c, 0)[0] - fr._rhs(x0 - dx, 0.0, c, 0)[0]) / (2 * eps)
    w_mode = np.abs(np.linalg.eigvals(jac).imag).max()
    J_eq = p["J_m"] + (p["J_o"] + p["J_v"]) / p["n"] ** 2
    assert w_mode == pytest.approx(math.sqrt(4.0e4 * (1 / J_eq + 1 / 25.0)), rel=1e-6)
    kw = dict(base=dict(mu_s=0.4, mu_c=0.4), pre_s=0.5)
    stiff_coupling = {"coupling_j2": {"J": 25.0, "k": 5e5, "c": 1500.0}}  # 31 Hz
    stiff = fr.simulate_plant(fr.PlantSpec("t_c", 6.0, 50.0, effects=stiff_coupling, **kw), h=1e-3)
    rigid = fr.simulate_plant(fr.PlantSpec("t_c", 6.0, 50.0, effects={"J2": {"J": 25.0}}, **kw), h=1e-3)
    ramp = (stiff["t"] > 1.0) & (stiff["t"] < 6.0)
    assert np.abs(stiff["w_2"][ramp] - stiff["w_m"][ramp]).max() < 1e-5 * stiff["w_m"][ramp].max()
    np.testing.assert_allclose(stiff["i_a"][ramp], rigid["i_a"][ramp], atol=0.1)  # the rotor adds 42 A
