"""Kiln and burden components (macro model, eqs. 1-19).

Sign convention: the kiln turns in the positive sense.  The burden angle
``psi`` is measured from bottom dead centre in the sense of rotation (the
paper's Phi is pi - psi, so sin(pi - Phi) = sin psi).  Gravity pulls the
burden back with torque m_v*g*L*sin(psi); the wall drags it forward.
"""

from __future__ import annotations

import casadi as ca

from ..params import param
from ..units import RPM_PER_RAD_S
from .base import Component, Guard, register
from .catalogue import Effect

#: speed that regularises the bearing friction at standstill [rad/s] (numerical, not physical)
BEARING_OMEGA_EPS = 1e-4
#: scale of the relative burden speed in the re-stick guard [rad/s]
V_REL_SCALE = 1e-2


def bearing_torque(omega_kiln, p, tanh=ca.tanh):
    """Support-roller bearing friction torque on the kiln, eq. 17, in the sense of rotation [N*m].

    T_brg*tanh(omega_o/BEARING_OMEGA_EPS), T_brg = 2*mu_brg*(P/2)*cos(30 deg)*(l + k)/2
    (:attr:`kilnctl.params.Parameters.T_brg`); the tanh regularises the sign at standstill.

    Parameters
    ----------
    omega_kiln : casadi.SX or array
        Kiln speed [rad/s].
    p : Parameters or SymParams
        ``T_brg`` is read from it.
    tanh : callable, default casadi.tanh
        ``numpy.tanh`` for numeric arrays.

    Returns
    -------
    casadi.SX or array
        Friction torque [N*m] (positive while the kiln turns forward); the kiln receives its negative.
    """
    return p.T_brg * tanh(omega_kiln / BEARING_OMEGA_EPS)


@register
class Kiln(Component):
    """Kiln shell on its support rollers: node ``kiln`` with inertia J_o.

    With ``J_e_mode = 'table'`` the shell inertia is J_e - J_v so that kiln
    and burden add up to the printed J_e.
    """

    name = "kiln"
    summary = "kiln shell inertia (J_o, or J_e - J_v)"
    param_names = ("J_o", "J_e")
    parameters = (
        param("J_o", 6.978e6, "kg*m^2", "Table 1", "inertia of kiln", "kiln"),
        param("J_e", 8.476e6, "kg*m^2", "Table 1 (2 % below J_o + J_v = 8.656e6)",
              "equivalent inertia J_e = J_o + J_v as printed; used only when J_e_mode = 'table'", "kiln"),
        param("J_e_mode", "sum", "-", "NOTES: Table 1 J_e disagrees with J_o + J_v by 2 %",
              "'sum': J_e = J_o + J_v; 'table': J_e as printed, the kiln shell then has J_e - J_v",
              "kiln", choices=("sum", "table")),
    )

    def declare(self, spec):
        spec.add_node("kiln", "kiln shell and girth gear", 0.05)

    def loads(self, e, mode):
        e.add_inertia("kiln", e.p.J_kiln)

    def finish(self, e, mode):
        e.add_output("kiln_rpm", e.x["omega_kiln"] * RPM_PER_RAD_S)


@register
class KilnFixed(Component):
    """Kiln held fixed (the paper's Fig. 9 check: the burden swings as a pendulum)."""

    name = "kiln_fixed"
    summary = "kiln clamped to ground"
    requires = ("kiln",)

    def loads(self, e, mode):
        e.link("kiln", "ground", 1.0)


