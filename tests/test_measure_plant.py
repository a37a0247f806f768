"""Records from the plant: other column names and units, timestamps, Excel, Parquet, MATLAB, long logs.

The truth throughout is a record the test writes itself in SI units (s, A, rpm): the test converts it to
another unit, layout or format with its own code, and kilnctl must read back the same numbers.
"""

import datetime as dt
import hashlib
import math

import numpy as np
import pytest

from kilnctl import Parameters
from kilnctl.cli import main
from kilnctl.errors import ConfigFileError, DataError
from kilnctl.measure import load_setup, read_record, split_startups
from kilnctl.measure.io import record_columns
from kilnctl.measure.tables import parse_columns, split_unit

RPM_PER_RAD_S = 60.0 / (2.0 * math.pi)


def _record(ramp_at=1.0, rate=74.0, top=500.0, n=1500, dt_s=0.02, t_start=0.0, seed=0, i_run=840.0):
    """A start-up in SI: reference ramp, speed lagging it by 40 ms, current with noise (all [s, A, rpm])."""
    rng = np.random.default_rng(seed)
    t = t_start + dt_s * np.arange(n)
    ref = np.clip(rate * (t - ramp_at), 0.0, top)
    speed = np.clip(rate * (t - ramp_at - 0.04), 0.0, top) + 0.2 * rng.standard_normal(n)
    cur = i_run * (ref > 0) + 60.0 * np.sin(2 * np.pi * 0.2 * t) + 3.0 * rng.standard_normal(n)
    return {"t": t, "I": cur, "n": speed, "ref": ref}


def _r(x):
    return repr(float(x))


def _sha(p):
    return hashlib.sha256(p.read_bytes()).hexdigest()


def _same(m, rec, t_tol=1e-9, rtol=1e-12):
    # truth: the SI arrays the test wrote, before its own unit conversion
    assert m.n == rec["t"].size
    assert np.allclose(m.t - m.t[0], rec["t"] - rec["t"][0], rtol=0, atol=t_tol)
    assert np.allclose(m.current, rec["I"], rtol=rtol, atol=1e-9)
    assert np.allclose(m.speed, rec["n"], rtol=rtol, atol=1e-9)
    if "ref" in rec and m.speed_ref is not None:
        assert np.allclose(m.speed_ref, rec["ref"], rtol=rtol, atol=1e-9)


def test_units_in_the_header_are_converted(tmp_path):
    rec = _record()
    p = tmp_path / "trace.csv"
    # the test's own conversion: ms, kA, 1/min (= rpm), rad/s
    rows = ["t [ms],I_arm [kA],n_mot [1/min],n_ref [rad/s]"] + [
        f"{_r(1000 * a)},{_r(b / 1000)},{_r(c)},{_r(d / RPM_PER_RAD_S)}" for a, b, c, d in
        zip(rec["t"], rec["I"], rec["n"], rec["ref"])]
    p.write_text("\n".join(rows) + "\n")
    before = _sha(p)
    m = read_record(p, columns="current_A=I_arm,speed_rpm=n_mot,time_s=t,speed_ref_rpm=n_ref")
    _same(m, rec)
    assert _sha(p) == before  # the file is only read
    assert any("ms to s" in s for s in m.notes) and any("kA to A" in s for s in m.notes)


def test_unit_given_in_the_mapping_and_in_the_setup_file(tmp_path):
    rec = _record()
    p = tmp_path / "trace.csv"
    p.write_text("t;I_arm;n_mot\n" + "\n".join(f"{_r(1000 * a)};{_r(b)};{_r(c / 60)}" for a, b, c in
                                               zip(rec["t"], rec["I"], rec["n"])) + "\n")
    setup = tmp_path / "setup.toml"
    setup.write_text('[measurement]\ncolumns = {current_A = "I_arm", speed_rpm = "n_mot [rev/s]", time_s = "t"}\n')
    s = load_setup(setup)
    # without a unit for t the time is read in seconds: 20 s steps cannot resolve a 6.8 s ramp
    with pytest.raises(DataError, match=r"column 't' \(read as time_s\).*looks like milliseconds.*'time_s=t \[ms\]'"):
        read_record(p, s.params, record_columns(s))
    # --columns wins over the setup file, channel by channel
    m = read_record(p, s.params, record_columns(s, "time_s=t [ms]"))
    _same(m, rec)


