"""Smoothed twins of the non-smooth components, for gradient-based optimization.

The hybrid plant switches modes at backlash contact and at burden
breakaway/re-stick; an optimizer needs equations that are smooth in the
states and parameters instead.  The components here are the same physics
with the switches regularised, each by one documented width:

``mesh_smooth`` (replaces ``mesh``)
    The backlash dead zone: contact force on the driving flank
    W = k_e*delta + C_e*d(Delta s)/dt for penetration delta = Delta s -
    Delta x > 0, clipped at zero (the damping never pulls the teeth
    together), and likewise on the back flank.  Every max(., 0) is replaced
    by a softplus over ``smooth_ds`` [m] of penetration (force width
    k_e*smooth_ds).  Default 1 um, against about 70 um of penetration at the
    running load: the smooth force differs from the exact one by at most
    k_e*smooth_ds*ln 2 = 10 kN (1.1 MPa of bending stress) at the instant of
    contact, and by less than 1e-9 of that beyond 20 um of penetration.
``burden_smooth`` (replaces ``burden``)
    The burden always has its own degree of freedom; the wall torque on it
    is T = mu(v)*N*R*tanh(v/smooth_v) with the relative speed
    v = omega_kiln - omega_burden and N = m_v*g*cos(psi).  Sticking becomes
    a creep of about ``smooth_v`` [rad/s] (default 1e-4 rad/s, 0.2 % of the
    kiln's running speed; over a 15 s start-up the burden lags the wall by
    under 2e-3 rad).  With ``friction_law = 'paper'``, mu = mu_c: in the
    hybrid plant the printed law's Filippov ``held`` mode lets the burden go
    where kinetic friction can no longer hold it, so mu_c sets the
    breakaway.  With ``'torque'``, mu(v) = mu_c + (mu_s - mu_c)*exp(-(v/v_s)^2)
    with the Stribeck speed v_s = 10*smooth_v: the static peak mu_s is held
    at creep speed and falls to mu_c once sliding.

The widths are *constant states* (their rate is zero) so that a
continuation can sharpen them without rebuilding the model: set them with
``simulate(..., initial={"smooth_ds": 1e-7})`` or through the optimizer's
initial state.  All other components (drive, coupling, kiln, stress) are
smooth already and are used unchanged.  The drive limits are left out of
the smooth model: the optimizer keeps the unlimited current and voltage
within I_max, V_max as constraints instead (:data:`CONSTRAINED`).

A component with modes names its twin in ``smooth_twin``;
:func:`smooth_names` turns any structure into its smooth twin.
"""

from __future__ import annotations

import casadi as ca

from ..errors import ModelError
from .base import REGISTRY, register
from .kiln import Burden
from .drivetrain import Mesh
from .ramps import softplus

__all__ = ["MeshSmooth", "BurdenSmooth", "SMOOTH_DS", "SMOOTH_V", "STRIBECK_RATIO", "CONSTRAINED", "smooth_names"]

#: default penetration width of the smoothed backlash [m]
SMOOTH_DS = 1e-6
#: default relative-speed width of the smoothed wall friction [rad/s]
SMOOTH_V = 1e-4
#: Stribeck speed over the friction width (``friction_law = 'torque'``) [-]
STRIBECK_RATIO = 10.0


#: components with modes that a smooth model leaves out: the optimizer keeps the unlimited voltage and current
#: within V_max and I_max as constraints instead
CONSTRAINED = ("voltage_limit", "current_limit", "current_limit_pi")


def smooth_names(names) -> tuple[str, ...]:
    """The smooth twin of a structure: each component with modes replaced by its ``smooth_twin``.

    The drive limits (:data:`CONSTRAINED`) are left out and the ``ramp``
    (whose modes a profile's smooth reference overrides) is kept; the order
    is kept, a twin taking its component's place.

    Parameters
    ----------
    names : sequence of str
        Component names of a hybrid structure.

    Returns
    -------
    tuple of str
        Component names without modes (besides the ramp's).

    Raises
    ------
    ModelError
        A component with modes that has no smooth twin (named).
    """
    out = []
    for nm in names:
        comp = REGISTRY[nm]
        if nm in CONSTRAINED:
            continue
        if comp.modes and nm != "ramp":
            if not comp.smooth_twin:
                raise ModelError(f"component {nm!r} has modes {comp.modes} and no smooth twin (its class sets no "
                                 "smooth_twin), so a smooth model cannot carry it")
            nm = comp.smooth_twin
        out.append(nm)
    return tuple(out)


