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

import csv
import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from ..errors import ConfigFileError, DataError, ParameterError, close_matches_hint
from ..params import GROUPS, SPECS, Parameters

__all__ = ["Measurement", "Setup", "Experiment", "read_csv", "load_setup", "REQUIRED", "OPTIONAL",
           "MIN_DURATION_S", "MIN_SAMPLES", "GAP_FACTOR"]

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

_RPM_PER_RAD_S = 60.0 / (2.0 * math.pi)


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
    """

    t0: float
    ramp_rate: float
    omega_ref: float
    source: str
    notes: tuple = ()

    def to_dict(self) -> dict:
        """Return the experiment as a JSON-ready dictionary."""
        return {"t0_s": self.t0, "ramp_rate_rpm_per_s": self.ramp_rate, "omega_ref_rpm": self.omega_ref,
                "source": self.source, "notes": list(self.notes)}


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
    """

    t: np.ndarray
    channels: Mapping[str, np.ndarray]
    source: str = "<arrays>"
    lines: np.ndarray | None = None
    notes: tuple = ()

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
        differ by more than 2 %, and a note says so.  Without it, the ramp of
        the setup is used, starting where the measured speed first exceeds
        2 % of ``omega_ref`` less the time the ramp takes to reach that (or
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
        """
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
        if t0 is not None:
            start = float(t0)
        start = max(start, float(self.t[0]))
        for label, rec, setv, unit in (("ramp rate", rate, params.ramp_rate, "rpm/s"),
                                       ("final speed reference", top, params.omega_ref, "rpm")):
            if abs(rec - setv) > 0.02 * abs(setv):
                notes.append(f"recorded {label} {rec:.4g} {unit} differs from the setup's {setv:.4g} {unit}: "
                             "the recorded value is used")
        notes.append(f"start-up begins at t = {start:.3f} s (from the recorded speed reference)")
        return Experiment(float(start), float(rate), float(top), "recorded speed_ref_rpm", tuple(notes))

    def _start_from_speed(self, params: Parameters) -> float:
        """Start of the ramp from the measured speed: where it first exceeds 2 % of omega_ref, less the
        time the setup's ramp takes to get there (the first sample if the record starts moving)."""
        level = 0.02 * params.omega_ref
        w = self.speed
        if abs(w[0]) > level:
            return float(self.t[0])
        above = np.nonzero(w > level)[0]
        if above.size == 0:
            return float(self.t[0])
        k = int(above[0])
        return float(max(self.t[0], self.t[k] - level / params.ramp_rate))

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

    def to_csv(self, path=None) -> str:
        """Write the record in the kilnctl CSV format (whole or not at all) and return the text.

        Parameters
        ----------
        path : path-like, optional
            Destination; refused if it exists (kilnctl never overwrites data).

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
            rows.append(",".join(f"{c[k]:.6g}" if j else f"{c[k]:.6f}" for j, c in enumerate(cols)))
        text = "\n".join(rows) + "\n"
        if path is not None:
            if Path(path).exists():
                raise DataError(f"{path}: file exists; kilnctl does not overwrite a record")
            write_atomic(path, text)
        return text


# --- reading ---------------------------------------------------------------------
def _where(source, lines, k, column=None, row_word="line"):
    s = f"{source}: {row_word} {int(lines[k])}"
    return s + (f", column {column!r}" if column else "")


def read_csv(path, params: Parameters | None = None) -> Measurement:
    """Read and check a measured record (see the module docstring for the format).

    Parameters
    ----------
    path : path-like
        The CSV file.  Comma, semicolon or tab separated; lines starting
        with ``#`` and blank lines are skipped.
    params : Parameters, optional
        Setup of the experiment, used by the unit checks (``omega_ref``
        [rpm], ``I_max`` [A]); the defaults otherwise.

    Returns
    -------
    Measurement

    Raises
    ------
    DataError
        Missing or duplicated columns, a non-numeric or empty cell, a row of
        the wrong length, non-increasing time, NaN, a gap (a step above
        5 x the median), a record shorter than 2 s or 50 samples, or a
        channel whose scale suggests the wrong unit.  The message names the
        file, the line and the column.
    """
    path = Path(path)
    try:
        raw = path.read_bytes()
    except FileNotFoundError:
        raise DataError(f"{path}: no such measurement file") from None
    except IsADirectoryError:
        raise DataError(f"{path}: is a folder, not a measurement file") from None
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise DataError(f"{path}: not a UTF-8 text file ({exc.reason} at byte {exc.start})") from None
    header = None
    rows: list[tuple[int, list[str]]] = []
    notes = []
    delim = ","
    for lineno, line in enumerate(text.splitlines(), start=1):
        s = line.strip()
        if not s or s.startswith("#"):
            continue
        if header is None:
            delim = ";" if (";" in s and "," not in s) else ("\t" if ("\t" in s and "," not in s) else ",")
            header = (lineno, [h.strip() for h in next(csv.reader([s], delimiter=delim))])
            continue
        rows.append((lineno, [c.strip() for c in next(csv.reader([s], delimiter=delim))]))
    if header is None:
        raise DataError(f"{path}: empty file (no header line with {', '.join(REQUIRED)})")
    hline, names = header
    seen = set()
    for j, nm in enumerate(names):
        if not nm:
            raise DataError(f"{path}: line {hline}, column {j + 1}: empty column name in the header")
        if nm in seen:
            raise DataError(f"{path}: line {hline}: column {nm!r} appears twice in the header")
        seen.add(nm)
    for req, unit in REQUIRED.items():
        if req not in names:
            hint = close_matches_hint(req, names)
            raise DataError(f"{path}: line {hline} (header): missing column {req!r} [{unit}]; "
                            f"the header has {', '.join(names)}; {hint}")
    if not rows:
        raise DataError(f"{path}: no data rows after the header (line {hline})")
    data = np.empty((len(rows), len(names)))
    lines = np.array([r[0] for r in rows])
    for i, (lineno, cells) in enumerate(rows):
        if len(cells) != len(names):
            raise DataError(f"{path}: line {lineno}: {len(cells)} cells, but the header (line {hline}) "
                            f"has {len(names)} columns")
        for j, c in enumerate(cells):
            if c == "":
                raise DataError(f"{path}: line {lineno}, column {names[j]!r}: empty cell (missing value); "
                                "kilnctl does not fill gaps: cut the record or fill the value yourself")
            try:
                data[i, j] = float(c)
            except ValueError:
                hint = " (decimal comma? write 1.5, not 1,5)" if "," in c or (delim == ";" and "," in c) else ""
                raise DataError(f"{path}: line {lineno}, column {names[j]!r}: {c!r} is not a number{hint}") from None
    arrays = {nm: data[:, j] for j, nm in enumerate(names)}
    extra = [nm for nm in names if nm not in REQUIRED and nm not in OPTIONAL]
    if extra:
        notes.append(f"extra columns kept but not compared: {', '.join(extra)}")
    return _checked(arrays, lines, str(path), params, tuple(notes), row_word="line")


def _checked(arrays, lines, source, params, notes, row_word) -> Measurement:
    """Run every check on the columns and return the Measurement."""
    params = Parameters() if params is None else params
    for name, a in arrays.items():
        bad = ~np.isfinite(a)
        if bad.any():
            k = int(np.argmax(bad))
            what = "NaN (missing value)" if np.isnan(a[k]) else f"{a[k]!r} (not finite)"
            raise DataError(f"{_where(source, lines, k, name, row_word)}: {what}; kilnctl does not fill gaps: "
                            f"cut the record or fill the value yourself ({int(bad.sum())} such cells in this column)")
    t = arrays.pop("time_s")
    n = t.size
    if n < 2:
        raise DataError(f"{source}: {n} sample(s): a record needs at least {MIN_SAMPLES} samples "
                        f"over at least {MIN_DURATION_S:g} s")
    dts = np.diff(t)
    if (dts <= 0).any():
        k = int(np.argmax(dts <= 0)) + 1
        raise DataError(f"{_where(source, lines, k, 'time_s', row_word)}: time {t[k]:.9g} s is not after "
                        f"the previous sample's {t[k - 1]:.9g} s ({row_word} {int(lines[k - 1])}); time must increase")
    med = float(np.median(dts))
    if (dts > GAP_FACTOR * med).any():
        k = int(np.argmax(dts > GAP_FACTOR * med)) + 1
        raise DataError(f"{_where(source, lines, k, 'time_s', row_word)}: gap of {dts[k - 1]:.6g} s between "
                        f"{t[k - 1]:.6g} s and {t[k]:.6g} s (median step {med:.6g} s; a gap is a step above "
                        f"{GAP_FACTOR:g} x the median); cut the record at the gap or resample it")
    duration = float(t[-1] - t[0])
    if duration < MIN_DURATION_S or n < MIN_SAMPLES:
        raise DataError(f"{source}: record too short to say anything: {n} samples over {duration:.3g} s "
                        f"(need at least {MIN_SAMPLES} samples and {MIN_DURATION_S:g} s)")
    _check_units(arrays, lines, source, params, row_word)
    m = Measurement(t=t, channels=arrays, source=source, lines=lines, notes=tuple(notes))
    return m


def _check_units(arrays, lines, source, params, row_word):
    """Refuse channels whose scale suggests the wrong unit."""
    w_ref = params.omega_ref
    for name in ("speed_rpm", "speed_ref_rpm"):
        if name not in arrays:
            continue
        a = arrays[name]
        top = float(np.max(np.abs(a)))
        k = int(np.argmax(np.abs(a)))
        rad = w_ref / _RPM_PER_RAD_S
        if 0.3 * rad < top < 0.12 * w_ref and top < 2.0 * rad:
            raise DataError(
                f"{_where(source, lines, k, name, row_word)}: largest value {top:.4g} looks like rad/s, not rpm "
                f"(the setup's speed reference {w_ref:g} rpm is {rad:.4g} rad/s); multiply by 60/(2*pi) = 9.549")
        kiln = w_ref / params.n
        if 0 < top < 0.3 * rad and top < 3.0 * kiln:
            raise DataError(
                f"{_where(source, lines, k, name, row_word)}: largest value {top:.4g} looks like the kiln speed, "
                f"not the motor speed (the setup's {w_ref:g} rpm motor speed is {kiln:.3g} rpm at the kiln, "
                f"reduction n = {params.n:g}); multiply by n")
        if name == "speed_rpm" and np.median(a[a.size // 2:]) < 0 < w_ref:
            raise DataError(
                f"{source}: column 'speed_rpm' is negative over the second half of the record (median "
                f"{np.median(a[a.size // 2:]):.4g} rpm) while the setup's reference is +{w_ref:g} rpm; "
                "flip the sign of the speed (and current) channels")
    cur = arrays["current_A"]
    top = float(np.max(np.abs(cur)))
    k = int(np.argmax(np.abs(cur)))
    if 0 < top < 0.01 * params.I_max:
        raise DataError(
            f"{_where(source, lines, k, 'current_A', row_word)}: largest value {top:.4g} looks like kA or a "
            f"per-unit value, not A (the setup's current limit is {params.I_max:g} A); give the current in A")


# --- setup file -------------------------------------------------------------------
#: keys of the optional [measurement] section of a setup file
MEASUREMENT_KEYS = {
    "t0_s": "time in the record at which the start-up (speed ramp) begins [s]",
    "calibrate": "list of base parameters to calibrate (default: mu_c, mu_s, m_v, J_v)",
    "candidates": "list of catalogue effects diagnose may try (default: all)",
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
        parameter names), ``candidates`` (list of effect names).
    source : str
        The file, or ``<defaults>``.
    """

    params: Parameters
    options: dict = field(default_factory=dict)
    source: str = "<defaults>"


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
    try:
        raw = tomllib.loads(path.read_text())
    except FileNotFoundError:
        raise ConfigFileError(f"{path}: no such setup file") from None
    except IsADirectoryError:
        raise ConfigFileError(f"{path}: is a folder, not a setup file") from None
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise ConfigFileError(f"{path}: not a valid TOML file ({exc})") from None
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
    flat: dict[str, Any] = {}
    for key, value in raw.items():
        if isinstance(value, dict):
            if key not in GROUPS:
                raise ConfigFileError(f"{path}: unknown section [{key}]: "
                                      f"{close_matches_hint(key, list(GROUPS) + ['measurement'])}")
            flat.update(value)
        else:
            flat[key] = value
    try:
        params = Parameters(flat)
    except ParameterError as exc:
        raise ParameterError(f"{path}: {exc}") from None
    for k in options.get("calibrate", []):
        if k not in SPECS or SPECS[k].is_option:
            raise ConfigFileError(f"{path}: [measurement] calibrate names {k!r}, not a numeric parameter: "
                                  f"{close_matches_hint(k, [s for s in SPECS if not SPECS[s].is_option])}")
    return Setup(params, dict(options), str(path))