def test_iso_timestamps_with_an_offset_are_seconds_since_the_first_sample(tmp_path):
    rec = _record(n=600)
    t0 = dt.datetime(2024, 3, 31, 0, 59, 50, tzinfo=dt.timezone(dt.timedelta(hours=2)))
    p = tmp_path / "historian.csv"
    p.write_text("# exported from the historian\ntimestamp,current_A,speed_rpm\n" + "\n".join(
        f"{(t0 + dt.timedelta(seconds=float(a))).isoformat()},{_r(b)},{_r(c)}"
        for a, b, c in zip(rec["t"], rec["I"], rec["n"])) + "\n")
    m = read_record(p, columns={"time_s": "timestamp"})
    _same(m, rec, t_tol=1e-6)  # isoformat keeps microseconds
    assert any("timestamps" in s and "2024-03-30T22:59:50" in s for s in m.notes)  # shown in UTC


def test_bad_timestamp_names_the_line(tmp_path):
    rec = _record(n=300)
    t0 = dt.datetime(2024, 3, 1, 6, 0, 0)
    lines = ["time_s,current_A,speed_rpm"] + [f"{(t0 + dt.timedelta(seconds=float(a))).isoformat()},{b},{c}"
                                              for a, b, c in zip(rec["t"], rec["I"], rec["n"])]
    lines[40] = "01/03/2024 06:00:00.78," + lines[40].split(",", 1)[1]
    p = tmp_path / "ts.csv"
    p.write_text("\n".join(lines) + "\n")
    with pytest.raises(DataError, match=r"ts.csv: line 41, column 'time_s': '01/03/2024 06:00:00.78' is neither"):
        read_record(p)
    lines[40] = "2024-03-01T06:00:00.78+01:00," + lines[40].split(",", 1)[1]
    p.write_text("\n".join(lines) + "\n")
    with pytest.raises(DataError, match=r"line 41, column 'time_s': .*mixes timestamps with and without a UTC offset"):
        read_record(p)


def test_excel_sheet_with_title_rows_and_datetime_cells(tmp_path):
    openpyxl = pytest.importorskip("openpyxl")
    rec = _record(n=500)
    wb = openpyxl.Workbook()
    ws = wb.active
    ws.title = "trace"
    ws.append(["# drive trace, kiln 2"])
    ws.append([])
    ws.append(["Zeit", "I_arm [A]", "n_mot [rpm]", "quality"])
    t0 = dt.datetime(2024, 3, 1, 6, 0, 0)
    for a, b, c in zip(rec["t"], rec["I"], rec["n"]):
        ws.append([t0 + dt.timedelta(seconds=float(a)), float(b), float(c), "good"])
    wb.create_sheet("notes")
    p = tmp_path / "trace.xlsx"
    wb.save(p)
    before = _sha(p)
    m = read_record(p, columns="time_s=Zeit,current_A=I_arm,speed_rpm=n_mot")
    _same(m, rec, t_tol=1e-3)  # Excel stores date-times to the millisecond
    assert _sha(p) == before
    assert any("quality (not numeric)" in s for s in m.notes) and any("'notes' not read" in s for s in m.notes)
    ws.cell(row=3 + 77, column=2).value = None  # data row 77 -> sheet row 80
    wb.save(p)
    with pytest.raises(DataError, match=r"trace.xlsx \(sheet 'trace'\): row 80, column 'I_arm \[A\]' "
                                        r"\(read as current_A\): empty cell"):
        read_record(p, columns="time_s=Zeit,current_A=I_arm,speed_rpm=n_mot")


def test_parquet_with_a_timezone_aware_timestamp(tmp_path):
    pa = pytest.importorskip("pyarrow")
    pq = pytest.importorskip("pyarrow.parquet")
    rec = _record(n=500)
    us = (np.round(rec["t"] * 1e6)).astype("int64") + 1_709_272_800_000_000  # 2024-03-01T06:00Z in microseconds
    table = pa.table({"ts": pa.array(us, type=pa.timestamp("us", tz="Europe/Berlin")),
                      "I_arm [A]": rec["I"], "n_mot [rad/s]": rec["n"] / RPM_PER_RAD_S})
    p = tmp_path / "trace.parquet"
    pq.write_table(table, p)
    m = read_record(p, columns={"time_s": "ts", "current_A": "I_arm", "speed_rpm": "n_mot"})
    _same(m, rec, t_tol=1e-6)


