"""Measured records: CSV import, checks, and the setup file of the experiment.

A record is a CSV file with a header line and one row per sample::

    # optional comment lines (start with '#') may precede the header
    time_s,current_A,speed_rpm,speed_ref_rpm
    0.00,0.0,0.00,0.00
    0.02,41.7,1.21,1.48
    ...

``time_s`` [s], ``current_A`` [A] (armature current of the measured motor)
and ``speed_rpm`` [rpm] (motor speed) are required; ``speed_ref_rpm`` [rpm]
(the speed reference given to the drive) and any other numeric channel are
optional and kept.  The file is only read, never written.

The setup file is a kilnctl TOML parameter file (see ``kilnctl params``) that
states what was known about the experiment: PID gains, ramp, burden mass ...
It may carry one extra section, ``[measurement]``, read by this module only
(see :class:`Setup`).  The format is documented in ``docs/measurements.md``.
"""

from __future__ import annotations

import math
import os
import re
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Mapping

import numpy as np

from ..errors import ConfigFileError, DataError, ParameterError, close_matches_hint
from ..files import read_toml
from ..params import SPECS, Parameters
from ..units import RPM_PER_RAD_S
from .clipping import clipped_levels, clipped_notes, unclipped
from .glitches import glitch_mask, glitch_notes, glitches
from .logger import frozen_notes, resampled_every, resampled_notes, sampling_notes, speed_step, speed_step_notes
from .reference import fit_knots, fit_scurve, scurve_values
from .standstill import standstill_offsets

__all__ = ["Measurement", "Setup", "Experiment", "read_csv", "read_record", "load_setup", "REQUIRED", "OPTIONAL",
           "MIN_DURATION_S", "MIN_SAMPLES", "GAP_FACTOR", "MAX_RECORD_S", "record_columns"]

#: columns every record must have, with their units
REQUIRED: dict[str, str] = {"time_s": "s", "current_A": "A", "speed_rpm": "rpm"}
#: optional columns kilnctl understands, with their units
OPTIONAL: dict[str, str] = {"speed_ref_rpm": "rpm"}
#: a record shorter than this says nothing about a start-up [s]
MIN_DURATION_S = 2.0
#: nor one with fewer samples than this
MIN_SAMPLES = 50
#: a time step larger than GAP_FACTOR x the median step is a gap
GAP_FACTOR = 5.0



#: time after the ramp's end for the speed loop to settle [s] (see Experiment.steady_from)
SETTLE_S = 1.5


@dataclass(frozen=True)
class Experiment:
    """What the simulation of a record must reproduce: start time and speed reference.

    Attributes
    ----------
    t0 : float
        Time in the record at which the start-up (speed reference ramp) begins [s].
        Samples before it are not compared (the model is at rest).
    ramp_rate : float
        Rate of rise of the speed reference [rpm/s].
    omega_ref : float
        Final speed reference [rpm].
    source : str
        Where these come from: ``setup`` or ``recorded speed_ref_rpm``.
    notes : tuple of str
        What was inferred and any disagreement with the setup file.
    jerk : float or None
        Jerk limit of a recorded S-curve reference [rpm/s^2] (then
        ``ramp_rate`` is its acceleration limit, and the model's reference is
        the S-curve, component ``ramp_scurve``; see
        :mod:`kilnctl.measure.reference`), or None for a straight ramp.
    knots : tuple of (float, float) or None
        Knots (t_k [s] from ``t0``, w_k [rpm]) of a recorded reference that is
        not one ramp and hold (two rates, a second ramp, a ramp down): the
        model's reference runs through them from rest and holds the last
        (component ``ramp_knots<K>``, :func:`~kilnctl.measure.reference.fit_knots`);
        ``ramp_rate`` is then the first segment's rate and ``omega_ref`` the
        highest knot.  None otherwise.
    held : bool
        The drive holds the kiln at rest before the start: the record's current at standstill lies away from
        zero (:func:`~kilnctl.measure.standstill.standstill_offsets`), so the model starts held by its speed loop
        (:func:`kilnctl.model.rest.held_state`: an unbalance's holding current) rather than from zero current.
        A drive switched on before the ramp shows it; so does a current sensor's offset, for which it changes
        nothing (a model without a load at rest holds it with zero current).
    """

    t0: float
    ramp_rate: float
    omega_ref: float
    source: str
    notes: tuple = ()
    jerk: float | None = None
    knots: tuple | None = None
    held: bool = False

    @property
    def ramp_end(self) -> float:
        """Record time at which the speed reference reaches ``omega_ref`` [s] (``t0`` without a ramp); with
        knots, the first time it comes within 2 % of its highest value."""
        if self.knots:
            top = max(w for _, w in self.knots)
            return self.t0 + next(t for t, w in self.knots if w >= 0.98 * top)
        if self.jerk is not None:
            from ..model.ramps import scurve_timing

            return self.t0 + float(scurve_timing(self.ramp_rate, self.jerk, self.omega_ref)[2])
        return self.t0 + (self.omega_ref / self.ramp_rate if self.ramp_rate > 0 else 0.0)

    @property
    def steady_from(self) -> float:
        """Record time from which the drive runs at its set speed [s]: the ramp's end plus
        :data:`SETTLE_S` for the speed loop to settle (stick-slip cycles, abrupt changes and the residual's
        signature are looked for from there)."""
        return self.ramp_end + SETTLE_S

    def to_dict(self) -> dict:
        """Return the experiment as a JSON-ready dictionary."""
        return {"t0_s": self.t0, "ramp_rate_rpm_per_s": self.ramp_rate, "omega_ref_rpm": self.omega_ref,
                "jerk_rpm_per_s2": self.jerk,
                "knots": None if self.knots is None else [{"t_s": t, "rpm": w} for t, w in self.knots],
                "source": self.source, "notes": list(self.notes), "held": self.held}


