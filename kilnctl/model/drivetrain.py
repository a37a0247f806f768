"""Drive-train components: gearbox, coupling, pinion, gear mesh, stress.

Macro model: ``gearbox`` joins motor and kiln rigidly through n (a pure
torque reducer, eqs. 9-10).  Micro model (eqs. 26-34): motor ->
``coupling`` (elastomeric) -> gearbox n_r -> ``pinion`` -> ``mesh``
(stiffness, damping, backlash) -> girth gear and kiln.
"""

from __future__ import annotations

import casadi as ca

from .base import Component, Guard, register

#: scale of the mesh deflection in guards [m]
DS_SCALE = 1e-4


@register
class Gearbox(Component):
    """Rigid reduction motor -> kiln with total ratio n (macro model, eq. 9).

    The transmitted tangential force at the girth gear, W_t, is the torque the
    reducer delivers to the kiln, n*(motor torque - J_m*domega_m/dt - friction),
    divided by R_o.
    """

    name = "gearbox"
    summary = "rigid reducer motor -> kiln, ratio n (eq. 9)"
    param_names = ("n", "R_o")
    requires = ("dc_motor", "kiln")

    def loads(self, e, mode):
        e.link("motor", "kiln", e.p.n)

    def finish(self, e, mode):
        # torque the reducer delivers to the kiln: n times the torque the motor shaft gives up to it
        # (not the kiln's net link torque, which also holds the burden link while the burden sticks)
        e.sig["W_t"] = -e.p.n * e.link_torque("motor") / e.p.R_o


@register
class DrivetrainCompliance(Component):
    """Torsional spring-damper of the drive train, k_po and C_po (Table 1).

    Replaces the rigid ``gearbox``: the motor drives the kiln through a spring
    k_po [N*m/rad] and damper C_po [N*m*s/rad] at the kiln axis (the shafts,
    gearbox and coupling lumped; torsional mode near 1.45 Hz).  State
    ``phi_po`` = theta_m/n - theta_o [rad].
    """

    name = "drivetrain_compliance"
    summary = "torsional spring-damper k_po, C_po between gearbox and kiln"
    param_names = ("k_po", "C_po", "n", "R_o")
    requires = ("dc_motor", "kiln")
    replaces = ("gearbox",)

    def declare(self, spec):
        spec.add_state("phi_po", "rad", 1e-2, "twist of the drive train at the kiln axis")

    def loads(self, e, mode):
        p = e.p
        rate = e.x["omega_motor"] / p.n - e.x["omega_kiln"]
        T = p.k_po * e.x["phi_po"] + p.C_po * rate
        e.add_torque("motor", -T / p.n)
        e.add_torque("kiln", T)
        e.sig["phi_po_rate"] = rate
        e.sig["W_t"] = T / p.R_o

    def finish(self, e, mode):
        e.set_rate("phi_po", e.sig["phi_po_rate"])


@register
class Pinion(Component):
    """Pinion and gearbox output: node ``pinion`` with inertia J_p (eq. 33)."""

    name = "pinion"
    summary = "pinion and gearbox output inertia J_p"
    param_names = ("J_p",)

    def declare(self, spec):
        spec.add_node("pinion", "pinion and gearbox output", 0.3)

    def loads(self, e, mode):
        e.add_inertia("pinion", e.p.J_p)


@register
class Coupling(Component):
    """Elastomeric coupling between motor and gearbox input.

    Torque on the motor side: T_c = k_c*phi*(1 + (phi/phi_c_ref)^2) + c_c*dphi/dt
    (``coupling_law = 'progressive'``) or k_c*phi + c_c*dphi/dt (``'linear'``),
    with twist phi = theta_m - n_r*theta_p [rad].  The thesis [9] curve is not
    available: shape and values are assumptions (docs/assumptions.md).
    """

    name = "coupling"
    summary = "elastomeric coupling, progressive torque-twist curve"
    param_names = ("k_c", "phi_c_ref", "c_c", "n_r")
    requires = ("dc_motor", "pinion")

    def declare(self, spec):
        spec.add_state("phi_c", "rad", 0.05, "twist of the elastomeric coupling (motor side)")

    def loads(self, e, mode):
        p = e.p
        phi = e.x["phi_c"]
        rate = e.x["omega_motor"] - p.n_r * e.x["omega_pinion"]
        spring = p.k_c * phi
        if p.coupling_law == "progressive":
            spring = spring * (1 + (phi / p.phi_c_ref) ** 2)
        T = spring + p.c_c * rate
        e.add_torque("motor", -T)
        e.add_torque("pinion", p.n_r * T)
        e.sig["phi_c_rate"] = rate
        e.sig["T_c"] = T

    def finish(self, e, mode):
        e.set_rate("phi_c", e.sig["phi_c_rate"])
        e.add_output("T_c", e.sig["T_c"])