@pytest.mark.parametrize("layout", ["struct", "variables"])
def test_matlab_file_in_ms(tmp_path, layout):
    import scipy.io

    rec = _record(n=500)
    # MATLAB saves column vectors (N x 1): the reader must flatten them
    vecs = {"t_ms": (1000 * rec["t"])[:, None], "I_arm": rec["I"][:, None], "n_mot": rec["n"][:, None],
            "scale": np.array([[2.0]])}
    p = tmp_path / "trace.mat"
    scipy.io.savemat(p, {"rec": vecs} if layout == "struct" else vecs)
    m = read_record(p, columns="time_s=t_ms [ms],current_A=I_arm,speed_rpm=n_mot")
    _same(m, rec)
    with pytest.raises(DataError, match=r"trace.mat: column 'I_arm' is mapped to both current_A and speed_rpm"):
        read_record(p, columns="time_s=t_ms [ms],current_A=I_arm,speed_rpm=I_arm")
    with pytest.raises(DataError, match=r"trace.mat: the column mapping gives current_A=I_a, but the file has no "
                                        r"column 'I_a'.*did you mean 'I_arm'"):
        read_record(p, columns="time_s=t_ms [ms],current_A=I_a,speed_rpm=n_mot")


@pytest.mark.parametrize("header, message", [
    ("time_s,current_A,speed_rpm [furlong/fortnight]", r"column 'speed_rpm \[furlong/fortnight\]' \(read as "
                                                        r"speed_rpm\): unknown speed unit \[furlong/fortnight\]"),
    ("time_s,current_A,speed_rpm [A]", r"unit \[A\] is a current unit, but the column is read as speed_rpm"),
    ("time_s,current_A,speed_rpm [1/s]", r"\[1/s\] is ambiguous \(rev/s or rad/s"),
    ("t [ms],I [A],n [rpm]", r"missing column 'time_s' \[s\].*--columns time_s=t,current_A=I,speed_rpm=n"),
])
def test_unit_and_header_errors_name_file_column_and_fix(tmp_path, header, message):
    rec = _record(n=300)
    p = tmp_path / "r.csv"
    p.write_text(header + "\n" + "\n".join(f"{a},{b},{c}" for a, b, c in zip(rec["t"], rec["I"], rec["n"])))
    with pytest.raises(DataError, match=message):
        read_record(p)


def test_column_mapping_errors():
    assert parse_columns("current_A=I_arm, time_s = t [ms]") == {"current_A": "I_arm", "time_s": "t [ms]"}
    with pytest.raises(ConfigFileError, match="unknown channel 'current'.*did you mean 'current_A'"):
        parse_columns("current=I_arm")
    with pytest.raises(ConfigFileError, match="has no '='"):
        parse_columns("current_A:I_arm")
    with pytest.raises(ConfigFileError, match="mapped twice"):
        parse_columns("current_A=a,current_A=b")
    assert split_unit("n_mot (1/min)") == ("n_mot", "1/min") and split_unit("speed (motor)") == ("speed (motor)", None)


@pytest.mark.parametrize("dt_s, n", [(0.02, 2000), (0.001, 40000)])
def test_milliseconds_read_as_seconds_are_caught(tmp_path, dt_s, n):
    # issue 11: a 40 s record whose time is in ms looked like an 11-hour record; 50 Hz trips the sample-step
    # check (20 "s" steps over a 6.8 s ramp), 1 kHz the span check (40 000 "s")
    rec = _record(n=n, dt_s=dt_s)
    p = tmp_path / "ms.csv"
    p.write_text("time_s,current_A,speed_rpm\n" + "\n".join(
        f"{1000 * a:.3f},{b},{c}" for a, b, c in zip(rec["t"], rec["I"], rec["n"])))
    with pytest.raises(DataError, match=r"ms.csv: column 'time_s': .*looks like milliseconds \(read in ms: step "
                                        rf"{1000 * dt_s:g} ms, span 40 s[;)]"):
        read_record(p)
    m = read_record(p, columns="time_s=time_s [ms]")
    assert m.duration == pytest.approx(dt_s * (n - 1))


def test_a_log_of_hours_is_refused_as_a_record_but_read_as_a_log(tmp_path):
    t = np.arange(0.0, 7300.0, 1.0)
    p = tmp_path / "shift.csv"
    p.write_text("time_s,current_A,speed_rpm\n" + "\n".join(f"{a},{800.0},{500.0}" for a in t))
    # the speed never rises, so the time unit cannot be told from the data: both readings are offered
    with pytest.raises(DataError, match=r"spans 2.03 h .*split-startups.*\[ms\]"):
        read_record(p)
    assert read_record(p, log=True).duration == 7299.0


# --- split-startups -------------------------------------------------------------------------
def _concat(recs):
    """Concatenate records on one time axis (each continues one sample after the last)."""
    out, t_next = {k: [] for k in recs[0]}, 0.0
    for r in recs:
        shift = t_next - r["t"][0]
        for k in r:
            out[k].append(r[k] + (shift if k == "t" else 0.0))
        t_next = out["t"][-1][-1] + (r["t"][1] - r["t"][0])
    return {k: np.concatenate(v) for k, v in out.items()}