@dataclass(frozen=True, eq=False)
class Measurement:
    """A checked measured record of a kiln start-up.

    Build it with :func:`read_csv` or :meth:`from_arrays`; both run the same
    checks.

    Attributes
    ----------
    t : ndarray
        Sample times [s], strictly increasing.
    channels : dict of str to ndarray
        ``current_A`` [A], ``speed_rpm`` [rpm], and optional ``speed_ref_rpm``
        [rpm] and other columns, one value per sample.
    source : str
        File the record came from (or ``<arrays>``).
    lines : ndarray of int
        File line number of each sample (for messages).
    notes : tuple of str
        Remarks made while reading (comment lines, ignored columns).
    row_word : str
        What ``lines`` counts: ``line`` (text file), ``row`` (spreadsheet,
        Parquet) or ``sample`` (MATLAB file, arrays).
    clipped : tuple of ClipLevel
        Channels the logger clipped at the end of its range
        (:func:`~kilnctl.measure.clipping.clipped_levels`); their samples at
        the level are left out of fits, evidence and fit % (:attr:`unclipped`).
    glitches : tuple of Glitch
        Isolated spikes of one or two samples (:func:`~kilnctl.measure.glitches.glitches`);
        their samples are left out of fits, evidence and fit % too (:attr:`kept`).
    """

    t: np.ndarray
    channels: Mapping[str, np.ndarray]
    source: str = "<arrays>"
    lines: np.ndarray | None = None
    notes: tuple = ()
    row_word: str = "line"
    clipped: tuple = ()
    glitches: tuple = ()

    # --- construction ---------------------------------------------------------
    @classmethod
    def from_arrays(cls, t, current_A, speed_rpm, speed_ref_rpm=None, *, extra=None,
                    source: str = "<arrays>", params: Parameters | None = None) -> "Measurement":
        """Build a checked measurement from arrays.

        Parameters
        ----------
        t : array_like
            Sample times [s].
        current_A : array_like
            Armature current [A].
        speed_rpm : array_like
            Motor speed [rpm].
        speed_ref_rpm : array_like, optional
            Speed reference [rpm].
        extra : dict of str to array_like, optional
            More channels, kept as they are.
        source : str, default '<arrays>'
            Name used in messages.
        params : Parameters, optional
            Setup of the experiment, used by the unit checks (``omega_ref``, ``I_max``).

        Returns
        -------
        Measurement

        Raises
        ------
        DataError
            On any failed check (the message names the row and the column).
        """
        cols = {"time_s": t, "current_A": current_A, "speed_rpm": speed_rpm}
        if speed_ref_rpm is not None:
            cols["speed_ref_rpm"] = speed_ref_rpm
        cols.update(extra or {})
        arrays = {}
        n = None
        for name, v in cols.items():
            a = np.asarray(v, dtype=float).ravel()
            if n is None:
                n = a.size
            elif a.size != n:
                raise DataError(f"{source}: channel {name!r} has {a.size} samples, time_s has {n}")
            arrays[name] = a
        lines = np.arange(n) + 1  # "row" numbers for arrays
        return _checked(arrays, lines, source, params, notes=(), row_word="sample")

    # --- access ------------------------------------------------------------------
    @property
    def current(self) -> np.ndarray:
        """Armature current [A]."""
        return self.channels["current_A"]

    @property
    def speed(self) -> np.ndarray:
        """Motor speed [rpm]."""
        return self.channels["speed_rpm"]

    @property
    def speed_ref(self) -> np.ndarray | None:
        """Speed reference [rpm], or None if not recorded."""
        return self.channels.get("speed_ref_rpm")

    @property
    def unclipped(self) -> np.ndarray:
        """Mask of the samples where no channel sits at a level the logger clipped it at (:attr:`clipped`):
        the samples fits, evidence and fit % use."""
        keep = unclipped(self.clipped, self.channels)
        return np.ones(self.t.size, bool) if keep is None else keep

    @property
    def unspiked(self) -> np.ndarray:
        """Mask of the samples outside the logger's spikes (:attr:`glitches`): where stick-slip falls are
        looked for (a spike falls back as sharply as a breakaway)."""
        return glitch_mask(self.glitches, self.t.size)

    @property
    def kept(self) -> np.ndarray:
        """Mask of the samples fits, evidence, fit % and failing intervals use: none clipped (:attr:`unclipped`)
        and none in a spike (:attr:`unspiked`)."""
        return self.unclipped & self.unspiked

    @property
    def n(self) -> int:
        """Number of samples."""
        return int(self.t.size)

    @property
    def duration(self) -> float:
        """Length of the record [s]."""
        return float(self.t[-1] - self.t[0])

    @property
    def dt(self) -> float:
        """Median sample step [s]."""
        return float(np.median(np.diff(self.t)))

    def experiment(self, params: Parameters, t0: float | None = None) -> Experiment:
        """Infer the start time and speed reference of the start-up.

        With a recorded ``speed_ref_rpm`` the ramp is fitted to it (start time,
        rate, final value); the recorded values win over the setup when they
        differ by more than 2 %, and a note says so.  A recorded reference
        whose corners are rounded (a drive's jerk limit) is fitted by an
        S-curve, which the model then follows when it fits much better than
        the straight ramp (:func:`~kilnctl.measure.reference.fit_scurve`).  Without it, the ramp of
        the setup is used, starting where the measured speed passes 2 % of
        ``omega_ref`` less the time the setup's model takes to get there from rest (or
        at ``t0``).

        Parameters
        ----------
        params : Parameters
            Setup of the experiment (``ramp_rate`` [rpm/s], ``omega_ref`` [rpm]).
        t0 : float, optional
            Start of the ramp in record time [s], if known (setup file
            ``[measurement] t0_s``); otherwise inferred.

        Returns
        -------
        Experiment

        Raises
        ------
        ParameterError
            ``t0`` is not a finite number, or leaves less than a record (:data:`MIN_SAMPLES` samples over
            :data:`MIN_DURATION_S`) after it.
        """
        exp = self._start_up(params, t0)
        # the current at standstill away from zero: the drive holds the kiln at rest (Experiment.held)
        held = any(o["channel"] == "current_A" for o in standstill_offsets(self, exp))
        return replace(exp, held=True) if held else exp

    def _start_up(self, params: Parameters, t0: float | None) -> Experiment:
        """The start time and speed reference of :meth:`experiment`, without ``held``."""
        if t0 is not None:
            t0 = self._checked_t0(t0)
        ref = self.speed_ref
        notes = []
        if ref is None:
            if t0 is not None:
                start, how = float(t0), "the setup's t0_s"
            else:
                start, how = self._start_from_speed(params), "the first rise of the measured speed"
            return Experiment(start, params.ramp_rate, params.omega_ref, "setup",
                              (f"no speed_ref_rpm recorded: the setup's ramp is assumed to start at t = {start:.3f} s "
                               f"(from {how})",))
        top = float(np.median(ref[ref >= np.percentile(ref, 90)]))
        if not np.isfinite(top) or top <= 0:
            start = float(self.t[0]) if t0 is None else float(t0)
            return Experiment(start, params.ramp_rate, params.omega_ref, "setup",
                              ("recorded speed_ref_rpm never rises above zero: the setup's ramp is used",))
        rising = (ref > 0.1 * top) & (ref < 0.9 * top)
        if rising.sum() >= 3:
            rate, icpt = np.polyfit(self.t[rising], ref[rising], 1)
            fit_err = np.std(ref[rising] - (rate * self.t[rising] + icpt)) / top
        else:  # a step: the reference jumps within one sample
            rate, icpt, fit_err = math.inf, 0.0, 0.0
        if not (rate > 0) or fit_err > 0.05:
            notes.append(f"recorded speed_ref_rpm is not a straight ramp (scatter {100 * fit_err:.0f} % of "
                         "the final value): the model still uses a straight ramp")
        if math.isfinite(rate) and rate > 0:
            start = -icpt / rate
        else:
            start = float(self.t[np.argmax(ref > 0.5 * top)])
            rate = max(top / max(self.dt, 1e-6), params.ramp_rate)
        shape = fit_scurve(self.t, ref, top, rate, start) if math.isfinite(rate) and rate > 0 else None
        jerk = None
        if shape is not None:
            start, rate, jerk = shape.t0, shape.a, shape.j
            notes = [f"recorded speed_ref_rpm is an S-curve with rounded corners (acceleration {rate:.4g} "
                     f"rpm/s, reached in {shape.rounding_s:.2f} s; fits the record to {shape.rms:.2g} rpm RMS "
                     f"where a straight ramp misses by {shape.rms_straight:.2g}): the model follows it"]
        before = (scurve_values(self.t, start, rate, jerk, top) if jerk is not None
                  else np.clip(rate * (self.t - start), 0.0, top) if math.isfinite(rate) else None)
        path = fit_knots(self.t, ref, start, before) if before is not None else None
        knots = None
        if path is not None:
            start, top, knots = path.t0, path.top, tuple(zip(path.times, path.values))
            rate, jerk = path.values[0] / path.times[0], None
            fits = "exactly" if path.rms < 0.01 else f"to {path.rms:.2g} rpm RMS"
            notes = [f"recorded speed_ref_rpm is not one ramp and hold: {path.describe()} (through "
                     f"{len(knots)} knot(s), which fit it {fits}, where a ramp and hold misses by "
                     f"{path.rms_before:.3g} rpm): the model follows it"]
        if t0 is not None:
            start = float(t0)
        start = max(start, float(self.t[0]))
        label = "first ramp rate" if knots else "peak ramp rate" if jerk else "ramp rate"
        for label, rec, setv, unit in ((label, rate, params.ramp_rate, "rpm/s"),
                                       ("final speed reference", top, params.omega_ref, "rpm")):
            if abs(rec - setv) > 0.02 * abs(setv):
                notes.append(f"recorded {label} {rec:.4g} {unit} differs from the setup's {setv:.4g} {unit}: "
                             "the recorded value is used")
        notes.append(f"start-up begins at t = {start:.3f} s (from the recorded speed reference)")
        return Experiment(float(start), float(rate), float(top), "recorded speed_ref_rpm", tuple(notes), jerk, knots)

    @staticmethod
    def require(measurement, where: str, name: str = "measurement") -> "Measurement":
        """Return ``measurement``, refused with the fix when it is not a :class:`Measurement` (a file name).

        Parameters
        ----------
        measurement : object
            What the caller was given.
        where : str
            The function or method, for the message (``compare``).
        name : str, default 'measurement'
            The argument's name, for the message.

        Returns
        -------
        Measurement

        Raises
        ------
        ParameterError
            Naming the argument, the type given and how to read a record.
        """
        if not isinstance(measurement, Measurement):
            hint = (f" (read the file first: {where}(read_record({str(measurement)!r}), ...))"
                    if isinstance(measurement, (str, Path)) else " (from kilnctl.measure.read_record(path))")
            raise ParameterError(f"{where}: {name} must be a kilnctl.measure.Measurement{hint}, "
                                 f"not {type(measurement).__name__}")
        return measurement

    def _checked_t0(self, t0) -> float:
        """``t0`` as a float, refused when it is not a time in the record with a record's worth of samples after it."""
        what = "t0 (the start of the start-up in record time; setup file: [measurement] t0_s)"
        try:
            value = float(t0)
        except (TypeError, ValueError):
            value = math.nan
        if isinstance(t0, bool) or not math.isfinite(value):
            raise ParameterError(f"{self.source}: {what} = {t0!r} must be a finite number of seconds")
        n_after = int(np.count_nonzero(self.t >= value - 1e-9))
        span = float(self.t[-1]) - value
        if n_after < MIN_SAMPLES or span < MIN_DURATION_S:
            raise ParameterError(
                f"{self.source}: {what} = {value:g} s leaves {n_after} sample(s) over {max(span, 0.0):.3g} s to "
                f"compare (the record runs from {self.t[0]:g} to {self.t[-1]:g} s; at least {MIN_SAMPLES} samples "
                f"and {MIN_DURATION_S:g} s are needed): give the time at which the ramp starts, or leave t0_s out "
                "to take it from the record")
        return value

    def _start_from_speed(self, params: Parameters) -> float:
        """Start of the ramp from the measured speed's first rise (the first sample if the record starts moving).

        The time at which the speed passes 2 % of omega_ref is found by a straight line through the samples
        between 1 % and 4 % of it (or between the two samples around it), which averages the noise and does
        not round to the sample step.  A drive's speed follows its reference with a lag, so the same crossing
        is found on the setup's own model started at t = 0 (same gains, inertias and ramp), and the ramp
        started that much earlier.  Without that correction the start came out 10-55 ms late on records of
        a foreign plant (30 ms is the lag of Table 1's drive with the example's gains), which cost up to
        8 points of current fit with the true model.
        """
        level = 0.02 * params.omega_ref
        w = self.speed
        if abs(w[0]) > level:
            return float(self.t[0])
        t_meas = _crossing(self.t, w, level)
        if t_meas is None:
            return float(self.t[0])
        return float(max(self.t[0], t_meas - _model_lag_to(level, params)))

    def to_dict(self) -> dict:
        """Return a JSON-ready description (not the samples).

        Returns
        -------
        dict
            ``source``, ``n_samples``, ``duration_s``, ``dt_s`` (median),
            ``channels`` with min and max of each, ``notes``.
        """
        return {"source": self.source, "n_samples": self.n, "duration_s": self.duration, "dt_s": self.dt,
                "channels": {k: {"min": float(v.min()), "max": float(v.max())} for k, v in self.channels.items()},
                "notes": list(self.notes)}

    def to_csv(self, path=None, digits: int = 6) -> str:
        """Write the record in the kilnctl CSV format (whole or not at all) and return the text.

        Parameters
        ----------
        path : path-like, optional
            Destination; refused if it exists (kilnctl never overwrites data).
        digits : int, default 6
            Significant digits of the channels (time: decimals).

        Returns
        -------
        str
            The CSV text.
        """
        from ..response import write_atomic

        names = ["time_s"] + list(self.channels)
        cols = [self.t] + [self.channels[k] for k in self.channels]
        rows = [",".join(names)]
        for k in range(self.n):
            rows.append(",".join(f"{c[k]:.{digits}g}" if j else f"{c[k]:.{digits}f}" for j, c in enumerate(cols)))
        text = "\n".join(rows) + "\n"
        if path is not None:
            if Path(path).exists():
                raise DataError(f"{path}: file exists; kilnctl does not overwrite a record")
            write_atomic(path, text)
        return text


