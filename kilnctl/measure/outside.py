"""Changes outside the catalogue, added to the model's current in closed form.

A calibration can carry one of these terms as the hypothesis of a difference that no model component
describes (see :class:`~kilnctl.measure.calibrate.Calibration`, ``outside``).  At every trial run the term
is fitted to the current's residual on the fitted samples by linear least squares (variable projection), so
it adds no parameter to the search, and counts as :attr:`n_params` parameters in the BIC.

- :class:`CurrentStep`: b H(t - tau), an abrupt change (a load step, a process upset, a sensor fault);
- :class:`CurrentDrift`: a + b (t - t_start), a straight-line drift of the logged current over the whole
  record (a current-sensor offset or gain drifting as the electronics warm up).

Each ``fit`` returns a dict with ``kind``, ``rss`` [A^2] and the term's values, or None; ``shape`` gives the
term at given times; ``text`` says it for a report.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .stats import best_step


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
