"""Isolated spikes in a logged channel: a logger's or a sensor's glitch of one or two samples.

A converter's thyristors or a contactor can put an electromagnetic spike of a
few tens to hundreds of amperes on the current sensor's line, over one sample
or two (the second smaller); a logger can drop a bit.  No model of the drive
makes such a spike, and one glitch costs every model points of fit % (3000 A
once in the shipped example: 98.1 -> 84.2 %) and shows as the model's largest
local failure.  The reader finds them (:func:`glitches`); a
:class:`~kilnctl.measure.io.Measurement` leaves their samples out of fits,
evidence, fit % and failing intervals, as it does with clipped samples
(:attr:`~kilnctl.measure.io.Measurement.kept`), and says so in a note.

A spike is a sample that lies more than :data:`SPIKE_SIGMAS` noise standard
deviations from the median of the samples two and three steps either side,
and more than five times their spread from it; the sample next to it on
either side is part of the spike when it lies on the same side by more than
:data:`TAIL_SIGMAS` (both so: three samples, an event, no glitch).  A
breakaway's fall, a ramp's corner or a backlash impact's ringing moves the
samples either side too, so the spread test keeps them out; a spike the
other channel answers (a backlash impact over two samples jolts the shaft)
is an event, not a glitch; and a spike is at least :data:`MIN_SHARE` of the
channel's range (where the noise is tiny, a kink is thousands of its
standard deviations).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .stats import robust_sigma

__all__ = ["Glitch", "glitches", "glitch_mask", "glitch_notes", "SPIKE_SIGMAS", "TAIL_SIGMAS", "JOLT_SIGMAS"]

#: a sample this many noise standard deviations from the median of its neighbours two and three steps away, and
#: five times further from it than they spread, is a spike
SPIKE_SIGMAS = 20.0
#: a sample next to a spike, on its side of the neighbours' median by this many noise standard deviations, is part
#: of it (a glitch over two samples, the second smaller)
TAIL_SIGMAS = 4.0
#: least size of a spike, as a share of the channel's range (its 1st to 99th percentile) [-]: where the noise is
#: tiny or none (a simulated record, a historian's compressed or interpolated values) a breakaway's kink in the
#: speed, a few rpm, or a knot of a 10 A deadband is thousands of "noise" standard deviations
MIN_SHARE = 0.02
#: the other channel leaping this many noise standard deviations at a spike's own sample, against it, answers the
#: spike: the shaft was jolted within one sample step
JOLT_SIGMAS = 10.0


@dataclass(frozen=True)
class Glitch:
    """A spike of one or two samples in one channel.

    Attributes
    ----------
    channel : str
        ``current_A`` or ``speed_rpm``.
    at : tuple of int
        Indices of its samples (one or two, increasing).
    peak : int
        Index of its largest sample.
    size : float
        Largest sample less the neighbours' median [unit of the channel].
    sigmas : float
        ``size`` in noise standard deviations.
    """

    channel: str
    at: tuple
    peak: int
    size: float
    sigmas: float


def _noise_sigma(a) -> float:
    """Noise standard deviation from the second differences (white noise of sigma gives sigma sqrt(6)); those of
    exactly zero (values held, clipped or quantised) say nothing of the noise and are left out."""
    d2 = np.diff(a, 2)
    moving = d2[d2 != 0.0]
    return max(robust_sigma(moving if moving.size >= 10 else d2) / math.sqrt(6.0),
               1e-9 * (float(np.ptp(a)) or 1.0))


def _channel(a, name: str) -> list[Glitch]:
    a = np.asarray(a, float)
    n = a.size
    if n < 7:
        return []
    sigma = _noise_sigma(a)
    floor = MIN_SHARE * float(np.subtract(*np.percentile(a, [99.0, 1.0])))
    k = np.arange(3, n - 3)
    nb = np.stack([a[k - 3], a[k - 2], a[k + 2], a[k + 3]])
    med = np.median(nb, axis=0)
    dev = a[k] - med
    spread = np.ptp(nb, axis=0)
    peaks = k[(np.abs(dev) > SPIKE_SIGMAS * sigma) & (np.abs(dev) > 5.0 * spread) & (np.abs(dev) > floor)]
    out: list[Glitch] = []
    taken: set = set()
    # largest first: a two-sample spike whose samples are both large is one glitch
    for p in sorted(peaks.tolist(), key=lambda j: -abs(dev[j - 3])):
        if p in taken:
            continue
        d = float(dev[p - 3])
        m = float(med[p - 3])
        tails = [q for q in (p - 1, p + 1)
                 if q not in taken and np.sign(a[q] - m) == np.sign(d) and abs(a[q] - m) > TAIL_SIGMAS * sigma]
        if len(tails) == 2:
            continue  # three samples or more on one side: an event, not a glitch of one or two samples
        if tails and abs(a[tails[0]] - m) > abs(d):
            continue  # the neighbour is larger: it is the peak, found on its own
        at = sorted([p] + tails)
        taken.update(at)
        out.append(Glitch(name, tuple(at), p, d, abs(d) / sigma))
    return sorted(out, key=lambda g: g.at[0])


def _answers(other, g: Glitch, sigma: float) -> bool:
    """True when the other channel answers a spike: it leaves the line through its samples three to eight steps
    either side by more than :data:`TAIL_SIGMAS` at three or more of the five samples around the spike's peak,
    or at one of the spike's own samples by more than :data:`JOLT_SIGMAS` the other way (the speed down where
    the current is up).  A backlash impact jolts the shaft (red team 8's second motor meeting its gear: +585 A
    over two samples at 50 Hz, the speed 26 standard deviations down and back over five; red team 21's rigid
    teeth meeting, four impacts within 70 ms: +374 A and the speed 19 standard deviations down in the same
    sample, back above its line in the next), and a breakaway's dip in the speed comes with the current's fall;
    interference on one sensor's line leaves the other channel alone, or puts a spike of its own on it with
    no relation to the first's sign."""
    k = g.peak
    idx = np.r_[np.arange(k - 8, k - 2), np.arange(k + 3, k + 9)]
    idx = idx[(idx >= 0) & (idx < other.size)]
    near = np.arange(max(k - 2, 0), min(k + 3, other.size))
    if idx.size < 4:
        return False
    c = np.polyfit(idx.astype(float), other[idx], 1)
    dev = other[near] - np.polyval(c, near.astype(float))
    if int(np.sum(np.abs(dev) > TAIL_SIGMAS * sigma)) >= 3:
        return True
    # a jolt within one sample: the other channel leaps at the spike's own samples, against it (current up, speed
    # down: a speed that drops raises the current through the speed loop and the back-EMF alike)
    leap = dev[[j - near[0] for j in g.at if near[0] <= j <= near[-1]]]
    return bool(np.any(-np.sign(g.size) * leap > JOLT_SIGMAS * sigma))