# --- reading ---------------------------------------------------------------------
def _crossing(t, w, level):
    """Time [s] at which a rising speed first passes ``level`` [rpm]: a line through the samples between
    half and twice the level up to the first one above twice it (at least the two around the crossing)."""
    above = np.nonzero(w > level)[0]
    if above.size == 0:
        return None
    k = int(above[0])
    if k == 0:
        return float(t[0])
    hi = np.nonzero(w > 2.0 * level)[0]
    end = int(hi[0]) if hi.size else w.size
    lo = k - 1
    while lo > 0 and w[lo - 1] > 0.5 * level and w[lo - 1] < w[lo]:
        lo -= 1
    sel = slice(lo, max(end, k + 1))
    tt, ww = t[sel], w[sel]
    if tt.size >= 3:
        slope, icpt = np.polyfit(tt - tt[0], ww, 1)
        if slope > 0:
            tc = tt[0] + (level - icpt) / slope
            if t[k - 1] - (t[k] - t[k - 1]) <= tc <= t[k] + (t[k] - t[k - 1]):
                return float(tc)
    w0, w1 = w[k - 1], w[k]
    return float(t[k - 1] + (level - w0) / (w1 - w0) * (t[k] - t[k - 1])) if w1 > w0 else float(t[k])


def _model_lag_to(level, params) -> float:
    """Time [s] the setup's model takes, from the ramp's start, to bring the speed to ``level`` [rpm]
    (``level / ramp_rate`` when the model cannot be run)."""
    from ..errors import KilnctlError

    plain = level / params.ramp_rate
    try:
        from ..simulate import resolve_gains, simulate

        p = resolve_gains(params)
        r = simulate(p, "macro", max(4.0 * plain, 0.5))
        tc = _crossing(np.asarray(r.t), np.asarray(r.outputs["speed_rpm"]), level)
    except (KilnctlError, ArithmeticError, ValueError):
        return plain
    return plain if tc is None or not (0.0 < tc < 10.0 * plain + 1.0) else float(tc)


def _where(source, lines, k, column=None, row_word="line", labels=None):
    s = f"{source}: {row_word} {int(lines[k])}"
    if not column:
        return s
    return s + ", column " + ((labels or {}).get(column) or repr(column))


def read_csv(path, params: Parameters | None = None, columns=None) -> Measurement:
    """Read and check a measured record in CSV (see the module docstring for the format).

    Parameters
    ----------
    path : path-like
        The CSV file.  Comma, semicolon or tab separated; lines starting
        with ``#`` and blank lines are skipped.
    params : Parameters, optional
        Setup of the experiment, used by the unit and plausibility checks
        (``omega_ref`` [rpm], ``ramp_rate`` [rpm/s], ``I_max`` [A]); the
        defaults otherwise.
    columns : str or dict, optional
        Column mapping, as for :func:`read_record`.

    Returns
    -------
    Measurement

    Raises
    ------
    DataError
        Missing or duplicated columns, a non-numeric or empty cell, a row of
        the wrong length, non-increasing time, NaN, a gap (a step above
        5 x the median), a record shorter than 2 s or 50 samples, a time
        axis implausible for a start-up (milliseconds read as seconds), a
        channel whose scale suggests the wrong unit, a current or speed
        with one value at every sample (a dead channel), or a speed that
        starts above 10 % of ``omega_ref`` (the record begins after the
        start-up).  The message names the file, the line and the column.
    """
    from .tables import read_table

    return _interpret(read_table(_record_path(path, "read_csv"), "csv"), params, columns)


def read_record(path, params: Parameters | None = None, columns=None, *, log: bool = False) -> Measurement:
    """Read and check a measured record from a CSV, Excel, Parquet or MATLAB file.

    The format comes from the suffix (``.xlsx``: first sheet; ``.parquet``;
    ``.mat``: one vector per channel, or one struct of them; anything else is
    read as CSV).  Columns are found by kilnctl's names (``time_s``,
    ``current_A``, ``speed_rpm``, ``speed_ref_rpm``) or by ``columns``.  A
    unit written in the header (``I_arm [kA]``, ``n_mot [1/min]``,
    ``t [ms]``) or in the mapping (``time_s=t [ms]``) is converted to s, A
    and rpm; a time column of ISO 8601 timestamps (or spreadsheet/Parquet
    date-times) becomes seconds since the first sample.  The file is only
    read.

    Parameters
    ----------
    path : path-like
        The record.
    params : Parameters, optional
        Setup of the experiment, used by the unit and plausibility checks
        (``omega_ref`` [rpm], ``ramp_rate`` [rpm/s], ``I_max`` [A]).
    columns : str or dict, optional
        Channel -> column in the file, ``"current_A=I_arm,speed_rpm=n_mot"``
        or ``{"current_A": "I_arm"}``; a unit may follow the column name
        (``"time_s=t [ms]"``).
    log : bool, default False
        Read a long log for :func:`kilnctl.measure.split_startups`: gaps
        (logger pauses) are allowed and the record may be longer than
        :data:`MAX_RECORD_S` (one hour: a start-up, not a shift).

    Returns
    -------
    Measurement

    Raises
    ------
    DataError
        Everything :func:`read_csv` refuses, and an unknown or ambiguous
        unit, a mapping naming a column the file lacks, a cell that is
        neither a number nor a timestamp.  The message names the file, the
        line/row/sample and the column, and the fix.
    """
    from .tables import read_table

    return _interpret(read_table(_record_path(path, "read_record")), params, columns, log=log)