@register
class BearingFriction(Component):
    """Support-roller bearing friction, eq. 17.

    T = 2*mu_brg*(P/2)*cos(30 deg)*(l + k)/2 opposes the kiln's rotation.  At
    standstill the sign is regularised with tanh(omega/1e-4 rad/s) (the torque
    is under 0.3 % of the burden torque).
    """

    name = "bearing_friction"
    summary = "support-roller bearing friction torque (eq. 17)"
    param_names = ("mu_brg", "P", "l_brg", "k_brg")
    parameters = (
        param("mu_brg", 0.001, "-", "Le Roux [10], eq. 17", "friction coefficient of support roller bearings",
              "kiln", "nonnegative"),
        param("P", 16.512e6, "N", "Table 1", "total weight of kiln", "kiln", "nonnegative"),
        param("l_brg", 0.7155, "m", "Table 1 ('l')", "torque arm of bearing l (eq. 17)", "kiln", "nonnegative"),
        param("k_brg", 0.5475, "m", "Table 1 ('k'; not the feedback constant K)", "torque arm of bearing k (eq. 17)",
              "kiln", "nonnegative"),
    )
    requires = ("kiln",)

    def loads(self, e, mode):
        e.add_torque("kiln", -bearing_torque(e.x["omega_kiln"], e.p))


