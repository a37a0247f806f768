"""Burden breakaways in a record, matched in time with the model's: a smooth cost for stick-slip fits.

Stick-slip cycles of the burden (the torque-consistent friction law) show in
the drive current as a saw-tooth: the current rises while the burden is
carried up with the shell and falls within a few tenths of a second when it
breaks away (and again when it sticks).  The simulation-error cost of such a
record is rugged in the friction and the burden's mass and inertia: every
fall that the model places a fraction of a sample away from the record's
leaves a spike in the residual, and the sum of those spikes changes by a cusp
each time a fall crosses a sample.  A local fit stops on the first cusp (on
the red-team record f6, 90 s at 10 Hz: 86 % where the same structure
reaches 96 %).

The model's own event times are smooth in the parameters (the simulator
finds each switch by root finding).  :class:`BreakawayTiming` therefore
replaces the samples around the record's falls by the difference of the
times themselves: the record's falls are found once by :func:`breakaways`,
paired in order with the model's burden switches after which its current
falls, and each pair contributes ``w_k (t_model - t_record)``, where ``w_k``
is what that time error costs in the simulation-error cost (the root sum of
squares of the model current's slope over the samples it replaces).  The
detector reads a fall a little late (it interpolates the middle of the fall
between samples); that lag is measured on the model (detector on its sampled
current against its exact switch times) and taken off the record's times.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .stats import median_step

__all__ = ["breakaways", "Falls", "model_switches", "BreakawayTiming", "DROP_WINDOW_S"]

#: window over which a breakaway's fall of the current is measured [s] (the speed loop answers a sudden loss
#: of load within a few tenths of a second)
DROP_WINDOW_S = 0.3
#: least time between two falls [s]
MIN_SPACING_S = 0.5
#: burden switches that can make the current fall (component, kinds)
BURDEN_SWITCHES = ("burden", ("breakaway", "restick"))


@dataclass
class Falls:
    """Sharp falls of a current found by :func:`breakaways`.

    Attributes
    ----------
    times : ndarray
        Where each fall crosses its middle level, interpolated between samples [s].
    threshold : float
        The least fall counted [A] (inf when there were too few samples).
    """

    times: np.ndarray
    threshold: float

    @property
    def size(self) -> int:
        """Number of falls."""
        return int(self.times.size)


def breakaways(t, current, *, t_from: float, threshold: float | None = None, keep=None) -> Falls:
    """Times at which the current falls sharply (burden breakaways and re-sticks), after ``t_from``.

    The fall over :data:`DROP_WINDOW_S`, ``D(t) = i(t + w) - i(t)``, is computed by linear interpolation on a
    grid of half the median sample step (any time base, uniform or not).  A fall is a local minimum of D
    below ``-threshold``, at least :data:`MIN_SPACING_S` from a deeper one.  Its time is where the current
    crosses the middle of the fall, interpolated between samples.

    Parameters
    ----------
    t : array_like
        Times [s], increasing.
    current : array_like
        Current [A].
    t_from : float
        Only falls that begin after this time count [s] (the ramp's own transients are no breakaways).
    threshold : float, optional
        Least fall [A].  Default: the larger of 8 robust standard deviations of D (noise alone rarely reaches
        it) and 40 % of the deepest fall.
    keep : ndarray of bool, optional
        The samples to use (default all): a logger's spike (:mod:`~kilnctl.measure.glitches`) falls back as
        sharply as a breakaway, so the record's spikes are left out and the current is read across them.

    Returns
    -------
    Falls
        Times of the falls [s], increasing, and the threshold used [A].
    """
    t = np.asarray(t, float)
    i = np.asarray(current, float)
    if keep is not None:
        t, i = t[np.asarray(keep, bool)], i[np.asarray(keep, bool)]
    none = Falls(np.zeros(0), float("inf") if threshold is None else float(threshold))
    if t.size < 4 or t[-1] - DROP_WINDOW_S <= t_from:
        return none
    dt = max(median_step(t), 1e-4)
    grid = np.arange(t_from, t[-1] - DROP_WINDOW_S, dt / 2.0)
    if grid.size < 3:
        return none
    lo = np.interp(grid, t, i)
    hi = np.interp(grid + DROP_WINDOW_S, t, i)
    d = hi - lo
    if threshold is None:
        dd = np.diff(d)
        noise = 1.4826 * float(np.median(np.abs(dd - np.median(dd)))) * np.sqrt(DROP_WINDOW_S / dt)
        threshold = max(8.0 * noise, 0.4 * float(-d.min()) if d.min() < 0 else 0.0)
        if not threshold > 0:
            return none
    cand = np.flatnonzero((d[1:-1] < d[:-2]) & (d[1:-1] <= d[2:]) & (d[1:-1] < -threshold)) + 1
    kept: list[int] = []
    for k in cand[np.argsort(d[cand], kind="stable")]:  # deepest first, each suppressing shallower neighbours
        if all(abs(grid[k] - grid[j]) >= MIN_SPACING_S for j in kept):
            kept.append(int(k))
    times = []
    for k in sorted(kept):
        mid = 0.5 * (lo[k] + hi[k])
        a, b = grid[k], grid[k] + DROP_WINDOW_S
        sel = (t > a) & (t < b)
        ts = np.concatenate([[a], t[sel], [b]])
        ys = np.concatenate([[lo[k]], i[sel], [hi[k]]])
        below = np.flatnonzero(ys <= mid)
        j = int(below[0]) if below.size else ys.size - 1
        if j == 0:
            times.append(float(a))
            continue
        y0, y1 = ys[j - 1], ys[j]
        frac = (y0 - mid) / (y0 - y1) if y0 != y1 else 0.0
        times.append(float(ts[j - 1] + frac * (ts[j] - ts[j - 1])))
    return Falls(np.asarray(times), float(threshold))


def model_switches(run, t0: float, t_from: float) -> np.ndarray:
    """Record times [s] of the model's burden breakaways and re-sticks after ``t_from``.

    Parameters
    ----------
    run : ModelRun
        A model run (its ``events`` are the simulator's switches, times from ``t0``).
    t0 : float
        Start of the experiment in record time [s].
    t_from : float
        Earliest record time [s].

    Returns
    -------
    ndarray
        Switch times [s], increasing (exact: the simulator's root-found event times).
    """
    comp, kinds = BURDEN_SWITCHES
    ts = [e.t + t0 for e in run.events if e.component == comp and e.kind in kinds and e.t + t0 >= t_from]
    return np.asarray(ts, float)


@dataclass
class BreakawayTiming:
    """The record's current falls paired with the model's burden switches, as a smooth residual.

    Attributes
    ----------
    t_record : ndarray
        Record times of the paired falls [s], less the detector's lag (so that they compare with a model
        switch).
    ordinals : ndarray of int
        Index of each paired switch among :func:`model_switches` of a run.
    weights : ndarray
        Cost of one second of time error of each pair [A/s]: the root sum of squares of the model
        current's slope over the samples it replaces.
    near : ndarray of bool
        Samples (of the compared part of the record) left out of the current's residual.
    clip : float
        Largest time error counted [s] (half the median spacing of the falls): a fall further off is a
        missing one, whatever its distance.
    lag : float
        The detector's lag behind a switch [s]: median over the pairs of the detector's time on the model's
        current (sampled like the record) less the model's switch time.
    t0, t_from : float
        Start of the experiment and of the cycles [s], record time.
    """

    t_record: np.ndarray
    ordinals: np.ndarray
    weights: np.ndarray
    near: np.ndarray
    clip: float
    lag: float
    t0: float
    t_from: float

    @classmethod
    def pair(cls, t, current, run, *, t0: float, t_from: float, mask=None, keep=None) -> "BreakawayTiming | None":
        """Pair the record's falls with those of a model run, in order of time.

        Parameters
        ----------
        t : ndarray
            Compared record times (at or after ``t0``) [s].
        current : ndarray
            Measured current at those times [A].
        run : ModelRun
            The model at the starting point of a fit (its current sampled at ``t``, and its fine output).
        t0 : float
            Start of the experiment [s].
        t_from : float
            Record time from which falls are stick-slip cycles [s] (after the ramp).
        mask : ndarray of bool, optional
            The fitted samples: a pair whose samples are not all fitted (a held-out block) is not used.
        keep : ndarray of bool, optional
            The record's samples its falls are found on (its spikes left out: :func:`breakaways`).

        Returns
        -------
        BreakawayTiming or None
            None when the record or the model has fewer than two falls after ``t_from``, or no pair lies
            wholly in the fitted samples (nothing to compare).
        """
        t = np.asarray(t, float)
        rec = breakaways(t, current, t_from=t_from, keep=keep)
        if rec.size < 2:
            return None
        y = np.asarray(run.outputs["current_A"], float)
        sw = model_switches(run, t0, t_from)
        dt = max(median_step(t), 1e-6)
        # the switches after which the model's current falls like the record's
        falls = [k for k, ts in enumerate(sw)
                 if np.diff(np.interp([ts - dt, ts + DROP_WINDOW_S], t, y))[0] < -0.5 * rec.threshold]
        n = min(len(falls), rec.size)
        if n < 2:
            return None
        ordinals = np.asarray(falls[:n], int)
        t_mod = sw[ordinals]
        # the detector's lag behind a switch, on the model's current sampled at the record's times: the same
        # detector on the same sample times, so that its bias from where a fall lies between samples cancels
        det = breakaways(t, y, t_from=t_from, threshold=rec.threshold).times
        lags = [float(det[np.argmin(np.abs(det - ts))] - ts) for ts in t_mod if det.size]
        lags = [v for v in lags if abs(v) < DROP_WINDOW_S]
        lag = float(np.median(lags)) if lags else 0.0
        t_record = rec.times[:n] - lag
        g = np.gradient(y, t)
        fitted = np.ones(t.size, bool) if mask is None else np.asarray(mask, bool)
        near = np.zeros(t.size, bool)
        keep, weights = [], []
        for k in range(n):
            # the samples where a misplaced fall leaves its spike, around the record's and the model's fall
            w_rec = (t >= t_record[k] - 1.5 * dt) & (t <= t_record[k] + DROP_WINDOW_S + dt)
            w_mod = (t >= t_mod[k] - 1.5 * dt) & (t <= t_mod[k] + DROP_WINDOW_S + dt)
            if not fitted[w_rec].all():
                continue
            near |= w_rec
            keep.append(k)
            weights.append(float(np.sqrt(np.sum(g[w_mod] ** 2))))
        if not keep or not np.all(np.isfinite(weights)):
            return None
        spacing = float(np.median(np.diff(t_record)))
        return cls(t_record[keep], ordinals[keep], np.asarray(weights), near, 0.5 * spacing, lag, float(t0),
                   float(t_from))

    @property
    def size(self) -> int:
        """Number of paired falls."""
        return int(self.ordinals.size)

    def errors(self, run) -> np.ndarray:
        """Model minus record time of each paired fall [s], clipped at ``clip`` (a missing switch: ``clip``)."""
        sw = model_switches(run, self.t0, self.t_from)
        d = np.full(self.size, self.clip)
        have = self.ordinals < sw.size
        d[have] = np.clip(sw[self.ordinals[have]] - self.t_record[have], -self.clip, self.clip)
        return d

    def residual(self, run, scale: float) -> np.ndarray:
        """``weights * errors / scale``: the pairs' part of a scaled residual [-]."""
        return self.weights * self.errors(run) / scale