def _record_path(path, where: str):
    """``path`` if it names a file (str or path-like); else a ParameterError naming the argument."""
    if isinstance(path, (str, os.PathLike)):
        return path
    raise ParameterError(f"{where}: path must be the record's file name (str or pathlib.Path), not "
                         f"{type(path).__name__}")


def _interpret(table, params, columns, *, log=False) -> Measurement:
    """Find kilnctl's channels in a RawTable, convert them to s, A, rpm, and check the record."""
    from .tables import QUANTITY, convert, parse_columns, split_unit

    if params is not None:
        Parameters.require(params, f"{table.source}: params", "the setup: load_setup(path).params")

    columns = parse_columns(columns) if not isinstance(columns, dict) else parse_columns(dict(columns))
    src, names, notes = table.source, table.names, list(table.notes)
    head = f"{src}: {table.header}" if table.header else src  # where the header is, for messages
    seen = set()
    for j, nm in enumerate(names):
        if not nm:
            raise DataError(f"{head}, column {j + 1}: empty column name in the header; name the column, or delete it "
                            "(a row number written by pandas' to_csv? write the file with index=False)")
        if nm in seen:
            raise DataError(f"{head}: column {nm!r} appears twice in the header")
        seen.add(nm)
    parsed = [split_unit(nm) for nm in names]
    found: dict[str, tuple[int, str | None]] = {}

    def named(base):  # the columns called ``base``, with or without a unit
        return [j for j, nm in enumerate(names) if nm == base] or [j for j, (b, _) in enumerate(parsed) if b == base]

    # a record kilnctl wrote (split-startups' pieces) read with the setup that maps the plant's log: every
    # required channel mapped to a column the file lacks, and the file has kilnctl's own names for them
    own_format = all(ch in columns and not named(split_unit(columns[ch])[0]) and named(ch) for ch in REQUIRED)
    fallback: list[str] = []  # mapped columns the file lacks, read under kilnctl's own names
    for ch in list(REQUIRED) + list(OPTIONAL):
        if ch in columns:
            want = columns[ch]
            wbase, wunit = split_unit(want)
            hits = [j for j, nm in enumerate(names) if nm == want] or \
                   [j for j, (b, _) in enumerate(parsed) if b == wbase]
            own = named(ch)
            if not hits and own and own_format:
                # kilnctl's own column, in kilnctl's unit unless its header says otherwise
                fallback.append(f"{ch}={want}")
                found[ch] = (own[0], parsed[own[0]][1])
                continue
            if not hits:
                raise DataError(f"{src}: the column mapping gives {ch}={want}, but the file has no column "
                                f"{wbase!r}; it has {', '.join(names)}; {close_matches_hint(wbase, names)}")
            if len(hits) > 1:
                raise DataError(f"{src}: {ch}={want} matches several columns ({', '.join(names[j] for j in hits)});"
                                " give the full name with its unit")
            j = hits[0]
            hunit = parsed[j][1]
            if wunit and hunit and wunit.lower() != hunit.lower() and _kiln_side(wunit)[0].lower() != hunit.lower():
                raise DataError(f"{head}: column {names[j]!r} says [{hunit}], but the column "
                                f"mapping says {ch}={want}; remove one of the two units")
            found[ch] = (j, wunit or hunit)
        else:
            hits = [j for j, nm in enumerate(names) if nm == ch] or \
                   [j for j, (b, _) in enumerate(parsed) if b == ch]
            if hits:
                found[ch] = (hits[0], parsed[hits[0]][1])
            elif ch in REQUIRED:
                raise DataError(f"{head}: missing column {ch!r} [{REQUIRED[ch]}]; "
                                f"the header has {', '.join(names)}; {_mapping_hint(ch, parsed, columns, found, table)}")
    if fallback:
        notes.append(f"the column mapping's {', '.join(fallback)} {'is' if len(fallback) == 1 else 'are'} not in "
                     "this file; it has kilnctl's own column names (a record written by kilnctl split-startups?), "
                     "which are read instead")
    by_col: dict[int, str] = {}
    for ch, (j, _) in found.items():
        if j in by_col:
            raise DataError(f"{src}: column {names[j]!r} is mapped to both {by_col[j]} and {ch}; each channel needs "
                            "its own column (check --columns or [measurement] columns)")
        by_col[j] = ch
    labels = {ch: (repr(names[j]) if names[j] == ch else f"{names[j]!r} (read as {ch})")
              for ch, (j, _) in found.items()}
    tj = found["time_s"][0]
    n = len(table.columns[tj])
    for j, col in enumerate(table.columns):
        if len(col) != n:
            used = [ch for ch, (jj, _) in found.items() if jj == j]
            if used:
                raise DataError(f"{src}: {names[j]!r} (read as {used[0]}) has {len(col)} samples, the time "
                                f"{names[tj]!r} has {n}: the channels must have one value per time")
    rows = table.rows[:n]
    arrays: dict[str, np.ndarray] = {}
    t, tnote = _time_seconds(table, tj, labels["time_s"], n)
    if tnote:
        notes.append(tnote)
    arrays["time_s"] = t
    for ch, (j, unit) in found.items():
        if ch == "time_s":
            if unit is not None and tnote:
                raise DataError(f"{src}: column {labels[ch]} holds timestamps; it needs no unit [{unit}]")
        else:
            arrays[ch] = _numbers(table, j, labels[ch], required=True)
        if not (ch == "time_s" and tnote):
            unit, kiln_side = _kiln_side(unit) if ch in ("speed_rpm", "speed_ref_rpm") else (unit, False)
            arrays[ch], note = convert(arrays[ch], unit, ch, f"{src}: column {labels[ch]}")
            if note:
                notes.append(note)
            if kiln_side:
                n_gear = (Parameters() if params is None else params).n
                arrays[ch] = arrays[ch] * n_gear
                notes.append(f"{ch} is the kiln-side speed: multiplied by the setup's reduction n = {n_gear:g} to "
                             "the motor speed")
    used_cols = {j for j, _ in found.values()}
    kept, dropped = [], []
    for j, nm in enumerate(names):
        if j in used_cols:
            continue
        if len(table.columns[j]) != n:
            dropped.append(f"{nm} ({len(table.columns[j])} samples, not {n})")
            continue
        if nm in QUANTITY:  # a kilnctl name mapped elsewhere
            dropped.append(f"{nm} (--columns maps {nm} to {columns[nm]!r})" if nm in columns else nm)
            continue
        a = _numbers(table, j, repr(nm), required=False)
        if a is None:
            dropped.append(f"{nm} (not numeric)")
        else:
            arrays[nm] = a
            kept.append(nm)
    if kept:
        notes.append(f"extra columns kept but not compared: {', '.join(kept)}")
    notes.extend(_speed_column_notes(arrays, parsed, names, found, kept, columns))
    if dropped:
        notes.append(f"columns ignored: {', '.join(dropped)}")
    m = _checked(arrays, rows, src, params, tuple(notes), row_word=table.row_word, labels=labels, log=log,
                 time_name=parsed[tj][0])
    if not log:  # a file must hold a start-up; arrays built in code may hold any test signal
        _check_dead(m.channels, src, labels)
        _check_starts_at_rest(m, src, labels, Parameters() if params is None else params)
    return m