def _write_log(path, log, ref=True):
    cols = ["t", "I", "n"] + (["ref"] if ref else [])
    path.write_text("time_s,current_A,speed_rpm" + (",speed_ref_rpm" if ref else "") + "\n" + "\n".join(
        ",".join(repr(float(log[c][k])) for c in cols) for k in range(log["t"].size)) + "\n")


def test_a_concatenation_of_known_records_splits_back_into_them(tmp_path):
    recs = [_record(ramp_at=1.5, rate=74.0, n=1500, seed=1), _record(ramp_at=3.0, rate=50.0, n=2000, seed=2),
            _record(ramp_at=2.0, rate=120.0, top=480.0, n=1200, seed=3, i_run=700.0)]
    p = tmp_path / "log.csv"
    _write_log(p, _concat(recs))
    before = _sha(p)
    out = tmp_path / "records"
    # --pre longer than any rest and --length longer than any record: the cuts are the concatenation seams
    assert main(["split-startups", str(p), "--out", str(out), "--pre", "10", "--length", "1000"]) == 0
    files = sorted(out.iterdir())
    assert [f.name for f in files] == ["startup_01.csv", "startup_02.csv", "startup_03.csv"]
    for f, rec in zip(files, recs):
        _same(read_record(f), rec, t_tol=1e-9, rtol=1e-11)
    assert _sha(p) == before


def test_split_finds_each_ramp_start_in_a_log_with_stops_idle_time_and_a_gap(tmp_path):
    # truth: the ramp starts the test puts into the log; between start-ups the drive ramps down and stands still
    rng = np.random.default_rng(7)
    dt_s, pieces, starts, t = 0.02, [], [], 0.0
    for k, (idle, rate) in enumerate([(30.0, 74.0), (200.0, 60.0), (45.0, 90.0)]):
        n = int(round((idle + 40.0) / dt_s))
        tt = t + dt_s * np.arange(n)
        ramp = t + idle
        starts.append(ramp)
        up = np.clip(rate * (tt - ramp), 0, 500)
        down = np.clip(500 - 100 * (tt - ramp - 32.0), 0, 500) if k < 2 else 500
        ref = np.minimum(up, down)
        pieces.append({"t": tt, "ref": ref, "n": np.maximum(0, ref - 2) + 0.3 * rng.standard_normal(n),
                       "I": 50 + 800 * (ref > 0) + 3 * rng.standard_normal(n)})
        t = tt[-1] + dt_s + (600.0 if k == 0 else 0.0)  # a 10-minute logger pause after the first start-up
    log = {c: np.concatenate([q[c] for q in pieces]) for c in pieces[0]}
    p = tmp_path / "log.csv"
    _write_log(p, log)
    for by, tol in (("ref", dt_s), ("speed", 0.1)):  # the speed lags the reference by 2 rpm / rate
        found = split_startups(read_record(p, log=True), Parameters(), by=by)
        assert len(found) == 3, found.summary_lines()
        for s, ramp in zip(found.items, starts):
            assert s.ramp_start == pytest.approx(ramp, abs=tol), (by, s)
            assert s.start == pytest.approx(s.ramp_start - 2.0, abs=dt_s)  # --pre 2 s
            assert s.end <= s.ramp_start + 60.0 + 1e-9  # --length 60 s
        # these two slow down (100 rpm/s) 32 s after their ramp: cut 1 s before, give or take the 2 % band
        # that marks the running level (2 % x 500 rpm / 100 rpm/s = 0.1 s)
        for s, ramp in zip(found.items[:2], starts):
            assert ramp + 30.9 < s.end <= ramp + 32.0 - 1.0 + 0.1 + 1e-9


def test_split_writes_all_or_nothing_and_skips_what_is_not_a_record(tmp_path, capsys):
    # the last start-up is only 1.6 s long (it passes half speed at 0.9 s): not a record
    recs = [_record(n=1500, seed=1), _record(n=1500, seed=2), _record(ramp_at=0.2, rate=400.0, n=80, seed=3)]
    p = tmp_path / "log.csv"
    _write_log(p, _concat(recs))
    out = tmp_path / "out"
    out.mkdir()
    (out / "mine.txt").write_text("keep")
    assert main(["split-startups", str(p), "--out", str(out)]) == 2
    assert "not empty" in capsys.readouterr().err and [f.name for f in out.iterdir()] == ["mine.txt"]
    found = split_startups(read_record(p, log=True))
    assert len(found) == 2 and "too short" in found.skipped[0]
    assert main(["split-startups", str(p), "--dry-run"]) == 0
    text = capsys.readouterr().out
    assert "2 start-up(s) found by the speed_ref" in text and "skipped: the start-up at t = 60.200 s" in text
    assert main(["split-startups", str(p)]) == 2
    assert "give --out DIR" in capsys.readouterr().err
    assert main(["split-startups", str(p), "--by", "ref", "--out", str(tmp_path / "x"),
                 "--columns", "speed_ref_rpm=nope"]) == 2
    assert "no column 'nope'" in capsys.readouterr().err and not (tmp_path / "x").exists()


