"""kilnctl: control design, hybrid simulation and tuning of rotary-kiln drives.

Built from D.J. van Dyk and L. Pretorius, "Analysis of dynamic effects in a
rotary kiln system used for iron production" (1994).
"""

from .errors import KilnctlError
from .params import Parameters

__all__ = ["KilnctlError", "Parameters"]
__version__ = "0.2.0"