#: a unit written at the end of a column's name, ``motor_current_A``, ``t_ms``, ``n_rad_s``
_NAME_UNIT = re.compile(r"(?:^|[_\s.-])(ka|ma|a|rpm|rad_s|rads|ms|us|s|sec)$", re.IGNORECASE)
_NAME_UNIT_AS = {"rad_s": "rad/s", "rads": "rad/s"}
#: words in a column's name that point to a channel: substrings (long words) and whole tokens (short ones)
_NAME_WORDS = {
    "time": (("time", "zeit", "stamp", "date"), ("t", "ts", "tm")),
    "current": (("current", "strom", "amp"), ("i", "ia", "iarm", "i_a", "i_arm", "curr", "cur")),
    "speed": (("speed", "drehzahl", "omega", "velocity", "rpm"), ("n", "nm", "w", "v", "spd", "n_mot", "nmot")),
}
#: words that mark a speed column as a reference or as the kiln-side speed (not the measured motor speed)
_REF_WORDS = ("ref", "soll", "set", "sp", "cmd", "demand", "target")
_KILN_WORDS = ("kiln", "ofen", "drum", "shell")


def _name_unit(name: str) -> str | None:
    """A unit written at the end of a column's name (``motor_current_A`` -> ``A``), if it is one kilnctl knows."""
    m = _NAME_UNIT.search(name.strip())
    if not m:
        return None
    u = _NAME_UNIT_AS.get(m.group(1).lower(), m.group(1))
    return u if _unit_quantity(u) else None


def _tokens(name: str) -> list[str]:
    spaced = re.sub(r"([a-z0-9])([A-Z])", r"\1 \2", name)  # camelCase: nRef -> n Ref
    return [w for w in re.split(r"[^a-z0-9]+", spaced.lower()) if w]


def _has_word(name: str, words) -> bool:
    low, toks = name.lower(), _tokens(name)
    return any(w in toks or (len(w) > 3 and w in low) for w in words)


def _looks_like_stamp(cell) -> bool:
    if isinstance(cell, np.datetime64):
        return True
    if not isinstance(cell, str):
        return False
    import datetime as _dt

    try:
        _dt.datetime.fromisoformat(cell.strip())
        return True
    except ValueError:
        return False


def _guess_mapping(table, parsed, columns, found) -> dict[str, str]:
    """Guess kilnctl's channels among a header's columns from units, names and cells (for a hint only).

    Returns channel -> the ``--columns`` value (the column's base name, with the unit when only the name says it).
    """
    from .tables import QUANTITY as QUANTITY_OF
    from .tables import UNITS as UNITS_OF

    taken = {j for j, _ in found.values()}
    first = [next((c for c in col if not _cell_missing(c)), None) if len(col) else None for col in table.columns]
    guess = {}
    for ch in list(REQUIRED) + list(OPTIONAL):
        if ch in found or ch in columns:
            continue
        q = QUANTITY_OF[ch]
        best, best_score = None, 0
        for j, (base, unit) in enumerate(parsed):
            if j in taken:
                continue
            nunit = None if unit else _name_unit(base)
            uq = _unit_quantity(unit or nunit or "")
            if uq is not None and uq != q:
                continue
            score = 2 * (uq == q)
            if q == "time" and j < len(first) and _looks_like_stamp(first[j]):
                score += 3
            subs, toks = _NAME_WORDS[q]
            if _has_word(base, subs) or any(t in _tokens(base) for t in toks) or base.lower() in toks:
                score += 1
            if q == "speed":
                is_ref, is_kiln = _has_word(base, _REF_WORDS), _has_word(base, _KILN_WORDS)
                if is_kiln or (is_ref != (ch == "speed_ref_rpm")):
                    continue
            if score > best_score:
                best, best_score = j, score
        if best is None:
            continue
        base, unit = parsed[best]
        nunit = None if unit else _name_unit(base)
        factor = UNITS_OF[QUANTITY_OF[ch]].get((nunit or "").lower(), 1.0)
        guess[ch] = base + (f" [{nunit}]" if nunit and factor != 1.0 else "")
        taken.add(best)
    return guess


def _mapping_hint(missing, parsed, columns, found, table=None) -> str:
    """Suggest a ``--columns`` mapping for the missing channels from the header's units and names."""
    where = " (or columns in the setup's [measurement] section)"
    guess = _guess_mapping(table, parsed, columns, found) if table is not None else {}
    if missing in guess:
        text = ",".join(f"{k}={v}" for k, v in guess.items())
        if any(c in text for c in " []()"):
            text = f"'{text}'"
        return f"map yours with --columns {text}{where}; guessed from the header's names and units: check it"
    hint = close_matches_hint(missing, [b for b, _ in parsed])
    return f"{hint} (map a column of another name with --columns {missing}=NAME{where})"


#: words that mark a speed unit as measured on the kiln side of the gears: ``[kiln rpm]``, ``[rpm @ kiln]``
_KILN_SIDE = re.compile(r"^\s*(?:kiln\s+|@\s*kiln\s+)?(?P<u>.*?)(?:\s*(?:@|at)?\s*kiln)?\s*$", re.IGNORECASE)


def _kiln_side(unit: str | None) -> tuple[str | None, bool]:
    """Split a speed unit into the unit proper and whether it is marked as the kiln-side speed.

    ``kiln rpm``, ``rpm kiln``, ``rpm @ kiln``, ``rad/s at kiln`` -> (``rpm``/``rad/s``, True); ``rpm`` -> (``rpm``,
    False); ``kiln`` alone means rpm at the kiln.
    """
    if unit is None or "kiln" not in unit.lower():
        return unit, False
    if unit.strip().lower() == "kiln":
        return "rpm", True
    m = _KILN_SIDE.match(unit)
    u = m.group("u").strip() if m else unit
    return (u or "rpm"), True


def _column_base(labels, channel) -> str:
    """The record's own column name (unit removed) behind a channel, from the labels used in messages."""
    from .tables import split_unit

    m = re.match(r"^'(.*)'(?: \(read as \w+\))?$", (labels or {}).get(channel, ""))
    return split_unit(m.group(1))[0] if m else channel


def _speed_column_notes(arrays, parsed, names, found, kept, columns) -> list[str]:
    """Notes on speed columns a user easily mixes up: the reference left unmapped, a reference or the kiln-side
    speed read as the measured motor speed (a reference is a noise-free straight ramp, a measured speed is not)."""
    out = []
    j_speed = found["speed_rpm"][0]
    base = parsed[j_speed][0]
    t, v = arrays["time_s"], arrays["speed_rpm"]
    with np.errstate(divide="ignore", invalid="ignore"):  # repeated times are refused later, with their line
        slope = np.diff(v) / np.diff(t)
        moving = np.abs(slope) > 1e-9
        change = np.abs(np.diff(slope[moving]))
    if v.size > 20 and moving.sum() > 10:
        top = float(np.max(np.abs(v))) or 1.0
        dt = float(np.median(np.diff(t)))
        # a record resampled from a coarser logger is straight between its samples too: that is said apart
        # (red team 7: an interpolated 200 Hz export read as "looks like the speed reference")
        # nor is a speed counted in an encoder's steps (its changes are whole steps, equal on a steady ramp:
        # red team 13's speed in 2 rpm steps)
        if np.isfinite(change).all() and np.median(change) * dt < 1e-6 * top \
                and resampled_every(arrays.get("current_A")) is None and speed_step(v) is None:
            out.append(f"speed_rpm ({names[j_speed]!r}) rises as a noise-free straight ramp: it looks like the speed "
                       "reference, not the measured motor speed; map the measured speed with --columns "
                       "speed_rpm=NAME")
    if _has_word(base, _REF_WORDS) and not any("noise-free" in n for n in out):
        out.append(f"speed_rpm is read from {names[j_speed]!r}, whose name says reference: kilnctl compares the "
                   "model with the measured motor speed; map that with --columns speed_rpm=NAME")
    if "speed_ref_rpm" not in found and "speed_ref_rpm" not in columns:
        refs = [nm for nm in kept if _has_word(split_unit_base(nm), _REF_WORDS)]
        if refs:
            out.append(f"{refs[0]!r} looks like the speed reference but is not used: the ramp's start is taken from "
                       f"the measured speed's rise; map it with --columns speed_ref_rpm={split_unit_base(refs[0])} to "
                       "take the ramp from it")
    return out


def split_unit_base(name: str) -> str:
    from .tables import split_unit

    return split_unit(name)[0]


