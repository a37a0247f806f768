"""Cut a long log of the plant into start-up records.

A historian or trace-tool export often holds several start-ups (and hours of
running or standstill between them).  :func:`split_startups` finds each
start-up from rest -- by the speed reference when the log has one, else by the
rise of the measured speed -- and :meth:`Startups.write` writes one kilnctl
record per start-up (``startup_01.csv`` ...), all of them or none.  The log is
only read.

A start-up is where the signal (reference or speed) leaves rest, below
``REST_FRACTION`` x ``omega_ref``, and goes on to exceed ``RUN_FRACTION`` x
``omega_ref``; it must have been at rest again before the next one counts.
Each record begins ``pre_s`` before the ramp starts (not before the rest that
precedes it began) and ends ``length_s`` after it, where the drive slows down
again (``STOP_MARGIN_S`` before the signal leaves its running level on the way
below ``STOP_FRACTION`` of it), where
the next record begins, at a gap in the log, or where the log ends.
"""

from __future__ import annotations

import math
import os
import shutil
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import DataError
from ..params import Parameters
from .io import Measurement, _check_dead, _checked

__all__ = ["Startup", "Startups", "split_startups", "REST_FRACTION", "RUN_FRACTION", "STOP_FRACTION"]

#: a signal below this fraction of omega_ref is at rest
REST_FRACTION = 0.02
#: a start-up counts once the signal exceeds this fraction of omega_ref
RUN_FRACTION = 0.5
#: a record ends where the signal falls below this fraction of its running level (the drive slows down)
STOP_FRACTION = 0.9
#: and this long before the slow-down began [s]
STOP_MARGIN_S = 1.0


@dataclass(frozen=True)
class Startup:
    """One start-up found in a log.

    Attributes
    ----------
    i0, i1 : int
        Samples ``i0 .. i1 - 1`` of the log form the record.
    ramp_start : float
        Where the signal leaves rest, in log time [s].
    start, end : float
        Time of the first and last sample of the record, in log time [s].
    rows : tuple of int
        First and last line (row, sample) of the record in the log file.
    peak_speed_rpm : float
        Largest measured motor speed in the record [rpm].
    """

    i0: int
    i1: int
    ramp_start: float
    start: float
    end: float
    rows: tuple
    peak_speed_rpm: float

    def to_dict(self) -> dict:
        """Return the start-up as a JSON-ready dictionary (times in log seconds)."""
        return {"start_s": self.start, "end_s": self.end, "ramp_start_s": self.ramp_start,
                "duration_s": self.end - self.start, "first_row": self.rows[0], "last_row": self.rows[1],
                "n_samples": self.i1 - self.i0, "peak_speed_rpm": self.peak_speed_rpm}


