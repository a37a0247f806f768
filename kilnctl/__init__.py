"""kilnctl: control design, hybrid simulation and tuning of rotary-kiln drives.

Built from D.J. van Dyk and L. Pretorius, "Analysis of dynamic effects in a
rotary kiln system used for iron production" (1994).
"""

from . import gains as _gains
from . import params as _params
from .errors import KilnctlError
from .params import Parameters


_REGISTRY = None


def _components():
    """The component registry, for the parameter declarations (``kilnctl.params.SPECS``).

    Importing :mod:`kilnctl.model` registers every component; the root wires
    it in because ``params`` sits below the model that imports it.  The
    registry is one dict for the life of the process (components are added to
    it), so it is imported once: this is called at every parameter look-up.
    """
    global _REGISTRY
    if _REGISTRY is None:
        from .model.base import REGISTRY

        _REGISTRY = REGISTRY
    return _REGISTRY


def _design_gains(params):
    """The default gain design, imported when a run first asks for designed gains.

    The package root is the one place above every layer, so it wires the
    design (top) into the gain resolution the simulator (below the design)
    uses: see :mod:`kilnctl.gains`.
    """
    from .design import gains_for

    return gains_for(params)


_params._registry_loader = _components
_gains.use_designer(_design_gains)

__all__ = ["KilnctlError", "Parameters"]
__version__ = "0.2.0"