def _unit_quantity(unit: str):
    from .tables import UNITS

    return next((q for q, tab in UNITS.items() if unit.strip().lower() in tab), None)


#: a number written with a thousands separator: ``1.234,5``, ``1,234.5``, ``1.234.567`` (not ``1,234``: a decimal
#: comma as well)
_THOUSANDS = re.compile(r"^[+-]?\d{1,3}(?P<sep>[.,])\d{3}(?:(?:(?P=sep)\d{3})+|(?:(?P=sep)\d{3})*(?!(?P=sep))[.,]\d*)$")


def _cell_missing(c) -> bool:
    return c is None or (isinstance(c, float) and math.isnan(c)) or (isinstance(c, str) and not c)


def _numbers(table, j, label, required):
    """Column j as floats; a bad cell is an error (required) or makes the column None (extra columns)."""
    col = table.columns[j]
    if col.dtype.kind in "fiub":
        out = col.astype(float)
        return out if (required or np.isfinite(out).all()) else None
    try:
        if col.dtype.kind != "O" or any(_cell_missing(c) for c in col):
            raise ValueError
        out = np.array(col, dtype=float)
        return out if (required or np.isfinite(out).all()) else None
    except (TypeError, ValueError):
        if not required:
            return None
    for k, c in enumerate(col):
        if _cell_missing(c) or (isinstance(c, str) and not c.strip()):
            raise DataError(f"{table.where(k)}, column {label}: empty cell (missing value); kilnctl does not fill "
                            "gaps: cut the record or fill the value yourself")
        try:
            float(c)
        except (TypeError, ValueError):
            hint = ""
            if isinstance(c, str) and _THOUSANDS.match(c.strip()):
                hint = " (a thousands separator? export the numbers without one: 1234.5, not 1.234,5 or 1,234.5)"
            elif isinstance(c, str) and "," in c:
                hint = f"; {table.decimal_clash}" if table.decimal_clash else " (decimal comma? write 1.5, not 1,5)"
            raise DataError(f"{table.where(k)}, column {label}: {c!r} is not a number{hint}") from None
    raise DataError(f"{table.source}: column {label}: not numeric")  # pragma: no cover - every cell converted


def _time_seconds(table, j, label, n):
    """The time column in seconds: numbers as they are, timestamps as seconds since the first sample."""
    col = table.columns[j][:n]
    utc = False
    if col.dtype.kind == "M":
        stamps = col.astype("datetime64[ns]")
    else:
        if col.dtype.kind != "O":
            return col.astype(float), None
        first = next((c for c in col if not _cell_missing(c)), None)
        is_number = isinstance(first, (int, float, np.number)) and not isinstance(first, bool)
        if isinstance(first, str):
            try:
                float(first)
                is_number = True
            except ValueError:
                pass
        if first is None or is_number:
            return _numbers(table, j, label, required=True)[:n], None
        stamps, utc = _parse_stamps(table, col, label)
    bad = np.isnat(stamps)
    if bad.any():
        k = int(np.argmax(bad))
        raise DataError(f"{table.where(k)}, column {label}: empty cell (missing time); kilnctl does not fill gaps")
    ns = (stamps - stamps[0]).astype("timedelta64[ns]").astype(np.int64)
    start = np.datetime_as_string(stamps[0], unit="ms")
    return ns * 1e-9, f"time from timestamps: t = 0 s at {start}" + (" UTC" if utc else "")


def _parse_stamps(table, col, label):
    """ISO 8601 strings or date-time cells -> datetime64[ns]; those with a UTC offset are compared in UTC."""
    import datetime as _dt

    out = np.empty(len(col), dtype="datetime64[ns]")
    kinds = set()
    for k, c in enumerate(col):
        if _cell_missing(c) or (isinstance(c, str) and not c.strip()):
            raise DataError(f"{table.where(k)}, column {label}: empty cell (missing time); kilnctl does not fill gaps")
        if isinstance(c, np.datetime64):
            out[k] = c
            kinds.add("naive")
            continue
        d = c
        if isinstance(c, str):
            try:
                d = _dt.datetime.fromisoformat(c.strip())
            except ValueError:
                d = None
        if not isinstance(d, _dt.datetime) and isinstance(c, str) and "," in c and table.decimal_clash:
            raise DataError(f"{table.where(k)}, column {label}: {c!r} is not a number; {table.decimal_clash}")
        if not isinstance(d, _dt.datetime):
            raise DataError(f"{table.where(k)}, column {label}: {c!r} is neither a number of seconds nor an ISO "
                            "8601 timestamp (e.g. 2024-03-01T06:15:00.020); give the time in one form for every row")
        if d.tzinfo is not None:
            d = d.astimezone(_dt.timezone.utc).replace(tzinfo=None)
            kinds.add("offset")
        else:
            kinds.add("naive")
        if len(kinds) > 1:
            raise DataError(f"{table.where(k)}, column {label}: {c!r}: the column mixes timestamps with and without "
                            "a UTC offset; give all of them with one, or none")
        out[k] = np.datetime64(d, "ns")
    return out, "offset" in kinds


def _checked(arrays, lines, source, params, notes, row_word, labels=None, log=False,
             time_name="time_s") -> Measurement:
    """Run every check on the columns and return the Measurement."""
    params = Parameters() if params is None else params
    labels = labels or {}

    def where(k, column=None):
        return _where(source, lines, k, column, row_word, labels)

    for name, a in arrays.items():
        bad = ~np.isfinite(a)
        if bad.any():
            k = int(np.argmax(bad))
            what = "NaN (missing value)" if np.isnan(a[k]) else f"{float(a[k])!r} (not finite)"
            raise DataError(f"{where(k, name)}: {what}; kilnctl does not fill gaps: "
                            f"cut the record or fill the value yourself ({int(bad.sum())} such cells in this column)")
    t = arrays.pop("time_s")
    n = t.size
    if n < 2:
        raise DataError(f"{source}: {n} sample(s): a record needs at least {MIN_SAMPLES} samples "
                        f"over at least {MIN_DURATION_S:g} s")
    dts = np.diff(t)
    if (dts <= 0).any():
        k = int(np.argmax(dts <= 0)) + 1
        stamped = any(str(n).startswith("time from timestamps") for n in notes)
        hint = ("; the timestamps repeat: export them with fractions of a second (2024-03-01T06:15:00.020)"
                if stamped and dts[k - 1] == 0 else "")
        raise DataError(f"{where(k, 'time_s')}: time {t[k]:.9g} s is not after "
                        f"the previous sample's {t[k - 1]:.9g} s ({row_word} {int(lines[k - 1])}); time must increase"
                        f"{hint}")
    med = float(np.median(dts))
    if not log and (dts > GAP_FACTOR * med).any():
        k = int(np.argmax(dts > GAP_FACTOR * med)) + 1
        raise DataError(f"{where(k, 'time_s')}: gap of {dts[k - 1]:.6g} s between "
                        f"{t[k - 1]:.6g} s and {t[k]:.6g} s (median step {med:.6g} s; a gap is a step above "
                        f"{GAP_FACTOR:g} x the median); cut the record at the gap or resample it")
    duration = float(t[-1] - t[0])
    if duration < MIN_DURATION_S or n < MIN_SAMPLES:
        hint = ""
        if 7e5 < t[0] < 8e5:
            hint = ("; the time looks like MATLAB datenum (days since year 0): map it with --columns "
                    "'time_s=NAME [d]'")
        raise DataError(f"{source}: record too short to say anything: {n} samples over {duration:.3g} s "
                        f"(need at least {MIN_SAMPLES} samples and {MIN_DURATION_S:g} s){hint}")
    _check_time_scale(t, med, source, labels.get("time_s", "'time_s'"), params, math.inf if log else MAX_RECORD_S,
                      time_name, arrays.get("speed_rpm"))
    _check_units(arrays, lines, source, params, row_word, labels, log)
    clipped = spikes = ()
    if not log:
        ref = arrays.get("speed_ref_rpm")
        tops = (params.omega_ref,) + ((float(np.max(np.abs(ref))),) if ref is not None and ref.size else ())
        clipped = tuple(clipped_levels(arrays, params.I_max, tops))
        spikes = glitches(arrays)
        kept = unclipped(clipped, arrays)
        if kept is not None and kept.sum() < MIN_SAMPLES:
            c = max(clipped, key=lambda c: c.n)
            raise DataError(f"{source}: {int(n - kept.sum())} of {n} samples sit at a level the logger clipped "
                            f"a channel at (column {labels.get(c.channel) or repr(c.channel)} at {c.level:.6g}): "
                            f"fewer than {MIN_SAMPLES} samples are left to compare a model with; log the channel "
                            "with a wider range")
        resampled = resampled_notes(t, arrays, med)
        notes = tuple(notes) + tuple(sampling_notes(t, dts, med, lines, row_word, GAP_FACTOR)) \
            + tuple(glitch_notes(spikes, arrays, lines, row_word, labels, med)) \
            + tuple(frozen_notes(t, arrays, lines, row_word)) \
            + tuple(resampled) + tuple(clipped_notes(clipped, arrays, t, lines, row_word, labels)) \
            + tuple(() if resampled else speed_step_notes(arrays))  # (held values repeat as counts do)
    return Measurement(t=t, channels=arrays, source=source, lines=lines, notes=tuple(notes), row_word=row_word,
                       clipped=clipped, glitches=spikes)


