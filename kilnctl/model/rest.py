"""The drive holding the kiln at rest before the start-up.

A drive that is switched on before the ramp holds the kiln where it stands: its speed loop, at a reference of
zero, integrates until the motor's torque balances the load the kiln has at rest, and the current reads that
torque.  A kiln unbalance is such a load (T_unb sin(phi_unb) at the kiln angle of t = 0); the burden, lying at
psi = 0, and the speed-dependent loads are not.  A simulation that starts from zero current at the ramp
instead lets the kiln roll back for a fraction of a second until the integrator catches it: a drive switched
on with the ramp does that, one switched on before it does not.

The held state is that of a rigid drive train (the macro model): motor at rest, current ``i_hold`` with
``k_i n i_hold`` balancing the kiln's load, the speed controller's integrator at ``R_a i_hold / k_I`` (the
armature voltage across R_a, the speed error zero), and a compliant drive train twisted by that torque
(:meth:`~kilnctl.model.base.Component.held_state`).  The micro model's coupling and mesh are not preloaded: its
play is taken up in the first moments of the run.
"""

from __future__ import annotations

from ..params import Parameters
from .base import REGISTRY

__all__ = ["rest_kiln_torque", "holding_current", "held_state"]


def rest_kiln_torque(params: Parameters, names) -> float:
    """Torque on the kiln at rest at t = 0 from the components ``names`` [N*m].

    Parameters
    ----------
    params : Parameters
    names : sequence of str
        The plant's components (:func:`kilnctl.simulate.plant_structure`).

    Returns
    -------
    float
        The sum of the components' :meth:`~kilnctl.model.base.Component.rest_kiln_torque`.
    """
    return float(sum(REGISTRY[n]().rest_kiln_torque(params) for n in names if n in REGISTRY))


def holding_current(params: Parameters, names) -> float:
    """Armature current with which the drive holds the kiln at rest [A].

    Parameters
    ----------
    params : Parameters
        Needs ``n`` (gear ratio) and ``k_i`` [N*m/A].
    names : sequence of str
        The plant's components.

    Returns
    -------
    float
        ``-rest_kiln_torque / (n k_i)``: zero for a plant whose kiln has no load at rest.
    """
    return -rest_kiln_torque(params, names) / (params.n * params.k_i)


def held_state(params: Parameters, names) -> dict[str, float]:
    """Initial states of a drive that holds the kiln at rest (see the module's note).

    Parameters
    ----------
    params : Parameters
        Gains resolved (``k_I``), motor (``R_a``, ``k_i``) and gear ratio ``n``.
    names : sequence of str
        The plant's components.

    Returns
    -------
    dict of str to float
        ``x_a`` [A] (the current, the speed error being zero), with an integrating speed controller its
        integrator ``z`` [rpm*s], and the drive train's twist where it has one; empty when nothing needs holding
        or the plant has no speed controller.
    """
    if "pid" not in names or "dc_motor" not in names:
        return {}
    carried = -rest_kiln_torque(params, names)  # what the drive train passes to the kiln
    if carried == 0.0:
        return {}
    i = carried / (params.n * params.k_i)  # (holding_current)
    out = {"x_a": i}
    if params.k_I > 0:
        out["z"] = params.R_a * i / params.k_I
    for n in names:
        if n in REGISTRY:
            out.update(REGISTRY[n]().held_state(params, carried))
    return out