def glitches(arrays) -> tuple:
    """The isolated spikes of the current and the speed (see the module's docstring).

    Parameters
    ----------
    arrays : dict of str to ndarray
        The record's channels (``current_A``, ``speed_rpm`` ...).

    Returns
    -------
    tuple of Glitch
        By channel, then time.
    """
    out = []
    pair = {"current_A": "speed_rpm", "speed_rpm": "current_A"}
    for name in ("current_A", "speed_rpm"):
        a = arrays.get(name)
        if a is None:
            continue
        found = _channel(a, name)
        other = arrays.get(pair[name])
        if found and other is not None and other.size >= 7:
            other = np.asarray(other, float)
            sigma = _noise_sigma(other)
            found = [g for g in found if not _answers(other, g, sigma)]
        out += found
    return tuple(out)


def glitch_mask(found, n: int) -> np.ndarray:
    """Mask of the samples outside every spike.

    Parameters
    ----------
    found : sequence of Glitch
        Spikes (:func:`glitches`).
    n : int
        Number of samples of the record.

    Returns
    -------
    ndarray of bool
        True where no spike sits.
    """
    keep = np.ones(n, bool)
    for g in found:
        keep[list(g.at)] = False
    return keep


def glitch_notes(found, arrays, lines, row_word, labels=None, step_s: float | None = None) -> list[str]:
    """One reader's note per channel with spikes: how many, the largest, and that they are left out.

    Parameters
    ----------
    found : sequence of Glitch
        Spikes (:func:`glitches`).
    arrays : dict of str to ndarray
        The record's channels.
    lines, row_word
        File line (row) of each sample, and what it counts.
    labels : dict, optional
        The record's own column names, for the notes.
    step_s : float, optional
        The record's sample step [s], named in the notes.

    Returns
    -------
    list of str
        The notes.
    """
    step = f" of {step_s * 1e3:.3g} ms" if step_s is not None and step_s > 0 else ""
    units = {"current_A": "A", "speed_rpm": "rpm"}
    out = []
    for name in ("current_A", "speed_rpm"):
        gs = [g for g in found if g.channel == name]
        if not gs:
            continue
        a = arrays[name]
        g = max(gs, key=lambda g: abs(g.size))
        unit = units[name]
        label = (labels or {}).get(name) or repr(name)
        n_two = sum(len(x.at) == 2 for x in gs)
        kinds = (f"{len(gs)} isolated spike(s) of one sample" if n_two == 0 else
                 f"{len(gs)} isolated spike(s) of one or two samples ({n_two} of two)")
        n_samples = sum(len(x.at) for x in gs)
        out.append(f"column {label}: {kinds}, the largest on {row_word} {int(lines[g.peak])}: "
                   f"{float(a[g.peak]):.4g} {unit} where the samples around it read about "
                   f"{float(a[g.peak] - g.size):.4g} {unit} ({g.sigmas:.0f} noise standard deviations): a "
                   f"glitch (a converter's or a contactor's interference, a logger's error) or an event shorter than "
                   f"the sample step{step} (a backlash's impact lasts a few milliseconds)? Their {n_samples} "
                   "sample(s) are left out of fits, evidence and fit % (no model makes such a spike); correct the "
                   "record if they are real")
    return out