#: longest start-up record compare and diagnose accept [s]: a start-up, not a shift (split a log first)
MAX_RECORD_S = 3600.0
#: the median sample step must resolve the setup's ramp with at least this many samples
RAMP_SAMPLES = 5
#: a sample step below this is always fine for a start-up [s]
STEP_ALWAYS_OK_S = 0.5


def _fmt_span(s: float) -> str:
    return f"{s / 3600:.3g} h" if s >= 7200 else (f"{s / 60:.3g} min" if s >= 120 else f"{s:.3g} s")


def _rise_ratio(t, speed, params):
    """How many times slower the measured speed rises (10 to 90 % of its top) than the setup's ramp; None if it
    does not rise to half the set point."""
    if speed is None or speed.size < 3:
        return None
    top = float(np.max(speed))
    if not top > 0.5 * params.omega_ref or not params.ramp_rate > 0 or not speed[0] < 0.1 * top:
        return None
    k10, k90 = int(np.argmax(speed >= 0.1 * top)), int(np.argmax(speed >= 0.9 * top))
    if k90 <= k10:
        return None
    return float(t[k90] - t[k10]) / (0.8 * top / params.ramp_rate)


def _check_time_scale(t, dt, source, label, params, max_span, name="time_s", speed=None):
    """Refuse a time axis that cannot be a start-up of this setup (milliseconds read as seconds)."""
    t_ramp = params.omega_ref / params.ramp_rate if params.ramp_rate > 0 else math.inf
    step_limit = max(t_ramp / RAMP_SAMPLES, STEP_ALWAYS_OK_S)
    span = float(t[-1] - t[0])
    problem = None
    if dt > step_limit:
        problem = (f"the median sample step is {dt:.4g} s, but the setup's ramp to {params.omega_ref:g} rpm at "
                   f"{params.ramp_rate:g} rpm/s takes {t_ramp:.3g} s: fewer than {RAMP_SAMPLES} samples would "
                   "cover the start-up")
    elif span > max_span:
        problem = (f"the record spans {_fmt_span(span)} (longest accepted: {_fmt_span(max_span)}); a start-up of "
                   f"this setup ramps in {t_ramp:.3g} s")
    if problem is None:
        return
    ms_fix = (f"write the unit in the header ('{name} [ms]') or map it with --columns 'time_s={name} [ms]' "
              f"(or columns in the setup's [measurement] section)")
    ms_ok = dt / 1000 <= step_limit and span / 1000 >= MIN_DURATION_S
    ratio = _rise_ratio(t, speed, params)
    if ms_ok and (ratio is None or ratio > 30):
        read_ms = f"read in ms: step {dt:.4g} ms, span {_fmt_span(span / 1000)}"
        if ratio is None and span > max_span:
            fix = (f"if this is a long log, cut the start-ups out of it with kilnctl split-startups; if the time is "
                   f"in milliseconds ({read_ms}), {ms_fix}")
        else:
            seen = "" if ratio is None else (f"; the measured speed rises {ratio:.0f} x slower than the setup's "
                                             "ramp in seconds")
            fix = f"the time column looks like milliseconds ({read_ms}{seen}): {ms_fix}"
    elif span > max_span:
        fix = "cut the start-ups out of the log with kilnctl split-startups"
    else:
        fix = f"give a record sampled at least every {step_limit:.3g} s"
    raise DataError(f"{source}: column {label}: {problem}; {fix}")


def _check_dead(arrays, source, labels=None):
    """Refuse a required channel that holds one value at every sample: a dead channel or the wrong column (its fit %
    is not defined, and a diagnosis would explain a flat line)."""
    for name in REQUIRED:
        a = arrays.get(name)
        if a is None or a.size == 0 or np.ptp(a) > 0:
            continue
        label = (labels or {}).get(name) or repr(name)
        what = "armature current" if name == "current_A" else "motor speed"
        still = "" if name == "current_A" else "; if the kiln did not move, the record holds no start-up to compare"
        raise DataError(f"{source}: column {label} is {a[0]:.6g} {REQUIRED[name]} at every one of its {a.size} "
                        "samples: a dead channel (sensor off, tag not logged) or the wrong column; export the "
                        f"measured {what}, or map it with --columns {name}=NAME{still}")


#: a current above this many times I_max, or a speed above this many times omega_ref, is in another unit
TOO_LARGE = 5.0
#: at most this fraction of a channel's samples beyond the unit limits, with the rest within them, are read as
#: isolated glitches of the logger (and named as such) rather than as a channel in another unit
GLITCH_FRACTION = 0.01
#: a record whose speed starts above this fraction of omega_ref does not start at rest (red team 7: a logger
#: triggered 0.5 s into a 74 rpm/s ramp, 7 % of the set speed, passed the 10 % this was, and the diagnosis
#: read the missing start as a viscous drag; a speed sensor's offset at rest is a few rpm, under 1 %)
START_AT_REST_FRACTION = 0.03
#: the first this many seconds of a record [s] (at most five samples) show whether it starts at rest
START_WINDOW_S = 0.1


def _check_starts_at_rest(m, source, labels, params):
    """Refuse a record that begins with the motor already running: the model starts at rest, so there is no
    start-up in it to compare (the median of the samples in its first :data:`START_WINDOW_S`, at most five, so
    that noise does not decide and a record at a few hertz that starts with the ramp is not judged a second into
    it)."""
    k = int(np.clip(np.sum(m.t <= m.t[0] + START_WINDOW_S), 1, 5))
    w0 = float(np.median(m.speed[:k]))
    if not w0 > START_AT_REST_FRACTION * params.omega_ref > 0:
        return
    at = _where(source, m.lines, 0, "speed_rpm", m.row_word, labels)
    raise DataError(f"{at}: the record starts with the motor running ({w0:.4g} rpm over its first samples, "
                    f"{100 * w0 / params.omega_ref:.0f} % of the setup's omega_ref = {params.omega_ref:g} rpm); "
                    "compare and diagnose start the model at rest, so a record must begin before the start-up: "
                    "export it from before the speed reference rises, or cut the start-ups out of a longer log with "
                    "kilnctl split-startups")


def _glitches(a, limit: float, source, lines, row_word, labels, name, unit: str) -> str | None:
    """The refusal's text when only a few isolated samples of ``a`` exceed ``limit`` in magnitude
    (:data:`GLITCH_FRACTION`) and the others stay within it: a logger's glitch, not a unit; else None."""
    bad = np.flatnonzero(np.abs(a) > limit)
    if bad.size == 0 or bad.size > GLITCH_FRACTION * a.size:
        return None
    rest = float(np.max(np.abs(np.delete(a, bad))))
    where = _where(source, lines, int(bad[0]), name, row_word, labels)
    more, what = ("", "an isolated glitch of the logger") if bad.size == 1 else \
        (f" (and {bad.size - 1} more, the last on {row_word} {int(lines[bad[-1]])})", "isolated glitches of the logger")
    return (f"{where}: {float(a[bad[0]]):.4g} {unit}{more}, beyond {limit:.4g} {unit}, while the other "
            f"{a.size - bad.size} samples stay within {rest:.4g} {unit}: {what}, not a unit; correct "
            f"{'it' if bad.size == 1 else 'them'} (the mean of the neighbours) and read the record again: kilnctl "
            "does not filter or replace values")


