"""Changes outside the catalogue, added to the model's current in closed form.

A calibration can carry one of these terms as the hypothesis of a difference that no model component
describes (see :class:`~kilnctl.measure.calibrate.Calibration`, ``outside``).  At every trial run the term
is fitted to the current's residual on the fitted samples by linear least squares (variable projection), so
it adds no parameter to the search, and counts as :attr:`n_params` parameters in the BIC.

- :class:`CurrentStep`: b H(t - tau), an abrupt change (a load step, a process upset, a sensor fault);
- :class:`CurrentPulse`: b (H(t - t_on) - H(t - t_off)), a change that comes and goes (a load that builds up
  and slumps, a process upset that passes);
- :class:`CurrentDrift`: a + b (t - t_start), a straight-line drift of the logged current over the whole
  record (a current-sensor offset or gain drifting as the electronics warm up);
- :class:`CurrentLine`: a sin(2 pi f t) + b cos(2 pi f t) at the set speed, a periodic load or oscillation at
  a frequency no catalogued effect has (an eccentric pinion, a gear's run-out, a process cycle).

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


@dataclass(frozen=True)
class CurrentLine:
    """A sinusoid a sin(2 pi f t) + b cos(2 pi f t) of the current at ``hz``, from ``t_from`` on (zero before).

    At the set speed a load that repeats with a shaft's rotation (an eccentric pinion, a bent gearbox shaft, a
    girth gear's run-out) or a process cycle is a line in the current's spectrum; none of the catalogue's
    effects makes one away from the kiln's own turn and the burden's oscillation.  The frequency comes from the
    residual's spectrum (:func:`~kilnctl.measure.signature.spectral_line`), so it counts as a parameter.

    Parameters
    ----------
    hz : float
        Frequency [Hz].
    t_from : float
        Record time from which the line is fitted [s] (the set speed's start: during the ramp a frequency locked
        to a shaft sweeps).
    """

    hz: float
    t_from: float

    kind = "line"
    n_params = 3  # a, b and the frequency read from the spectrum

    def _columns(self, t) -> np.ndarray:
        t = np.asarray(t, float)
        w = 2.0 * np.pi * self.hz * t
        on = (t >= self.t_from).astype(float)
        return np.column_stack([np.sin(w) * on, np.cos(w) * on])

    def fit(self, t, e) -> dict | None:
        """The least-squares sinusoid at ``hz`` through the residual ``e`` [A] at times ``t`` [s] from ``t_from``
        on, or None with fewer than ten samples there."""
        e = np.asarray(e, float)
        design = self._columns(t)
        if int(np.count_nonzero(design[:, 1] != 0.0)) < 10:
            return None
        (a, b), *_ = np.linalg.lstsq(design, e, rcond=None)
        res = e - design @ np.array([a, b])
        return {"kind": self.kind, "hz": float(self.hz), "t": float(self.t_from), "sin": float(a), "cos": float(b),
                "amplitude": float(np.hypot(a, b)), "rss": float(res @ res)}

    def shape(self, t, fitted) -> np.ndarray:
        """The sinusoid, in A, at times ``t`` [s]."""
        return self._columns(t) @ np.array([fitted["sin"], fitted["cos"]])

    @staticmethod
    def text(fitted) -> str:
        """The line for a report."""
        return (f"a periodic change at {fitted['hz']:.3g} Hz (a period of {1.0 / fitted['hz']:.3g} s) from t = "
                f"{fitted['t']:.1f} s: the current swings by +-{fitted['amplitude']:.0f} A, which no catalogued "
                "effect makes at that frequency (a load that repeats with a shaft's rotation: an eccentric pinion, "
                "a bent gearbox shaft, a girth gear's run-out; or a process cycle)")

