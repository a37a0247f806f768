"""Changes outside the catalogue, added to the model's current in closed form.

A calibration can carry one of these terms as the hypothesis of a difference that no model component
describes (see :class:`~kilnctl.measure.calibrate.Calibration`, ``outside``).  At every trial run the term
is fitted to the current's residual on the fitted samples by linear least squares (variable projection), so
it adds no parameter to the search, and counts as :attr:`n_params` parameters in the BIC.

- :class:`CurrentStep`: b H(t - tau), an abrupt change (a load step, a process upset, a sensor fault);
- :class:`CurrentPulse`: b (H(t - t_on) - H(t - t_off)), a change that comes and goes (a load that builds up
  and slumps, a process upset that passes);
- :class:`CurrentDrift`: a + b (t - t_start), a straight-line drift of the logged current over the whole
  record (a current-sensor offset or gain drifting as the electronics warm up).

Each ``fit`` returns a dict with ``kind``, ``rss`` [A^2] and the term's values, or None; ``shape`` gives the
term at given times; ``text`` says it for a report.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .stats import best_pulse, best_step, robust_sigma


@dataclass(frozen=True)
class CurrentStep:
    """An abrupt step b H(t - tau) of the current, tau within ``window``.

    Parameters
    ----------
    window : (float, float)
        Earliest and latest step times tried [s] (record time).
    """

    window: tuple

    kind = "step"
    n_params = 2  # b and tau

    def fit(self, t, e) -> dict | None:
        """The best step of the residual ``e`` [A] at times ``t`` [s] (zero before it), or None when no step
        time lies in the window (:func:`~kilnctl.measure.stats.best_step`)."""
        step = best_step(t, e, t_min=self.window[0], t_max=self.window[1], intercept=False)
        return None if step is None else dict(step, kind=self.kind)

    def shape(self, t, fitted) -> np.ndarray:
        """The step, in A, at times ``t`` [s]."""
        return fitted["size"] * (np.asarray(t, float) >= fitted["t"])

    @staticmethod
    def text(fitted) -> str:
        """The step for a report."""
        return (f"an abrupt change at t = {fitted['t']:.1f} s: the current steps by {fitted['size']:+.0f} A while "
                "the drive runs at its set speed, which no catalogued effect does (a load step, a process upset, a "
                "sensor fault)")


@dataclass(frozen=True)
class CurrentPulse:
    """A change b (H(t - t_on) - H(t - t_off)) of the current that comes and goes, both edges within ``window``.

    Parameters
    ----------
    window : (float, float)
        Earliest rise and latest fall tried [s] (record time).
    min_width : float, default 1.0
        Shortest pulse tried [s]: a shorter one is a local failure, which the residual's signature names.
    """

    window: tuple
    min_width: float = 1.0

    kind = "pulse"
    n_params = 3  # b, t_on and t_off

    def fit(self, t, e) -> dict | None:
        """The best pulse of the residual ``e`` [A] at times ``t`` [s] (zero outside it), or None when none
        fits the window (:func:`~kilnctl.measure.stats.best_pulse`)."""
        pulse = best_pulse(t, e, t_min=self.window[0], t_max=self.window[1], min_width=self.min_width)
        return None if pulse is None else dict(pulse, kind=self.kind)

    def shape(self, t, fitted) -> np.ndarray:
        """The pulse, in A, at times ``t`` [s]."""
        t = np.asarray(t, float)
        return fitted["size"] * ((t >= fitted["t"]) & (t < fitted["t_end"]))

    @staticmethod
    def abrupt(t, e, fitted, *, span: float = 1.0, share: float = 0.5, z: float = 3.0) -> bool:
        """True when both edges of the fitted pulse are abrupt in the residual ``e`` [A] that it was fitted to.

        Across each edge the residual's mean over ``span`` seconds after it differs from its mean over
        ``span`` seconds before it by at least ``share`` of the pulse's height, in the pulse's direction (at
        the fall, in the opposite one), and that share of the height is at least ``z`` standard errors of such
        a difference (the robust standard deviation of the same difference taken at every sample away from
        the edges: the record's own noise at that scale, coloured noise and the model's misfit included): the
        edges must be resolved above the noise.  A smooth rise and fall
        (part of a slow sinusoid, as a kiln unbalance shows over less than a kiln turn) also has a best pulse,
        but changes over a second by little of its height, or by what slowly correlated noise moves a second's
        mean anyway.

        Parameters
        ----------
        t : array_like
            Times [s], increasing.
        e : array_like
            The residual without the pulse [A].
        fitted : dict
            The pulse (:meth:`fit`).
        span : float, default 1.0
            Length of the means on either side of an edge [s] (the pulse is at least ``min_width`` long).
        share : float, default 0.5
            Least jump across an edge, as a share of the pulse's height [-].
        z : float, default 3.0
            Least size of that share, in standard errors of the jump [-].
        """
        t = np.asarray(t, float)
        e = np.asarray(e, float)
        size = float(fitted["size"])
        n = int(np.sum((t >= fitted["t"]) & (t < fitted["t"] + span)))
        if n == 0:
            return False
        # the noise of such a jump, read off the record: the jumps between neighbouring means of n samples
        # wherever the pulse's edges are not (coloured noise and the model's own misfit included)
        c = np.concatenate([[0.0], np.cumsum(e)])
        k = np.arange(n, e.size - n + 1)
        jump = (c[k + n] - 2.0 * c[k] + c[k - n]) / n
        clear = (np.abs(t[k] - fitted["t"]) >= span) & (np.abs(t[k] - fitted["t_end"]) >= span)
        if clear.sum() < 3:
            return False
        if share * abs(size) < z * robust_sigma(jump[clear] - np.median(jump[clear])):
            return False
        for edge, sign in ((fitted["t"], 1.0), (fitted["t_end"], -1.0)):
            before = e[(t >= edge - span) & (t < edge)]
            after = e[(t >= edge) & (t < edge + span)]
            if before.size == 0 or after.size == 0:
                return False
            if sign * float(np.mean(after) - np.mean(before)) * np.sign(size) < share * abs(size):
                return False
        return True

    @staticmethod
    def text(fitted) -> str:
        """The pulse for a report."""
        return (f"a change that comes and goes from t = {fitted['t']:.1f} s to {fitted['t_end']:.1f} s: the current "
                f"moves by {fitted['size']:+.0f} A while the drive runs at its set speed and comes back, which no "
                "catalogued effect does (a load that builds up and slumps, a process upset that passes, a sensor "
                "fault)")


@dataclass(frozen=True)
class CurrentDrift:
    """A straight-line drift a + b (t - t_start) of the logged current over the whole record.

    No catalogued effect makes one: a kiln unbalance is a sinusoid of the kiln angle (over a record longer
    than one kiln revolution it rises and falls), a drag or a friction change follows the speed."""

    kind = "drift"
    n_params = 2  # a and b

    def fit(self, t, e) -> dict | None:
        """The least-squares line through the residual ``e`` [A] at times ``t`` [s], or None with fewer than
        three samples."""
        t = np.asarray(t, float)
        e = np.asarray(e, float)
        if t.size < 3:
            return None
        x = t - t[0]
        design = np.column_stack([np.ones_like(x), x])
        (a, b), *_ = np.linalg.lstsq(design, e, rcond=None)
        res = e - design @ np.array([a, b])
        return {"kind": self.kind, "t_start": float(t[0]), "t_end": float(t[-1]), "offset": float(a),
                "rate": float(b), "rss": float(res @ res)}

    def shape(self, t, fitted) -> np.ndarray:
        """The drift, in A, at times ``t`` [s]."""
        return fitted["offset"] + fitted["rate"] * (np.asarray(t, float) - fitted["t_start"])

    @staticmethod
    def text(fitted) -> str:
        """The drift for a report."""
        span = fitted["t_end"] - fitted["t_start"]
        return (f"a slow drift of the current: {fitted['rate'] * span:+.0f} A over the record's {span:.0f} s "
                f"({fitted['rate']:+.2f} A/s), along a straight line, which no catalogued effect makes (a "
                "current-sensor offset or gain drifting as the electronics warm up, a slowly changing load)")
