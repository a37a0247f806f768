"""Unit conversions used across kilnctl, defined once.

>>> from kilnctl.units import RPM_PER_RAD_S
>>> round(500 / RPM_PER_RAD_S, 3)  # 500 rpm in rad/s
52.36
"""

from __future__ import annotations

import math

__all__ = ["RPM_PER_RAD_S", "PA_PER_MPA", "M_PER_MM"]

#: revolutions per minute in one rad/s: 60/(2 pi) (also the paper's speed feedback constant K, eq. 21)
RPM_PER_RAD_S = 60.0 / (2.0 * math.pi)
#: pascal in one megapascal
PA_PER_MPA = 1e6
#: metres in one millimetre
M_PER_MM = 1e-3