@register
class Mesh(Component):
    """Pinion / girth-gear mesh with stiffness, damping and backlash (eqs. 26-32).

    Deflection Delta s = R_p*theta_p - R_o*theta_o [m] (state ``ds``).  Teeth
    in series: k_e = k_o*k_pi/(k_o + k_pi) (eq. 26).  Driving flank in contact
    for Delta s >= Delta x, free in 0 < Delta s < Delta x, back flank for
    Delta s <= 0 (eq. 31).  In contact W = k_e*(Delta s - Delta x) + C_e*dDelta s/dt,
    and, as in Modelica's ElastoBacklash, the damping never pulls the teeth
    together: W is clipped at zero.  Modes: ``contact``, ``gap``, ``back``.
    """

    name = "mesh"
    summary = "gear mesh: stiffness k_e, damping C_e, backlash delta_x"
    param_names = ("k_o", "k_pi", "C_e", "delta_x", "gap_0", "R_p", "R_o")
    requires = ("pinion", "kiln")
    modes = ("contact", "gap", "back")

    def declare(self, spec):
        spec.add_state("ds", "m", 1e-3, "mesh deflection R_p*theta_p - R_o*theta_o")

    def initial_state(self, params):
        return {"ds": params.delta_x * (1.0 - params.gap_0)}

    def initial_mode(self, params, x0):
        return "contact" if params.delta_x == 0 or params.gap_0 == 0 else "gap"

    def loads(self, e, mode):
        p = e.p
        ds = e.x["ds"]
        rate = p.R_p * e.x["omega_pinion"] - p.R_o * e.x["omega_kiln"]
        if mode == "contact":
            W = ca.fmax(p.k_e * (ds - p.delta_x) + p.C_e * rate, 0)
        elif mode == "back":
            W = ca.fmin(p.k_e * ds + p.C_e * rate, 0)
        else:
            W = ca.SX(0)
        e.add_torque("pinion", -W * p.R_p)
        e.add_torque("kiln", W * p.R_o)
        e.sig["ds_rate"] = rate
        e.sig["W_t"] = W

    def finish(self, e, mode):
        p = e.p
        ds = e.x["ds"]
        e.set_rate("ds", e.sig["ds_rate"])
        if mode == "contact":
            e.add_guard(Guard("separation", self.name, (ds - p.delta_x) / DS_SCALE, "gap"))
        elif mode == "gap":
            e.add_guard(Guard("contact", self.name, (p.delta_x - ds) / DS_SCALE, "contact"))
            e.add_guard(Guard("back_contact", self.name, ds / DS_SCALE, "back"))
        else:
            e.add_guard(Guard("back_separation", self.name, -ds / DS_SCALE, "gap"))
        e.add_output("ds", ds)

    def sliding_mode(self, cycle):
        """Resting contact: teeth touching with (almost) no relative speed and no force.

        At a flank with zero relative velocity the gap and the contact mode can
        switch into one another without time passing; the Filippov solution is
        the teeth resting on that flank (contact, force k_e*deflection clipped at
        zero), which the guards then leave as soon as the drive pulls them apart.
        """
        if "gap" in cycle:
            if "contact" in cycle:
                return "contact"
            if "back" in cycle:
                return "back"
        return None


@register
class BendingStress(Component):
    """Girth-gear tooth bending stress, Lewis form (after Michalopoulos [11]).

    sigma = W_t * K_v / (b * m * Y), with b = ``face_width``, m = ``module``,
    Y = ``Y_lewis``; K_v = 1, or Barth's (6.1 + V)/6.1 with the pitch-line
    speed V = R_o*|omega_o| [m/s] when ``dynamic_factor = 'barth'``.  W_t is
    the mesh force (micro) or the reducer torque at the kiln over R_o (macro).
    """

    name = "bending_stress"
    summary = "Lewis bending stress of the girth-gear tooth from W_t"
    param_names = ("module", "face_width", "Y_lewis", "R_o")
    requires = ("kiln",)

    def finish(self, e, mode):
        p = e.p
        W = e.sig.get("W_t", ca.SX(0))
        Kv = 1.0
        if p.dynamic_factor == "barth":
            Kv = (6.1 + p.R_o * ca.fabs(e.x["omega_kiln"])) / 6.1
        e.add_output("W_t", W)
        e.add_output("sigma", W * Kv / (p.face_width * p.module * p.Y_lewis))