@register
class Burden(Component):
    """Burden as a rigid disk with stick-slip friction against the wall.

    Modes
    -----
    stick
        One degree of freedom with the kiln (eq. 7, 11).  Breakaway when
        ``friction_law = 'paper'``: F_t > F_bf, i.e. sin(psi) > mu_s*cos(psi)
        (forces, eq. 1-3); ``'torque'``: the wall torque needed to hold the
        burden exceeds mu_s*N*R.
    slip_pos, slip_neg
        Two degrees of freedom (eq. 15, 16); kinetic wall torque mu_c*N*R,
        N = m_v*g*cos(psi), opposing the relative velocity
        v_rel = omega_kiln - omega_burden (slip_pos: v_rel > 0, the wall
        outruns the burden).  Re-sticks when v_rel reaches zero.
    held
        Filippov sliding mode: entered when sticking and slipping would switch
        into one another without time passing (the printed law between
        tan(psi) = mu_s and tan(psi) = mu_c*R/L).  The burden moves with the
        wall, held by kinetic friction; it slips when the holding torque
        exceeds mu_c*N*R.
    """

    name = "burden"
    summary = "burden with stick-slip wall friction (eqs. 1-3, 6, 16)"
    param_names = ("m_v", "J_v", "L", "R", "mu_c", "mu_s", "g", "psi_0")
    parameters = (
        param("J_v", 1.678e6, "kg*m^2", "Table 1", "inertia of burden", "kiln"),
        param("m_v", 580e3, "kg", "Table 1", "mass of burden", "kiln"),
        param("L", 1.353, "m", "Table 1", "torque arm of burden (centre of mass from kiln axis)", "kiln"),
        param("R", 2.17, "m", "Table 1", "radius of kiln (arm of the wall friction force)", "kiln"),
        param("mu_c", 0.4, "-", "paper, Fig. 4: mu3 fits best", "Coulomb (kinetic) friction coefficient of burden",
              "kiln", "nonnegative"),
        param("mu_s", 0.51, "-", "paper, Fig. 4: mu3 fits best", "static friction coefficient of burden", "kiln",
              "nonnegative"),
        param("friction_law", "paper", "-", "NOTES: the printed law is not torque-consistent",
              "'paper': breakaway when F_t > F_bf (forces, eq. 3); 'torque': breakaway when the holding torque "
              "exceeds mu_s*N*R. Both use kinetic torque mu_c*N*R opposing the relative velocity and re-stick",
              "kiln", choices=("paper", "torque")),
        param("psi_0", 0.0, "rad", "assumed: the paper does not give the initial burden angle; burden at rest at "
              "the bottom", "initial burden angle from bottom dead centre", "kiln", "finite"),
        param("g", 9.81, "m/s^2", "nomenclature", "gravitational constant", "kiln"),
    )
    catalogue = (
        Effect(
            "torque_friction_law",
            "The burden breaks away when the friction torque needed to hold it exceeds mu_s N R (torque-"
            "consistent), instead of the paper's force comparison (eq. 3): large stick-slip cycles.",
            (), {"friction_law": "torque"}, None, (),
            "a saw-tooth in the current at steady speed: rising while the burden sticks, dropping at each "
            "breakaway, with a period of seconds; the paper's law gives small sliding oscillations",
            notes="an option of the burden model, not a component: no new parameter; mu_c and mu_s are refitted "
                  "(their meaning changes with the law) on the whole record, each local fit beginning with a "
                  "phase-free stage (the cycles' mean level and autocovariance after the ramp): the cost of a long "
                  "run of stick-slip cycles is rugged, a valley for every whole number of cycles. A breakaway "
                  "misplaced in time costs in proportion to the shift (a cusp at the right friction): after the "
                  "stage a timing stage compares the current's falls by the model's switch times "
                  "(measure/breakaways.py), then each fit runs on a residual smoothed over 0.4 s, then 0.1 s, "
                  "then none.",
            horizons="after_first_failure", separation=0.04, smoothing=(0.4, 0.1)),
    )
    requires = ("kiln",)
    modes = ("stick", "slip_pos", "slip_neg", "held")
    smooth_twin = "burden_smooth"

    def declare(self, spec):
        spec.add_node("burden", "burden (rigid disk)", 0.05)
        spec.add_state("psi", "rad", 1.0, "burden angle from bottom dead centre")

    def initial_state(self, params):
        return {"psi": params.psi_0}

    def _normal(self, e):
        p = e.p
        return p.m_v * p.g * ca.fmax(ca.cos(e.x["psi"]), 0)

    def loads(self, e, mode):
        p = e.p
        e.add_inertia("burden", p.J_v)
        e.add_torque("burden", -p.m_v * p.g * p.L * ca.sin(e.x["psi"]))
        if mode in ("stick", "held"):
            e.link("burden", "kiln", 1.0)
        else:
            sgn = 1.0 if mode == "slip_pos" else -1.0
            T_k = sgn * p.mu_c * self._normal(e) * p.R
            e.add_torque("burden", T_k)
            e.add_torque("kiln", -T_k)
            e.sig["T_f"] = T_k

    def finish(self, e, mode):
        p = e.p
        e.set_rate("psi", e.x["omega_burden"])
        v_rel = e.x["omega_kiln"] - e.x["omega_burden"]
        scale = p.m_v * p.g * p.R
        if mode in ("stick", "held"):
            T_need = e.link_torque("burden")
            e.sig["T_f"] = T_need
            if mode == "held":
                cap = p.mu_c * self._normal(e) * p.R
                e.add_guard(Guard("breakaway", self.name, (cap - T_need) / scale, "slip_pos"))
                e.add_guard(Guard("breakaway", self.name, (cap + T_need) / scale, "slip_neg"))
            elif p.friction_law == "torque":
                cap = p.mu_s * self._normal(e) * p.R
                e.add_guard(Guard("breakaway", self.name, (cap - T_need) / scale, "slip_pos"))
                e.add_guard(Guard("breakaway", self.name, (cap + T_need) / scale, "slip_neg"))
            else:  # 'paper': F_t against F_bf, eq. 1-3
                c, s = ca.cos(e.x["psi"]), ca.sin(e.x["psi"])
                e.add_guard(Guard("breakaway", self.name, p.mu_s * c - s, "slip_pos"))
                e.add_guard(Guard("breakaway", self.name, p.mu_s * c + s, "slip_neg"))
        elif mode == "slip_pos":
            e.add_guard(Guard("restick", self.name, v_rel / V_REL_SCALE, "stick"))
        else:
            e.add_guard(Guard("restick", self.name, -v_rel / V_REL_SCALE, "stick"))
        e.add_output("psi", e.x["psi"])
        e.add_output("v_rel", v_rel)
        e.add_output("T_f", e.sig["T_f"])

    def sliding_mode(self, cycle):
        if ("stick" in cycle or "held" in cycle) and ("slip_pos" in cycle or "slip_neg" in cycle):
            return "held"
        return None
