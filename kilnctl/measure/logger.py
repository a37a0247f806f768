"""What a logger did to a record: an uneven time base, held values, resampling onto a finer grid, coarse steps.

The reader (:func:`kilnctl.measure.io.read_record`) turns each finding into a note; none changes the samples.
Two other logger checks have modules of their own, as they also mark samples that fits leave out: a channel
clipped at the end of its range (:mod:`~kilnctl.measure.clipping`) and spikes of one or two samples
(:mod:`~kilnctl.measure.glitches`).
"""

from __future__ import annotations

import numpy as np

__all__ = ["sampling_notes", "frozen_notes", "resampled_every", "resampled_notes", "speed_step", "speed_step_notes",
           "FROZEN_S", "FROZEN_SAMPLES", "RESAMPLED_MAX", "SPEED_STEP_RPM"]

def sampling_notes(t, dts, med, lines, row_word, gap_factor: float) -> list[str]:
    """Say how uneven the time base is: jitter, and steps that look like missing samples (beyond the jitter,
    below ``gap_factor`` times the median step, where the reader refuses a gap).

    Parameters
    ----------
    t : ndarray
        Sample times [s].
    dts : ndarray
        Their steps [s].
    med : float
        The median step [s].
    lines, row_word
        File line (row) of each sample, and what it counts (for the notes).
    gap_factor : float
        Steps this many medians long are gaps, refused before this is called [-].

    Returns
    -------
    list of str
        The reader's notes (none for an even time base).
    """
    out = []
    spread = float(1.4826 * np.median(np.abs(dts - med)) / med)  # robust relative spread of the steps
    if spread > 0.02:
        out.append(f"uneven time base: steps of {np.min(dts):.4g}-{np.max(dts):.4g} s (median {med:.4g} s, "
                   f"spread {100 * spread:.0f} %); the model is compared at the measured times")
    limit = max(1.5, 1.0 + 4.0 * spread)
    long_steps = np.flatnonzero(dts > limit * med)
    if long_steps.size:
        k = int(long_steps[np.argmax(dts[long_steps])])
        out.append(f"{long_steps.size} step(s) of {limit:.3g}-{gap_factor:g} x the median step {med:.4g} s (missing "
                   f"samples?), the longest {dts[k]:.4g} s between t = {t[k]:.6g} s and {t[k + 1]:.6g} s ({row_word} "
                   f"{int(lines[k + 1])}); "
                   "the model is compared at the measured times (only the residual spectrum is taken on an even grid)")
    return out


#: a stretch where the current and the speed both repeat their previous sample exactly, the drive turning, for
#: at least this long [s] and this many samples is named as a frozen logger
FROZEN_S, FROZEN_SAMPLES = 0.2, 5


def frozen_notes(t, arrays, lines, row_word) -> list[str]:
    """Say where the current and the speed both repeat one sample exactly while the drive turns (a logger that
    held its last values: a dropped connection, a stalled trend buffer).  Measured noise never repeats in both
    channels, even on a coarse converter's steps (the red team's record with 10 A steps and 6 A of noise: not
    once outside its held stretch); at standstill an encoder's zero and a converter that is off can, so
    stretches at zero speed are not named.  The samples are compared as they are.

    Parameters
    ----------
    t : ndarray
        Sample times [s].
    arrays : dict of str to ndarray
        The record's channels (``current_A`` [A], ``speed_rpm`` [rpm]).
    lines, row_word
        File line (row) of each sample, and what it counts (for the notes).

    Returns
    -------
    list of str
        One note per held stretch of at least :data:`FROZEN_S` and :data:`FROZEN_SAMPLES`.
    """
    cur, spd = arrays.get("current_A"), arrays.get("speed_rpm")
    if cur is None or spd is None or cur.size < FROZEN_SAMPLES + 1:
        return []
    same = (np.diff(cur) == 0) & (np.diff(spd) == 0) & (spd[1:] != 0)
    # runs of repeats: same[a:b] all True, so samples a..b hold the value of sample a
    edges = np.flatnonzero(np.diff(np.concatenate(([0], same.astype(np.int8), [0]))))
    out = []
    for a, b in zip(edges[::2], edges[1::2]):
        if b - a >= FROZEN_SAMPLES and t[b] - t[a] >= FROZEN_S:
            out.append(f"{row_word}s {int(lines[a])}-{int(lines[b])} ({t[a]:.2f}-{t[b]:.2f} s): the current and "
                       f"the speed both repeat one sample ({float(cur[a]):.4g} A, {float(spd[a]):.4g} rpm) for "
                       f"{t[b] - t[a]:.2f} s while the drive turns: a logger that held its last values? They are "
                       "not measurements, but they are compared as they are: cut them out if they are")
    return out


