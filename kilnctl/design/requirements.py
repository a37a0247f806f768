"""Closed-loop requirements of the speed-loop design, and their defaults.

The defaults follow the paper's aim, "minimum rise time with minimum overshoot
in order not to induce vibrations in the modelled drive system", and are
justified in ``docs/tutorial_design.md``:

* ``zeta_min = 0.7``: every closed-loop pole at least this damped.  The motor's
  own electromechanical pair has zeta of about 0.23; a PI controller leaves it
  there (the paper found PI "not satisfactory"), the derivative term damps it.
* ``overshoot_max = 2 %``: overshoot within the 2 % settling band, that is,
  none visible.
* ``settling_time_max = 2 s``: well inside the 6.8 s start-up ramp
  (74 rpm/s to 500 rpm), so the loop follows the ramp closely.
* ``wn_max``: the dominant closed-loop poles no faster than half the
  drive-train torsional mode (``sqrt(k_po/J_e)``, 9.0 rad/s = 1.43 Hz with
  Table 1), so the rigid-body design stays valid and the loop does not drive
  the mode.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, replace

from ..errors import DesignError
from ..params import Parameters

__all__ = ["Requirements", "torsional_mode_frequency", "WN_FRACTION_OF_TORSIONAL_MODE"]

#: default ceiling on the dominant natural frequency, as a fraction of the torsional mode
WN_FRACTION_OF_TORSIONAL_MODE = 0.5


def torsional_mode_frequency(params: Parameters) -> float:
    """Return the drive-train torsional mode of Table 1's equivalent spring.

    The kiln and burden (``J_e``) on the equivalent torsional spring ``k_po``,
    with the drive side held: ``sqrt(k_po / J_e)``.  With the motor free the
    mode is about 15 % higher (motor side ``n^2 J_m`` is 2.9 times ``J_e``), so
    this is the conservative (lower) value.

    Parameters
    ----------
    params : Parameters
        Parameter set (``k_po`` [N*m/rad], ``J_e`` per ``J_e_mode`` [kg*m^2]).

    Returns
    -------
    float
        Angular frequency [rad/s] (9.00 rad/s, 1.43 Hz, with Table 1).
    """
    return math.sqrt(params.k_po / params.J_e_eff)


def _number(name: str, value, unit: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise DesignError(f"requirement {name} = {value!r} must be a number in {unit}")
    value = float(value)
    if not math.isfinite(value):
        raise DesignError(f"requirement {name} = {value!r} must be a finite number in {unit}")
    return value


@dataclass(frozen=True)
class Requirements:
    """What the closed speed loop must achieve, in both load conditions.

    Attributes
    ----------
    zeta_min : float, default 0.7
        Minimum damping ratio of every closed-loop pole [-], in [0, 1].
    settling_time_max : float, default 2.0
        Maximum 2 % settling time of the speed after a reference step [s], > 0.
    overshoot_max : float, default 2.0
        Maximum overshoot of the speed after a reference step [%], >= 0.
    wn_max : float or None, default None
        Maximum natural frequency of the dominant closed-loop pole(s) [rad/s],
        > 0.  ``None``: ``WN_FRACTION_OF_TORSIONAL_MODE`` (0.5) times
        :func:`torsional_mode_frequency` of the parameter set, filled in by
        :meth:`resolve`.

    Raises
    ------
    DesignError
        For a value outside its range; the message names the requirement and
        the fix.
    """

    zeta_min: float = 0.7
    settling_time_max: float = 2.0
    overshoot_max: float = 2.0
    wn_max: float | None = None

    def __post_init__(self):
        z = _number("zeta_min", self.zeta_min, "-")
        if z < 0:
            raise DesignError(f"requirement zeta_min = {z!r} is negative: a damping ratio floor lies in [0, 1]")
        if z > 1:
            raise DesignError(
                f"requirement zeta_min = {z!r} exceeds 1: no pole pair is damped more than critically; "
                "use zeta_min = 1 to ask for real poles only")
        ts = _number("settling_time_max", self.settling_time_max, "s")
        if ts <= 0:
            raise DesignError(f"requirement settling_time_max = {ts!r} s must be > 0")
        os_ = _number("overshoot_max", self.overshoot_max, "%")
        if os_ < 0:
            raise DesignError(f"requirement overshoot_max = {os_!r} % must be >= 0 (0 asks for no overshoot)")
        object.__setattr__(self, "zeta_min", z)
        object.__setattr__(self, "settling_time_max", ts)
        object.__setattr__(self, "overshoot_max", os_)
        if self.wn_max is not None:
            wn = _number("wn_max", self.wn_max, "rad/s")
            if wn <= 0:
                raise DesignError(
                    f"requirement wn_max = {wn!r} rad/s must be > 0, or None for half the drive-train "
                    "torsional mode")
            object.__setattr__(self, "wn_max", wn)

    @property
    def sigma_min(self) -> float:
        """Smallest decay rate 4/settling_time_max of the dominant poles [1/s] (2 % rule)."""
        return 4.0 / self.settling_time_max

    def resolve(self, params: Parameters) -> "Requirements":
        """Return a copy with ``wn_max`` filled in from the parameter set.

        Parameters
        ----------
        params : Parameters
            Parameter set (``k_po``, ``J_e``) for the default ``wn_max``.

        Returns
        -------
        Requirements
            ``wn_max`` is a number [rad/s].
        """
        if self.wn_max is not None:
            return self
        return replace(self, wn_max=WN_FRACTION_OF_TORSIONAL_MODE * torsional_mode_frequency(params))

    def as_dict(self) -> dict:
        """Return the requirements as a plain dictionary (units in the key names' docs)."""
        return asdict(self)