@pytest.mark.parametrize("name, message", [
    ("r.xlsx", r"r.xlsx: not a readable Excel workbook"),
    ("r.parquet", r"r.parquet: not a readable Parquet file"),
    ("r.mat", r"r.mat: not a readable MATLAB .mat file"),
])
def test_a_damaged_binary_file_is_a_clear_error(tmp_path, name, message):
    p = tmp_path / name
    p.write_text("time_s,current_A,speed_rpm\n0,1,2\n")  # a CSV under the wrong suffix
    with pytest.raises(DataError, match=message):
        read_record(p)


def test_a_mat_file_without_vectors_says_what_layout_is_read(tmp_path):
    import scipy.io

    p = tmp_path / "r.mat"
    scipy.io.savemat(p, {"name": "kiln 2", "gain": 2.0})
    with pytest.raises(DataError, match=r"no numeric vector in the file; kilnctl reads one variable per channel"):
        read_record(p)


def test_a_log_at_standstill_reads_and_says_why_nothing_was_found(tmp_path, capsys):
    # an hour of standstill with sensor noise around zero: a valid log (no kiln-speed or sign complaint), no start-up
    rng = np.random.default_rng(3)
    t = np.arange(0.0, 3600.0, 0.5)
    p = tmp_path / "idle.csv"
    p.write_text("time_s,current_A,speed_rpm\n" + "\n".join(
        f"{a},{800 + b},{c}" for a, b, c in zip(t, rng.standard_normal(t.size), 0.05 * rng.standard_normal(t.size))))
    found = split_startups(read_record(p, log=True))
    assert len(found) == 0 and "to above 250 rpm" in found.why_none()
    assert main(["split-startups", str(p), "--out", str(tmp_path / "o")]) == 2
    assert "no start-up found, nothing written; a start-up rises from rest" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()


def test_a_log_with_a_dead_current_tag_writes_no_record(tmp_path, capsys):
    """A log whose current tag was not logged (0 at every sample) yields no record, and says why.

    Truth: the test writes the current as 0 A at every sample; a start-up draws current (breakaway, acceleration),
    so a cut record would have a flat current and no defined fit % (it was written, and compare printed -inf %).
    """
    log = _concat([_record(n=1500, seed=1), _record(n=1500, seed=2)])
    log["I"] = np.zeros_like(log["I"])
    p = tmp_path / "log.csv"
    _write_log(p, log)
    found = split_startups(read_record(p, log=True))
    assert len(found) == 0 and len(found.skipped) == 2
    assert all("column 'current_A' is 0 A at every one of its" in s and "dead channel" in s for s in found.skipped)
    assert main(["split-startups", str(p), "--out", str(tmp_path / "o")]) == 2
    assert "dead channel" in capsys.readouterr().err and not (tmp_path / "o").exists()


def test_a_units_row_keeps_the_header_line_number(tmp_path):
    """Under a units row, messages name the header's own line and the units' line.

    Truth: the file the test writes has its header on line 1 and the units on line 2 (it said 'line 2 (header)
    and 2 (units)', and 'the header (line 2)' for a short row).
    """
    rec = _record()
    rows = [f"{_r(a)};{_r(b)};{_r(c)}" for a, b, c in zip(rec["t"], rec["I"], rec["n"])]
    p = tmp_path / "r.csv"
    p.write_text("Zeit;I_arm;n_mot\ns;A;1/min\n" + "\n".join(rows) + "\n")
    with pytest.raises(DataError, match=r"r.csv: line 1 \(header\) and 2 \(units\): missing column 'time_s'"):
        read_record(p)
    p.write_text("time_s;current_A;speed_rpm\ns;A;1/min\n" + "\n".join(rows[:5] + ["1;2"] + rows[5:]) + "\n")
    with pytest.raises(DataError, match=r"r.csv: line 8: 2 cells, but the header \(line 1\) has 3 columns"):
        read_record(p)
