"""PID gains of the speed controller: :class:`PIDGains` lives in :mod:`kilnctl.gains` (below the design, the
linear models and the simulator); it is re-exported here for ``from kilnctl.design import PIDGains``."""

from ..gains import GAIN_UNITS, PIDGains

__all__ = ["PIDGains", "GAIN_UNITS"]
