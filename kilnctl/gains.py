"""PID gains of the speed controller (eq. 21): used by the design, the linear models and the simulator alike,
so it lives below all three (no upward import).

A parameter set may ask for designed gains (``gains = "design"``).  The
design lives above the simulator, so the simulator cannot import it; instead
the design is plugged in here from above: the package root
(``kilnctl/__init__.py``, which Python runs before any kilnctl module) passes
:func:`kilnctl.design.gains_for` to :func:`use_designer`, importing the design
only when a run first needs it.  :func:`resolve_gains` then turns such a set
into one with ``gains = "given"`` before anything is simulated.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .errors import DesignError
from .params import Parameters

__all__ = ["PIDGains", "GAIN_UNITS", "resolve_gains", "use_designer"]

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


#: the function that designs gains for ``gains = "design"`` (set by :func:`use_designer`)
_designer = None


def use_designer(designer) -> None:
    """Set the function that designs the gains of a parameter set with ``gains = "design"``.

    The package root sets :func:`kilnctl.design.gains_for`; call this only to
    design gains another way everywhere (simulation, verification, sweeps).

    Parameters
    ----------
    designer : callable
        ``designer(params) -> PIDGains`` [V/rpm, V/(rpm*s), V*s/rpm].

    Raises
    ------
    DesignError
        When ``designer`` is not callable.
    """
    global _designer
    if not callable(designer):
        raise DesignError(f"designer = {designer!r} must be a function params -> PIDGains")
    _designer = designer


def resolve_gains(params: Parameters) -> Parameters:
    """Return ``params`` with k_p, k_I, k_D filled in from the design if ``gains == 'design'``.

    Parameters
    ----------
    params : Parameters
        With ``gains = "given"`` it is returned unchanged; with ``gains =
        "design"`` the designer set by :func:`use_designer` (the root-locus
        design with default requirements) gives k_p [V/rpm], k_I
        [V/(rpm*s)] and k_D [V*s/rpm].

    Returns
    -------
    Parameters
        With ``gains = 'given'`` and the designed (or given) gains.

    Raises
    ------
    DesignError
        When the gains are to be designed and no designer is set.
    ParameterError
        ``params`` is not a :class:`~kilnctl.params.Parameters` (a dict of values, a file name).
    """
    Parameters.require(params, hint="Parameters(m_v=5e5), or Parameters.from_toml(path) for a file")
    if params.gains == "given":
        return params
    if _designer is None:
        raise DesignError("params.gains = 'design' but no gain designer is set: import kilnctl (whose root sets "
                          "kilnctl.design.gains_for) or set gains = 'given' with k_p, k_I, k_D")
    g = _designer(params)
    if not isinstance(g, PIDGains):
        raise DesignError(f"the gain designer returned {type(g).__name__}, not PIDGains")
    return params.replace(gains="given", k_p=g.k_p, k_I=g.k_I, k_D=g.k_D)
