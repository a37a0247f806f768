"""PID gains of the speed controller (eq. 21): used by the design, the linear models and the simulator alike,
so it lives below all three (no upward import)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .errors import DesignError

__all__ = ["PIDGains", "GAIN_UNITS"]

#: units of the three gains, keyed as in :meth:`PIDGains.as_dict`
GAIN_UNITS = {"kp": "V/rpm", "ki": "V/(rpm*s)", "kd": "V*s/rpm"}


@dataclass(frozen=True)
class PIDGains:
    """Gains of the paper's PID speed controller (eq. 21).

    The controller acts on the speed error ``e_f = e_v - K*omega_m`` [rpm] as
    ``C(s) = k_p + k_I/s + k_D*s``: ``e_a = k_p e_f + k_I * integral(e_f)`` is
    the armature voltage, and ``k_D de_f/dt`` is realised through the armature
    inductance as the current term ``(k_D/L_a) e_f`` (eq. 21, line 2).

    Attributes
    ----------
    k_p : float
        Proportional constant [V/rpm].
    k_I : float
        Integral constant [V/(rpm*s)].
    k_D : float
        Derivative constant [V*s/rpm].

    Raises
    ------
    DesignError
        When a gain is not a finite number >= 0 (the message names the gain).
    """

    k_p: float
    k_I: float
    k_D: float

    def __post_init__(self):
        for name, unit in (("k_p", "V/rpm"), ("k_I", "V/(rpm*s)"), ("k_D", "V*s/rpm")):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float, np.floating, np.integer)):
                raise DesignError(f"gain {name} = {value!r} must be a number in {unit}")
            value = float(value)
            if not math.isfinite(value) or value < 0:
                raise DesignError(
                    f"gain {name} = {value!r} must be a finite number >= 0 ({unit}); the paper's PID has "
                    "non-negative constants")
            object.__setattr__(self, name, value)

    def scaled(self, kappa: float) -> "PIDGains":
        """Return the gains multiplied by ``kappa`` (the PID zeros stay fixed).

        Parameters
        ----------
        kappa : float
            Root-locus gain [-], >= 0.

        Returns
        -------
        PIDGains
        """
        return PIDGains(kappa * self.k_p, kappa * self.k_I, kappa * self.k_D)

    def zeros(self) -> np.ndarray:
        """Return the zeros of the PID, the roots of ``k_D s^2 + k_p s + k_I``.

        Returns
        -------
        numpy.ndarray
            Complex zeros [rad/s]; fewer than two when ``k_D`` (or ``k_p``) is zero.
        """
        return np.roots(np.trim_zeros([self.k_D, self.k_p, self.k_I], "f")).astype(complex)

    def as_dict(self) -> dict[str, float]:
        """Return ``{"kp": k_p, "ki": k_I, "kd": k_D}`` (units in ``GAIN_UNITS``)."""
        return {"kp": self.k_p, "ki": self.k_I, "kd": self.k_D}

    def __str__(self) -> str:
        return f"k_p = {self.k_p:.4g} V/rpm, k_I = {self.k_I:.4g} V/(rpm*s), k_D = {self.k_D:.4g} V*s/rpm"