def _smax0(x, width):
    """Smooth max(x, 0) over ``width`` (same unit as x)."""
    return width * softplus(x / width)


def _step(x, width):
    """Smooth unit step over ``width``: the derivative of :func:`_smax0`."""
    return 0.5 * (1 + ca.tanh(0.5 * x / width))


@register
class MeshSmooth(Mesh):
    """Pinion / girth-gear mesh with a smoothed backlash dead zone (see module docstring).

    Same states, parameters and outputs as ``mesh`` (eqs. 26-32), no modes;
    the constant state ``smooth_ds`` [m] is the smoothing width.
    """

    name = "mesh_smooth"
    summary = "gear mesh with backlash, dead zone smoothed over smooth_ds [m]"
    replaces = ("mesh",)
    modes = ()
    smooth_twin = None

    def declare(self, spec):
        super().declare(spec)
        spec.add_state("smooth_ds", "m", SMOOTH_DS, "backlash smoothing width (constant: its rate is zero)")

    def initial_state(self, params):
        x0 = super().initial_state(params)
        x0["smooth_ds"] = SMOOTH_DS
        return x0

    def initial_mode(self, params, x0):
        return None

    def loads(self, e, mode):
        p = e.p
        ds, eps = e.x["ds"], e.x["smooth_ds"]
        rate = p.R_p * e.x["omega_pinion"] - p.R_o * e.x["omega_kiln"]
        F = p.k_e * eps  # force width [N]
        fwd = ds - p.delta_x  # penetration of the driving flank [m]
        back = -ds  # penetration of the back flank [m]
        W_fwd = _smax0(p.k_e * _smax0(fwd, eps) + p.C_e * rate * _step(fwd, eps), F)
        W_back = _smax0(p.k_e * _smax0(back, eps) - p.C_e * rate * _step(back, eps), F)
        W = W_fwd - W_back
        e.add_torque("pinion", -W * p.R_p)
        e.add_torque("kiln", W * p.R_o)
        e.sig["ds_rate"] = rate
        e.sig["W_t"] = W

    def finish(self, e, mode):
        e.set_rate("ds", e.sig["ds_rate"])
        e.set_rate("smooth_ds", ca.SX(0))
        e.add_output("ds", e.x["ds"])


@register
class BurdenSmooth(Burden):
    """Burden with regularised wall friction, always two degrees of freedom (see module docstring).

    Same states, parameters and outputs as ``burden`` (eqs. 1-3, 6, 16), no
    modes; the constant state ``smooth_v`` [rad/s] is the friction width.
    """

    name = "burden_smooth"
    summary = "burden with wall friction mu*N*R*tanh(v_rel/smooth_v)"
    replaces = ("burden",)
    modes = ()
    smooth_twin = None

    def declare(self, spec):
        super().declare(spec)
        spec.add_state("smooth_v", "rad/s", SMOOTH_V, "wall-friction smoothing width (constant: its rate is zero)")

    def initial_state(self, params):
        return {"psi": params.psi_0, "smooth_v": SMOOTH_V}

    def initial_mode(self, params, x0):
        return None

    def loads(self, e, mode):
        p = e.p
        v_rel = e.x["omega_kiln"] - e.x["omega_burden"]
        eps = e.x["smooth_v"]
        mu = p.mu_c
        if p.friction_law == "torque":
            mu = p.mu_c + (p.mu_s - p.mu_c) * ca.exp(-(v_rel / (STRIBECK_RATIO * eps)) ** 2)
        T_w = mu * self._normal(e) * p.R * ca.tanh(v_rel / eps)
        e.add_inertia("burden", p.J_v)
        e.add_torque("burden", -p.m_v * p.g * p.L * ca.sin(e.x["psi"]) + T_w)
        e.add_torque("kiln", -T_w)
        e.sig["T_f"] = T_w

    def finish(self, e, mode):
        e.set_rate("psi", e.x["omega_burden"])
        e.set_rate("smooth_v", ca.SX(0))
        e.add_output("psi", e.x["psi"])
        e.add_output("v_rel", e.x["omega_kiln"] - e.x["omega_burden"])
        e.add_output("T_f", e.sig["T_f"])