def _check_units(arrays, lines, source, params, row_word, labels=None, log=False):
    """Refuse channels whose scale suggests the wrong unit (in a long log only the rad/s and kA checks: a log may
    stand still for most of its length, and each start-up cut from it gets every check)."""
    w_ref = params.omega_ref
    for name in ("speed_rpm", "speed_ref_rpm"):
        if name not in arrays:
            continue
        at = _where(source, lines, int(np.argmax(np.abs(arrays[name]))), name, row_word, labels)
        a = arrays[name]
        top = float(np.max(np.abs(a)))
        k = int(np.argmax(np.abs(a)))
        rad = w_ref / RPM_PER_RAD_S
        if 0.3 * rad < top < 0.12 * w_ref and top < 2.0 * rad:
            pct = "" if abs(top / rad - 1.0) < 0.15 else (
                f"; it is {100 * top / rad:.0f} % of that, so it may instead be per cent of a rated speed: then "
                "convert it to rpm yourself")
            col = _column_base(labels, name)
            raise DataError(
                f"{at}: largest value {top:.4g} looks like rad/s, not rpm (the setup's speed reference {w_ref:g} rpm "
                f"is {rad:.4g} rad/s); multiply by 60/(2*pi) = 9.549, or write the unit in the header "
                f"('{col} [rad/s]')" + (f" or the mapping (--columns '{name}={col} [rad/s]')" if col != name else "")
                + pct)
        if not log and top > TOO_LARGE * w_ref > 0:
            glitch = _glitches(a, TOO_LARGE * w_ref, source, lines, row_word, labels, name, "rpm")
            if glitch:
                raise DataError(glitch)
            raise DataError(
                f"{at}: largest value {top:.4g} is {top / w_ref:.0f} x the setup's speed reference {w_ref:g} rpm: not "
                "a motor speed in rpm (a drive's internal units, 16384 = 100 %? a glitch value?); convert it to rpm, "
                "or, if the setup's omega_ref is wrong, correct it in the setup file (--config)")
        kiln = w_ref / params.n
        if not log and 0 < top < 0.3 * rad and top < 3.0 * kiln:
            raise DataError(
                f"{at}: largest value {top:.4g} looks like the kiln speed, "
                f"not the motor speed (the setup's {w_ref:g} rpm motor speed is {kiln:.3g} rpm at the kiln, "
                f"reduction n = {params.n:g}); map the motor speed if the file has it, or mark this one as measured at "
                f"the kiln (it is then multiplied by n): --columns '{name}={_column_base(labels, name)} [kiln rpm]'")
        if not log and name == "speed_rpm" and np.median(a[a.size // 2:]) < 0 < w_ref:
            raise DataError(
                f"{source}: column 'speed_rpm' is negative over the second half of the record (median "
                f"{np.median(a[a.size // 2:]):.4g} rpm) while the setup's reference is +{w_ref:g} rpm; "
                "flip the sign of the speed (and current) channels")
    cur = arrays["current_A"]
    top = float(np.max(np.abs(cur)))
    k = int(np.argmax(np.abs(cur)))
    if not log and top > TOO_LARGE * params.I_max > 0:
        glitch = _glitches(cur, TOO_LARGE * params.I_max, source, lines, row_word, labels, "current_A", "A")
        if glitch:
            raise DataError(glitch)
        raise DataError(
            f"{_where(source, lines, k, 'current_A', row_word, labels)}: largest value {top:.4g} is "
            f"{top / params.I_max:.0f} x the setup's current limit I_max = {params.I_max:g} A: looks like mA or a "
            "drive's internal units (16384 = 100 %?), not A; give the current in A, or write the unit in the header "
            f"('{_column_base(labels, 'current_A')} [mA]'); if the setup's I_max is wrong, correct it in the setup "
            "file (--config)")
    if 0 < top < 0.01 * params.I_max:
        raise DataError(
            f"{_where(source, lines, k, 'current_A', row_word, labels)}: largest value {top:.4g} looks like kA or a "
            f"per-unit value, not A (the setup's current limit is {params.I_max:g} A); give the current in A, or "
            f"write the unit in the header ('{_column_base(labels, 'current_A')} [kA]')")


# --- setup file -------------------------------------------------------------------
#: keys of the optional [measurement] section of a setup file
MEASUREMENT_KEYS = {
    "t0_s": "time in the record at which the start-up (speed ramp) begins [s]",
    "calibrate": "list of base parameters to calibrate (default: mu_c, mu_s, m_v, J_v)",
    "candidates": "list of catalogue effects diagnose may try (default: all)",
    "columns": "table: kilnctl channel -> column of the record, e.g. {current_A = \"I_arm\", time_s = \"t [ms]\"}",
}


@dataclass(frozen=True)
class Setup:
    """What was known about an experiment: parameters and measurement options.

    Attributes
    ----------
    params : Parameters
        The plant and controller as set up for the experiment.
    options : dict
        The ``[measurement]`` section: ``t0_s`` [s], ``calibrate`` (list of
        parameter names), ``candidates`` (list of effect names), ``columns``
        (channel -> column of the record, see :func:`read_record`).
    source : str
        The file, or ``<defaults>``.
    """

    params: Parameters
    options: dict = field(default_factory=dict)
    source: str = "<defaults>"


def record_columns(setup: Setup, text=None) -> dict:
    """Return the column mapping of a record: the setup's ``[measurement] columns``, overridden by ``--columns``.

    Parameters
    ----------
    setup : Setup
        The experiment's setup.
    text : str, optional
        ``--columns`` as typed (``current_A=I_arm,...``); a channel given here wins over the setup file.

    Returns
    -------
    dict of str to str
        Channel -> column name (with an optional unit).
    """
    from .tables import parse_columns

    return {**setup.options.get("columns", {}), **parse_columns(text)}


def load_setup(path=None) -> Setup:
    """Read a setup file: a kilnctl TOML parameter file plus an optional ``[measurement]`` section.

    Parameters
    ----------
    path : path-like, optional
        The TOML file; without it, the paper's defaults.

    Returns
    -------
    Setup

    Raises
    ------
    ConfigFileError
        The file is missing, not TOML, or has an unknown section or
        ``[measurement]`` key.
    ParameterError
        A parameter is unknown or impossible (the message names the file).
    """
    if path is None:
        return Setup(Parameters())
    path = Path(path)
    # the reader of every kilnctl TOML file: names a byte-order mark, a file that is not UTF-8 and an unreadable
    # file with the fix (a setup saved by Notepad as 'UTF-8 with BOM' was "Invalid statement (at line 1, column 1)")
    raw = read_toml(path, "setup file")
    options = raw.pop("measurement", {})
    if not isinstance(options, dict):
        raise ConfigFileError(f"{path}: 'measurement' must be a section [measurement]")
    for k, v in options.items():
        if k not in MEASUREMENT_KEYS:
            raise ConfigFileError(f"{path}: unknown key {k!r} in [measurement]: {close_matches_hint(k, MEASUREMENT_KEYS)}")
    if "t0_s" in options and (isinstance(options["t0_s"], bool) or not isinstance(options["t0_s"], (int, float))):
        raise ConfigFileError(f"{path}: [measurement] t0_s = {options['t0_s']!r} must be a number of seconds")
    for k in ("calibrate", "candidates"):
        if k in options and (not isinstance(options[k], list) or not all(isinstance(s, str) for s in options[k])):
            raise ConfigFileError(f"{path}: [measurement] {k} must be a list of names, e.g. [\"mu_c\", \"m_v\"]")
    if "columns" in options:
        from .tables import parse_columns

        if not isinstance(options["columns"], dict):
            raise ConfigFileError(f"{path}: [measurement] columns must be a table, e.g. "
                                  "columns = {current_A = \"I_arm\", speed_rpm = \"n_mot\"}")
        options["columns"] = parse_columns(options["columns"], f"{path}: [measurement] columns")
    params = Parameters.from_sections(raw, str(path))
    for k in options.get("calibrate", []):
        if k not in SPECS or SPECS[k].is_option:
            raise ConfigFileError(f"{path}: [measurement] calibrate names {k!r}, not a numeric parameter: "
                                  f"{close_matches_hint(k, [s for s in SPECS if not SPECS[s].is_option])}")
    return Setup(params, dict(options), str(path))
