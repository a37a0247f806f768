"""A logged channel clipped at the end of its range (an ADC or a transducer saturated).

A current clipped at 95 % of its peak sits at one value for seconds; calibrated as it is, the flat
stretch is matched by the model's parameters (red team 7: J_v 87 % low and a motor friction 18 %
high on one record, nothing said).  A clipped sample says only that the quantity was *at least* its
level: it is not a measurement of it.  :func:`clipped_levels` finds such a stretch;
:attr:`Measurement.unclipped <kilnctl.measure.io.Measurement.unclipped>` marks the samples the fits,
the evidence and the fit % use.  (Kept as bounds instead -- a model beyond the level agreeing with such a
sample -- they let a fit buy the rest of the record with anything above the level: on red team 7's record
clipped at 95 % of its peak, a kiln unbalance of 3.3e6 N m whose current stays above it.)
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .logger import speed_step
from .stats import robust_sigma

__all__ = ["ClipLevel", "clipped_levels", "clipped_notes", "unclipped", "residual", "CLIP_MIN_SAMPLES", "CLIP_RATIO", "NOISE_REL",
           "DRIVE_LIMIT_TOL"]

#: a channel is clipped at its largest (smallest) value when at least this many samples sit exactly there ...
CLIP_MIN_SAMPLES = 10
#: ... and at least this many times as many as at any other single value: measured noise, even on a coarse
#: converter's steps, spreads the samples over many values (red team 7's 10 A steps: 2-33 samples at the
#: largest value, 248-428 at the commonest; clipped at 95 % of the peak: 1149-1209 at the largest, 1-2 at any other)
CLIP_RATIO = 5.0
#: ... in a channel with measurement noise of at least this fraction of its largest magnitude [-] (from its
#: third differences, which a smooth signal keeps near zero): without noise a record that settles at one value,
#: or follows a limit, holds it exactly, and 6 significant digits round at 1e-6 of the value
NOISE_REL = 2e-5
#: an upper (lower) level of the current within this fraction of the setup's I_max (-I_max) is the drive's own
#: current limit, which a record without noise holds exactly, not the logger's range [-]; so is a speed level
#: within this fraction of the set speed (or within one step of a speed logged in steps), the speed loop
#: holding its set point: an encoder counted over each sample reads it exactly while the speed's ripple stays
#: inside one count (red team 13's speed in 2 rpm steps at its 600 rpm set point: 71 % of the record, both
#: channels, had been left out as clipped, and the base calibrated on the ramp alone, mu_c 30 % high)
DRIVE_LIMIT_TOL = 0.01


@dataclass(frozen=True)
class ClipLevel:
    """Where a logged channel is clipped.

    Attributes
    ----------
    channel : str
        ``current_A`` or ``speed_rpm``.
    side : {'upper', 'lower'}
        Clipped at the channel's largest or smallest value.
    level : float
        The value the clipped samples sit at (in the channel's unit).
    n : int
        Samples at it.
    n_other : int
        Most samples at any other single value of the channel.
    """

    channel: str
    side: str
    level: float
    n: int
    n_other: int

    def at(self, values) -> np.ndarray:
        """Mask of the samples of ``values`` that sit at the level."""
        return np.asarray(values, float) == self.level


def clipped_levels(arrays, i_max: float | None = None, set_speeds=()) -> list[ClipLevel]:
    """The logged channels' clipped ends: a largest or smallest value held by many samples.

    Parameters
    ----------
    arrays : dict of str to ndarray
        The record's channels (``current_A`` [A], ``speed_rpm`` [rpm]).
    i_max : float, optional
        The setup's armature current limit [A]: a level within :data:`DRIVE_LIMIT_TOL` of it is the drive's
        limit, not the logger's.
    set_speeds : sequence of float
        The set speeds the drive may hold [rpm] (the setup's omega_ref, the logged reference's top): a speed
        level within :data:`DRIVE_LIMIT_TOL` of one, or within one step of a speed logged in steps
        (:func:`~kilnctl.measure.logger.speed_step`), is the speed loop holding it, not the logger's range.

    Returns
    -------
    list of ClipLevel
        Empty when no channel is clipped.
    """
    out = []
    for name in ("current_A", "speed_rpm"):
        a = arrays.get(name)
        if a is None or a.size < 2 * CLIP_MIN_SAMPLES:
            continue
        values, counts = np.unique(a, return_counts=True)
        for side, k in (("upper", -1), ("lower", 0)):
            n_at = int(counts[k])
            others = np.delete(counts, k if k >= 0 else counts.size - 1)
            if n_at < CLIP_MIN_SAMPLES or (others.size and n_at < CLIP_RATIO * others.max()):
                continue
            level = float(values[k])
            if name == "current_A" and i_max and abs(abs(level) - i_max) <= DRIVE_LIMIT_TOL * i_max:
                continue
            if name == "speed_rpm" and _holds_set_speed(a, level, set_speeds):
                continue
            at_mask = a == level
            if _noise(a, at_mask) < NOISE_REL * float(np.max(np.abs(a))):
                continue
            at = np.flatnonzero(at_mask)
            # a converter that is off before the start logs one value (0 A) on every sample at rest: a stretch
            # from the first sample is no clipped range unless enough samples sit at the level after it
            lead = int(np.argmax(np.diff(at) != 1)) + 1 if at.size > 1 and (np.diff(at) != 1).any() else at.size
            if at[0] == 0 and at.size - lead < CLIP_MIN_SAMPLES:
                continue
            out.append(ClipLevel(name, side, level, n_at, int(others.max()) if others.size else 0))
    return out


def _holds_set_speed(speed, level: float, set_speeds) -> bool:
    """True when a speed level lies within :data:`DRIVE_LIMIT_TOL` of a set speed, or within one of the
    speed's logged steps."""
    step = None
    for w in set_speeds:
        if w is None or not np.isfinite(w) or w == 0:
            continue
        if abs(abs(level) - abs(w)) <= DRIVE_LIMIT_TOL * abs(w):
            return True
        step = speed_step(speed) if step is None else step
        if step and abs(abs(level) - abs(w)) <= step:
            return True
    return False


def unclipped(levels, channels) -> np.ndarray | None:
    """Mask of the samples where no channel sits at the level the logger clipped it at.

    Parameters
    ----------
    levels : sequence of ClipLevel
        Clipped ends (:func:`clipped_levels`).
    channels : dict of str to ndarray
        The record's channels.

    Returns
    -------
    ndarray of bool or None
        True where no channel is clipped; None when ``levels`` is empty.
    """
    keep = None
    for c in levels:
        at = c.at(channels[c.channel])
        keep = ~at if keep is None else keep & ~at
    return keep


def residual(measurement, channel: str, model, active) -> np.ndarray:
    """Measured minus model of one channel, 0 where the logger clipped the record or a spike sits.

    Parameters
    ----------
    measurement : Measurement
        The record (:attr:`Measurement.kept <kilnctl.measure.io.Measurement.kept>` marks the samples that
        are measurements).
    channel : str
        ``current_A`` or ``speed_rpm``.
    model : ndarray
        The model's signal on the samples ``active`` [unit of the channel].
    active : ndarray of bool
        The compared samples.

    Returns
    -------
    ndarray
        The residual on the samples ``active`` [unit of the channel].
    """
    return np.where(measurement.kept[active], measurement.channels[channel][active] - model, 0.0)


def _noise(a, at) -> float:
    """Robust standard deviation of a channel's noise away from the samples ``at`` [its unit], from its third
    differences (white noise of sigma gives sigma sqrt(20); a smooth signal, near zero); 0 when too few."""
    d3 = np.diff(a, 3)
    away = ~(at[:-3] | at[1:-2] | at[2:-1] | at[3:])
    if away.sum() < 5:  # (a gate, noise or none: a few differences tell)
        return 0.0
    return robust_sigma(d3[away]) / np.sqrt(20.0)


def clipped_notes(levels, arrays, t, lines, row_word, labels=None) -> list[str]:
    """One reader's note per clipped channel: how many samples, where, and what is done with them.

    Parameters
    ----------
    levels : sequence of ClipLevel
        Clipped ends (:func:`clipped_levels`).
    arrays : dict of str to ndarray
        The record's channels.
    t : ndarray
        Sample times [s].
    lines, row_word
        File line (row) of each sample, and what it counts.
    labels : dict, optional
        The record's own column names, for the notes.

    Returns
    -------
    list of str
        The notes.
    """
    units = {"current_A": "A", "speed_rpm": "rpm"}
    out = []
    for c in levels:
        at = np.flatnonzero(c.at(arrays[c.channel]))
        label = (labels or {}).get(c.channel) or repr(c.channel)
        word, bound = ("largest", "at least") if c.side == "upper" else ("smallest", "at most")
        what = "current" if c.channel == "current_A" else "speed"
        out.append(f"column {label}: {c.n} samples ({100.0 * c.n / t.size:.0f} % of the record, "
                   f"{t[at[0]]:.2f}-{t[at[-1]]:.2f} s, {row_word}s {int(lines[at[0]])}-{int(lines[at[-1]])}) sit at "
                   f"exactly {c.level:.6g} {units[c.channel]}, its {word} value, where no other value is logged "
                   f"more than {_times(c.n_other)}: the logger's range looks clipped there. Such a sample "
                   f"says only that the {what} was {bound} {c.level:.6g} {units[c.channel]}, so the fits, the "
                   "evidence and the fit % leave those samples out (both channels)")
    return out


def _times(n: int) -> str:
    return {1: "once", 2: "twice"}.get(n, f"{n} times")