class Startups:
    """The start-ups found in a log (build it with :func:`split_startups`).

    Attributes
    ----------
    log : Measurement
        The whole log.
    items : list of Startup
        The start-ups, in time order.
    by : str
        The signal the start-ups were found on: ``speed_ref_rpm`` or ``speed_rpm``.
    skipped : list of str
        Rises that were not taken, and why (the log starts in motion, a record
        that fails the checks of a start-up record: too short, a gap).
    """

    def __init__(self, log: Measurement, items, by: str, skipped, params: Parameters):
        self.log, self.by, self.skipped = log, by, list(skipped)
        self._params, self._row_word = params, log.row_word
        self.items, self._records = [], []
        for s in items:  # a start-up that is not a usable record is skipped, with the reason
            try:
                self._records.append(self._record(s, len(self.items) + 1))
                self.items.append(s)
            except DataError as exc:
                self.skipped.append(f"the start-up at t = {s.ramp_start:.3f} s ({self._row_word}s {s.rows[0]}-"
                                    f"{s.rows[1]}): {str(exc).split(': ', 1)[-1]}")

    def _record(self, s: Startup, n: int) -> Measurement:
        arrays = {"time_s": self.log.t[s.i0:s.i1]}
        arrays.update({k: v[s.i0:s.i1] for k, v in self.log.channels.items()})
        src = f"{self.log.source} start-up {n} ({self._row_word}s {s.rows[0]}-{s.rows[1]})"
        rec = _checked(arrays, self.log.lines[s.i0:s.i1], src, self._params,
                       (f"start-up {n} of {self.log.source}, ramp from t = {s.ramp_start:.3f} s",),
                       row_word=self._row_word)
        _check_dead(rec.channels, src)
        return rec

    def __len__(self) -> int:
        return len(self.items)

    def records(self) -> list[Measurement]:
        """Return each start-up as a checked record (the checks of :func:`kilnctl.measure.read_record`).

        Returns
        -------
        list of Measurement
            One per start-up, with the log's time and line numbers.
        """
        return list(self._records)

    def why_none(self) -> str:
        """Say why no start-up was found (empty when some were).

        Returns
        -------
        str
            The levels a start-up must cross and what the signal did.
        """
        if self.items:
            return ""
        sig = self.log.channels[self.by]
        lo, hi = REST_FRACTION * self._params.omega_ref, RUN_FRACTION * self._params.omega_ref
        what = (f"a start-up rises from rest (below {lo:.4g} rpm) to above {hi:.4g} rpm (2 % and 50 % of the "
                f"setup's omega_ref = {self._params.omega_ref:g} rpm); {self.by} ranges from {sig.min():.4g} to "
                f"{sig.max():.4g} rpm")
        return what + ("; " + "; ".join(self.skipped) if self.skipped else "")

    def to_dict(self) -> dict:
        """Return the split as JSON-ready data."""
        return {"log": self.log.source, "by": self.by, "n_startups": len(self.items),
                "startups": [s.to_dict() for s in self.items], "skipped": list(self.skipped)}

    def summary_lines(self) -> list[str]:
        """Return a short table of the start-ups found."""
        lines = [f"{self.log.source}: {len(self.items)} start-up(s) found by the {self.by.replace('_rpm', '')} "
                 f"({self.log.n} samples over {self.log.duration:.1f} s)"]
        if self.items:
            lines.append(f"  {'#':>3} {'start [s]':>11} {'ramp at [s]':>11} {'length [s]':>10} {'peak [rpm]':>10}"
                         f"  {self._row_word}s")
        for n, s in enumerate(self.items, start=1):
            lines.append(f"  {n:>3} {s.start:>11.3f} {s.ramp_start:>11.3f} {s.end - s.start:>10.2f} "
                         f"{s.peak_speed_rpm:>10.1f}  {s.rows[0]}-{s.rows[1]}")
        lines += [f"  skipped: {k}" for k in self.skipped]
        if not self.items:
            lines.append(f"  {self.why_none()}")
        return lines

    def write(self, out_dir, protect=()) -> list[Path]:
        """Write ``startup_NN.csv`` per start-up into a new or empty folder, all of them or none.

        Parameters
        ----------
        out_dir : path-like
            Destination folder; it must not exist or be empty (kilnctl never
            overwrites a record).
        protect : sequence of path-like, optional
            Files that must not be inside ``out_dir`` (the log itself).

        Returns
        -------
        list of pathlib.Path
            The files written.

        Raises
        ------
        DataError
            No start-up to write, or the folder is a file, not empty, or
            holds the log (then nothing is written).
        """
        out_dir = Path(out_dir)
        if not self.items:
            raise DataError(f"{self.log.source}: no start-up found, nothing written; {self.why_none()}")
        if out_dir.exists() and not out_dir.is_dir():
            raise DataError(f"--out {out_dir} is a file: give a folder")
        if out_dir.is_dir() and any(out_dir.iterdir()):
            raise DataError(f"--out {out_dir} is not empty: give a new or empty folder (kilnctl never overwrites "
                            "a record)")
        for p in protect:
            if p and Path(p).resolve().parent == out_dir.resolve():
                raise DataError(f"--out {out_dir} holds the log {p}: give another folder")
        texts = {f"startup_{n:02d}.csv": self._text(n, rec) for n, rec in enumerate(self.records(), start=1)}
        parent = out_dir.resolve().parent
        try:
            parent.mkdir(parents=True, exist_ok=True)
            tmp = Path(tempfile.mkdtemp(dir=parent, prefix=".tmp-split-"))
        except OSError as exc:  # a file in the way, a read-only folder: nothing is written
            raise DataError(f"--out {out_dir}: cannot make the folder ({exc.strerror or exc}); give a folder path "
                            "you may write into") from None
        try:
            for name, text in texts.items():
                (tmp / name).write_text(text)
            if not out_dir.exists():
                os.rename(tmp, out_dir)  # one step: the folder appears whole
            else:
                moved = []
                try:
                    for name in texts:
                        os.replace(tmp / name, out_dir / name)
                        moved.append(out_dir / name)
                except BaseException:
                    for p in moved:
                        p.unlink(missing_ok=True)
                    raise
        except OSError as exc:  # a full disk, a folder made read-only meanwhile: nothing is left behind
            raise DataError(f"--out {out_dir}: cannot write the records ({exc.strerror or exc}); nothing was written; "
                            "give a folder you may write into") from None
        finally:
            shutil.rmtree(tmp, ignore_errors=True)
        return [out_dir / name for name in texts]

    def _text(self, n: int, rec: Measurement) -> str:
        s = self.items[n - 1]
        head = (f"# start-up {n} of {len(self.items)} cut from {self.log.source} by kilnctl split-startups\n"
                f"# {self._row_word}s {s.rows[0]}-{s.rows[1]} of the log; time is log time; ramp starts at "
                f"t = {s.ramp_start:.6f} s\n")
        return head + rec.to_csv(digits=12)