def resampled_every(current) -> int | None:
    """Every how many samples the logged current bends, when it is straight (or flat) in between: a record
    resampled from a coarser logger onto a finer grid, by linear interpolation or by holding values.

    A measured current has noise on every sample, so its differences are never zero to rounding; one
    interpolated k-fold is straight over k - 1 of every k samples, its bends all in one place modulo k (one
    held k-fold changes only there).  Judged: the bends (second differences above 1e-6 of the channel's peak,
    rounding below), or else the changes (first differences), in one residue modulo k for at least 90 % of
    them, k at most :data:`RESAMPLED_MAX` = 10.

    Parameters
    ----------
    current : ndarray
        The logged current [A], on an even grid.

    Returns
    -------
    int or None
        k (2 to 10), or None when the current is not resampled so.
    """
    a = np.asarray(current, float)
    if a.size < 50:
        return None
    tiny = 1e-6 * (float(np.max(np.abs(a))) or 1.0)
    for order in (2, 1):  # bends of a line interpolated, steps of values held
        bends = np.flatnonzero(np.abs(np.diff(a, order)) > tiny)
        if bends.size < 10 or bends.size > 0.6 * (a.size - order):
            continue
        for k in range(RESAMPLED_MAX, 1, -1):  # the largest: bends every 4th sample are every 2nd one's too
            if np.max(np.bincount(bends % k, minlength=k)) >= 0.9 * bends.size:
                return k
    return None


#: a speed logged in steps of at least this many rpm is named (:func:`speed_step`) [rpm]
SPEED_STEP_RPM = 0.2


def speed_step(speed) -> float | None:
    """The step a logged speed is quantised in (an encoder's counts per sample interval), or None.

    A measured speed from a tachometer or a fine encoder changes on every sample; one counted by a coarse
    encoder over a sample interval repeats its value on many samples and moves in whole steps (1024 counts
    per revolution read every 20 ms: 2.93 rpm).  Judged: at least 10 % of the changes are zero, in at least
    10 separate stretches (the counts flicker between steps; a speed without noise does not), and 90 % of
    the others lie within 5 % of a whole multiple of the step (the 10th percentile of their sizes), which
    is at least :data:`SPEED_STEP_RPM`.

    Parameters
    ----------
    speed : ndarray
        The logged speed [rpm].

    Returns
    -------
    float or None
        The step [rpm].
    """
    d = np.abs(np.diff(np.asarray(speed, float)))
    if d.size < 50:
        return None
    still = d <= 1e-9 * (float(np.max(np.abs(speed))) or 1.0)
    moving = d[~still]
    # the counts flicker between steps: many separate stretches without a change (a speed without noise, a
    # straight ramp and its hold, changes by one amount and then not at all: one stretch)
    stretches = int(np.sum(still[1:] & ~still[:-1])) + int(still[0])
    if moving.size < 10 or moving.size > 0.9 * d.size or stretches < 10:
        return None
    q = float(np.percentile(moving, 10))
    r = moving / q
    if q < SPEED_STEP_RPM or np.mean(np.abs(r - np.round(r)) < 0.05) < 0.9:
        return None
    return float(np.median(moving[np.round(r) == 1]))


def speed_step_notes(arrays) -> list[str]:
    """Say when the speed is logged in coarse steps (:func:`speed_step`).

    Parameters
    ----------
    arrays : dict of str to ndarray
        The record's channels (``speed_rpm`` [rpm]).

    Returns
    -------
    list of str
        The reader's note, or none.
    """
    q = speed_step(arrays.get("speed_rpm"))
    if q is None:
        return []
    return [f"the speed is logged in steps of {q:.3g} rpm (a coarse encoder counted over each sample?): "
            "detail smaller than a step is not in the record, so an effect seen only in the speed's detail "
            "(a drive train's ringing of a few rpm) may go unseen; log the speed finer if you can"]


#: largest factor of resampling :func:`resampled_every` names
RESAMPLED_MAX = 10


def resampled_notes(t, arrays, med) -> list[str]:
    """Say when the current was resampled from a coarser logger (:func:`resampled_every`).

    Parameters
    ----------
    t : ndarray
        Sample times [s].
    arrays : dict of str to ndarray
        The record's channels (``current_A`` [A]).
    med : float
        The median sample step [s].

    Returns
    -------
    list of str
        The reader's note, or none.
    """
    k = resampled_every(arrays.get("current_A"))
    if k is None:
        return []
    return [f"the current is straight or flat between samples {k} apart: the record looks resampled from a "
            f"logger at about {1.0 / (k * med):.3g} Hz onto {1.0 / med:.3g} Hz (linear interpolation or held "
            "values); the samples in between are not measurements, yet the fit % and the evidence count them as "
            "such: export the record at the logger's own rate if you can"]