def split_startups(log: Measurement, params: Parameters | None = None, *, by: str = "auto", pre_s: float = 2.0,
                   length_s: float = 60.0) -> Startups:
    """Find the start-ups from rest in a long log.

    Parameters
    ----------
    log : Measurement
        The log, read with ``read_record(path, log=True)`` (gaps allowed).
    params : Parameters, optional
        Setup: ``omega_ref`` [rpm] sets the rest and run levels,
        ``ramp_rate`` [rpm/s] dates the ramp start from the speed.
    by : {'auto', 'ref', 'speed'}, default 'auto'
        Signal to cut by: the speed reference (``auto`` when the log has
        ``speed_ref_rpm``) or the measured speed.
    pre_s : float, default 2.0
        Time kept before the ramp starts [s] (at rest; the model starts there).
    length_s : float, default 60.0
        Longest record, from the ramp start [s].

    Returns
    -------
    Startups

    Raises
    ------
    DataError
        ``by='ref'`` on a log without ``speed_ref_rpm``, a bad ``pre_s`` or ``length_s``.
    """
    Measurement.require(log, "split_startups", "log")
    params = Parameters() if params is None else params
    if by not in ("auto", "ref", "speed"):
        raise DataError(f"by={by!r}: use 'auto', 'ref' or 'speed'")
    for name, v in (("pre", pre_s), ("length", length_s)):
        if not (isinstance(v, (int, float)) and math.isfinite(v) and v >= 0):
            raise DataError(f"--{name} {v}: give a time in seconds >= 0")
    if length_s <= 0:
        raise DataError("--length 0: give the longest record in seconds (> 0)")
    if by == "ref" and log.speed_ref is None:
        raise DataError(f"{log.source}: --by ref, but the log has no speed_ref_rpm column (map yours with "
                        "--columns speed_ref_rpm=NAME, or cut by the speed: --by speed)")
    use_ref = log.speed_ref is not None and by != "speed"
    sig = log.speed_ref if use_ref else log.speed
    lo, hi = REST_FRACTION * params.omega_ref, RUN_FRACTION * params.omega_ref
    t, n = log.t, log.n
    idx = np.arange(n)
    below, above = sig <= lo, sig >= hi
    last_below = np.maximum.accumulate(np.where(below, idx, -1))
    last_moving = np.maximum.accumulate(np.where(~below, idx, -1))
    ups = np.nonzero(above & np.concatenate(([True], ~above[:-1])))[0]
    found, skipped = [], []
    prev_hi = -1
    for k in ups:
        lb = int(last_below[k])
        if lb < 0:
            skipped.append(f"a rise at t = {t[k]:.3f} s: the log starts in motion (no rest before it)")
            continue
        if lb < prev_hi:  # never back at rest since the last start-up
            continue
        prev_hi = int(k)
        first_up = lb + 1
        rest_from = int(last_moving[lb]) + 1
        # the ramp left zero sig/rate before the first sample above rest, at the rate the signal rises
        # between that sample and the run level (the setup's rate if it does not rise)
        rise = float(sig[k] - sig[first_up]) / max(float(t[k] - t[first_up]), 1e-12)
        rate = rise if (k > first_up and rise > 0) else params.ramp_rate
        ramp = max(float(t[rest_from]), float(t[first_up]) - (float(sig[first_up]) / rate if rate > 0 else 0.0))
        i0 = max(rest_from, int(np.searchsorted(t, ramp - pre_s - 1e-9 * max(1.0, abs(ramp)), side="left")))
        found.append((i0, ramp, int(k)))
    items = []
    for j, (i0, ramp, k) in enumerate(found):
        i1 = int(np.searchsorted(t, ramp + length_s, side="right"))
        if j + 1 < len(found):
            i1 = min(i1, found[j + 1][0])
        # a record stops where the drive slows down again: the signal falls below STOP_FRACTION of its running level
        run = sig[k:i1]
        if run.size:
            level = float(np.percentile(run, 90))
            reached = np.nonzero(run >= STOP_FRACTION * level)[0]
            if reached.size:
                falls = np.nonzero(run[reached[0]:] < STOP_FRACTION * level)[0]
                if falls.size:  # the slow-down began after the last sample within 2 % of the level; keep
                    f = int(reached[0]) + int(falls[0])  # STOP_MARGIN_S less (the current drops before the speed)
                    still = np.nonzero(run[:f] >= 0.98 * level)[0]
                    t_slow = float(t[k + (int(still[-1]) if still.size else f)])
                    i1 = min(i1, int(np.searchsorted(t, t_slow - STOP_MARGIN_S, side="right")))
        # a record stops at a gap in the log (a logger pause between start-ups)
        dts = np.diff(t[i0:i1])
        if dts.size:
            med = float(np.median(dts))
            gaps = np.nonzero(dts > 5.0 * med)[0]
            gaps = gaps[t[i0 + gaps] >= ramp]  # a gap before the ramp starts the record after it
            if gaps.size:
                i1 = i0 + int(gaps[0]) + 1
            pre_gaps = np.nonzero(dts > 5.0 * med)[0]
            pre_gaps = pre_gaps[t[i0 + pre_gaps + 1] <= ramp]
            if pre_gaps.size:
                i0 = i0 + int(pre_gaps[-1]) + 1
        items.append(Startup(i0, i1, ramp, float(t[i0]), float(t[i1 - 1]),
                             (int(log.lines[i0]), int(log.lines[i1 - 1])), float(np.max(log.speed[i0:i1]))))
    return Startups(log, items, "speed_ref_rpm" if use_ref else "speed_rpm", skipped, params)
