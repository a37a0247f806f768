"""Motor-side Coulomb friction: brushes and bearings on the motor shaft (an effect added by name).

A torque of constant size T_cm [N*m] opposes the motor's rotation
(``simulate(..., effects=("motor_coulomb_friction",))``, ``--effects
motor_coulomb_friction``):

============  ==============  =====================================================
mode          motor speed     friction torque on the motor shaft
============  ==============  =====================================================
``slip_pos``  omega_m > 0     -T_cm
``slip_neg``  omega_m < 0     +T_cm
``stick``     omega_m = 0     T_cm*(2u - 1), whatever in [-T_cm, T_cm] holds it
============  ==============  =====================================================

Sticking is Coulomb friction's Filippov solution, built like the current
limit's sliding modes: u in [0, 1] is the plant's equivalent control that
keeps omega_m at zero (:meth:`kilnctl.model.assembly.Eqs.equivalent_control`).
The shaft breaks away (event ``sliding_end``) when holding it would take more
than T_cm, i.e. when even -T_cm lets it accelerate forwards or even +T_cm
backwards, and re-sticks (``restick``) when its speed returns to zero.  At
rest at t = 0 the motor starts in ``stick`` and turns once k_i*i_a exceeds
T_cm plus what the drive train asks of the shaft at standstill.  Sticking is
modelled rather than regularised because the start-up delay it causes is
part of the signature.

Its ``building`` form (component ``motor_friction_building``) is a friction
without sticking that builds up over the first turn of the shaft, as Dahl's
model of pre-sliding has it for a shaft turning one way from rest:
-T_cm (1 - exp(-theta_fm/theta_cm)) on the turning shaft, theta_fm the
angle the motor has turned [rad].  Dahl's dT/dtheta = sigma (1 - T/T_cm)
gives exactly this with theta_cm = T_cm/sigma.

``motor_coulomb_friction_smooth`` is its twin for the ramp optimizer:
-T_cm*tanh(omega_m/MOTOR_FRICTION_OMEGA), a creep below 0.01 rad/s
(0.02 % of the 52 rad/s running speed).
"""

from __future__ import annotations

import math

import casadi as ca

from ..params import param
from .base import Component, Guard, register
from .catalogue import Effect, Form, FreeParameter, motor_torque_scale

#: motor speed over which the smooth twin regularises the friction's sign, and the scale of the stick guards
#: [rad/s]
MOTOR_FRICTION_OMEGA = 1e-2


def _falling_story(form_values: dict, own_values: dict) -> str | None:
    """The falling form's story where it differs from a constant friction, in words: a friction that falls by
    30 % or more, or a burden 1 % or more away from the constant friction's (red team 14's F10: a_cm 0.27 with
    the burden 1.7 % heavier, nearer the plant's; the constant friction's burden was 4.8 % light)."""
    a = form_values.get("a_cm", 0.0)
    m_f, m_o = form_values.get("m_v"), own_values.get("m_v")
    moved = m_f is not None and m_o is not None and abs(m_f / m_o - 1.0) >= 0.01
    if a < 0.3 and not moved:
        return None
    s = (f"a friction of {form_values['T_cm']:.3g} N*m at rest falling by {100 * a:.0f} % at the set speed, "
         f"against a constant {own_values['T_cm']:.3g} N*m")
    if "m_v" in form_values and "m_v" in own_values:
        s += f", with a burden of {form_values['m_v'] / 1e3:.1f} t against {own_values['m_v'] / 1e3:.1f} t"
    return s


def _falling_also(form_values: dict) -> str | None:
    """What else draws the current of a friction that has fallen by 80 % or more at the set speed, on one ramp:
    an excess that fades with the time (red team 21's X1: a motor field at 55 % at the ramp start, restored with
    1.6 s, was selected as a friction of 141 N*m at rest falling by 100 %)."""
    if form_values.get("a_cm", 0.0) < 0.8:
        return None
    return (f"the friction, {100 * form_values['a_cm']:.0f} % gone at the set speed, is a current above the "
            "model at the start that fades as the drive speeds up. Along one ramp the speed grows with the time, "
            "so an excess that fades with the time draws the same current: a motor field weakened at standstill "
            "and restored as the ramp starts, a cold bearing or seal warming, a brake released late")


def _building_story(form_values: dict, own_values: dict) -> str | None:
    """The building form's story where it differs from a constant friction, in words: one that takes more than
    a tenth of a turn of the motor shaft to build up."""
    th = form_values.get("theta_cm", 0.0)
    if th < 0.1 * 2.0 * math.pi:
        return None
    return (f"a friction of {form_values['T_cm']:.3g} N*m without sticking, built up over {th:.2g} rad of the "
            f"motor's rotation, against a constant {own_values['T_cm']:.3g} N*m that holds the shaft at rest")


@register
class MotorCoulombFriction(Component):
    """Coulomb friction of brushes and bearings on the motor shaft, with sticking (see the module docstring).

    Torque -T_cm*sign(omega_m) on the node ``motor`` while it turns; at rest
    whatever in [-T_cm, T_cm] holds it (Filippov).  Output ``T_fm`` [N*m]:
    the friction torque on the shaft.
    """

    name = "motor_coulomb_friction"
    summary = "Coulomb friction T_cm of brushes and bearings against the motor speed, with sticking"
    param_names = ("T_cm",)
    requires = ("dc_motor",)
    modes = ("stick", "slip_pos", "slip_neg")
    smooth_twin = "motor_coulomb_friction_smooth"
    phase_after = "second_motor"
    parameters = (
        param("T_cm", 40.0, "N*m", "assumed: about 1 % of the 3.9 kN*m running motor torque (k_i x 840 A), usual "
              "for the brush and bearing friction of a large DC machine",
              "Coulomb friction torque on the motor shaft (component 'motor_coulomb_friction')", "effects",
              "nonnegative"),
    )
    catalogue = (
        Effect(
            "motor_coulomb_friction",
            "Brush and bearing friction on the motor shaft: a torque of constant size T_cm against the motor's "
            "rotation, which holds the shaft at rest until the drive torque exceeds it.",
            ("motor_coulomb_friction",), {}, None,
            (FreeParameter("T_cm", 0.0, 2000.0, "lin", 40.0),),
            "current above the model by T_cm/k_i (9 A with 40 N*m) as soon as the motor turns, the same along "
            "the ramp and at steady speed (a viscous drag instead grows with the speed), and a motor that "
            "starts a little late, once the current has reached T_cm/k_i",
            starts=lambda params, m: [{"T_cm": 20.0}, {"T_cm": 60.0}, {"T_cm": 200.0}],
            plausible={"T_cm": (10.0, 100.0)}, null={"T_cm": 0.0}, scale=motor_torque_scale, steady_load=True,
            offset_in_motion=lambda values, params: values["T_cm"] / params.k_i,
            notes="a friction that falls with the speed (support rollers or bearings lifting onto their oil film) "
                  "is its 'falling' form, tried in each round where it is supported: on one set speed a constant "
                  "friction and a lighter burden, or a falling friction and a heavier one, draw the same steady "
                  "current, and only the ramp tells them apart; a friction without sticking that builds up "
                  "over the shaft's first turn (Dahl's pre-sliding) is its 'building' form.",
            forms=(Form("falling",
                        "a friction of T_cm at rest that falls in proportion to the motor speed, by a_cm T_cm at "
                        "the set speed (support rollers or bearings lifting onto their oil film): "
                        "T_cm (1 - a_cm omega_m/omega_set)",
                        ("motor_coulomb_friction", "motor_friction_falloff"),
                        (FreeParameter("a_cm", 0.0, 1.0, "lin", 0.5),),
                        near={"a_cm": 0.0},
                        # the constant friction fitted to a falling one is held at the set speed by a lighter
                        # burden: each start keeps the friction at the set speed, T_cm (1 - a_cm), where the
                        # constant one ended (the steady current unchanged), and the refit moves along that
                        # valley (a_cm and the burden's mass together) as far as the ramp asks
                        starts=lambda v: [{"a_cm": a, "T_cm": v["T_cm"] / (1.0 - a)} for a in (0.5, 0.8, 0.95)],
                        # a friction gone at the set speed is the form's physical limit, not a stand-in's
                        ends={"a_cm": "upper"},
                        # the near start alone ends where the constant friction did (a_cm 0): the valley of a
                        # falling friction is reached from the starts above (red team 12's R17: a_cm 1.0 and
                        # the plant's burden, 309.7 t for 309)
                        local_fits=3, alike=_falling_story, also=_falling_also),
                   Form("building",
                        "a friction without sticking that builds up over the shaft's first turn (brushes, seals, "
                        "pre-sliding in the bearings; Dahl's model): T_cm (1 - exp(-theta_fm/theta_cm)) after "
                        "the motor has turned theta_fm",
                        ("motor_friction_building",),
                        (FreeParameter("theta_cm", 1e-3, 30.0, "log", 0.5),),
                        near={"theta_cm": 1e-3},
                        starts=lambda v: [{"theta_cm": th} for th in (0.2, 1.0, 5.0)],
                        # built up at once is the Coulomb friction without its sticking: the form's own end
                        ends={"theta_cm": "lower"},
                        local_fits=2, alike=_building_story))),
    )

    def initial_mode(self, params, x0):
        w = x0.get("omega_motor", 0.0)
        return "stick" if w == 0 else ("slip_pos" if w > 0 else "slip_neg")

    def loads(self, e, mode):
        T_cm = e.p.T_cm
        if mode == "stick":
            u = e.sig["u_motor_stick"] = e.equivalent_control(self.name)
            T = T_cm * (2 * u - 1)
        else:
            T = -T_cm if mode == "slip_pos" else T_cm
        e.add_torque("motor", T)
        e.sig["T_fm"] = T

    def finish(self, e, mode):
        w = e.x["omega_motor"] / MOTOR_FRICTION_OMEGA
        if mode == "stick":
            # u = 0 (-T_cm) and still accelerating forwards: break away forwards; u = 1 and still backwards
            e.hold_constant(e.sig["u_motor_stick"], w, below="slip_pos", above="slip_neg", component=self.name)
        elif mode == "slip_pos":
            e.add_guard(Guard("restick", self.name, w, "stick"))
        else:
            e.add_guard(Guard("restick", self.name, -w, "stick"))
        e.add_output("T_fm", e.sig["T_fm"])


@register
class MotorCoulombFrictionSmooth(MotorCoulombFriction):
    """Motor Coulomb friction with the sign regularised: -T_cm*tanh(omega_m/0.01 rad/s), no modes."""

    name = "motor_coulomb_friction_smooth"
    summary = "motor Coulomb friction -T_cm*tanh(omega_m/omega_eps), for the optimizer"
    replaces = ("motor_coulomb_friction",)
    modes = ()
    smooth_twin = None

    def initial_mode(self, params, x0):
        return None

    def loads(self, e, mode):
        T = -e.p.T_cm * ca.tanh(e.x["omega_motor"] / MOTOR_FRICTION_OMEGA)
        e.add_torque("motor", T)
        e.sig["T_fm"] = T

    def finish(self, e, mode):
        e.add_output("T_fm", e.sig["T_fm"])


@register
class MotorFrictionFalloff(Component):
    """The motor Coulomb friction falling with speed: torque +a_cm*T_cm*omega_m/omega_set on the motor.

    With :class:`MotorCoulombFriction` (the ``falling`` form of its catalogue effect) the friction on the
    turning shaft is T_cm*(1 - a_cm*omega_m/omega_set), omega_set the set speed (``omega_ref``, through
    K_fb): T_cm at rest, T_cm*(1 - a_cm) at the set speed.  Odd in omega_m and zero at rest, so the
    friction's sticking is the Coulomb component's alone.  Not a catalogue effect of its own.
    """

    name = "motor_friction_falloff"
    summary = "motor Coulomb friction falling with speed: +a_cm*T_cm*omega_m/omega_set"
    param_names = ("a_cm",)
    requires = ("dc_motor",)
    parameters = (
        param("a_cm", 0.0, "-", "assumed: none unless fitted (a friction that lifts off with speed)",
              "fraction of the motor Coulomb friction T_cm lost at the set speed (component "
              "'motor_friction_falloff')", "effects", "nonnegative"),
    )

    def loads(self, e, mode):
        e.add_torque("motor", e.p.a_cm * e.p.T_cm * e.x["omega_motor"] * e.p.K_fb / e.p.omega_ref)


@register
class MotorFrictionBuilding(Component):
    """Motor friction without sticking that builds up with the shaft's rotation: the ``building`` form of
    ``motor_coulomb_friction`` (see the module docstring).

    Torque -T_cm*(1 - exp(-theta_fm/theta_cm))*tanh(omega_m/0.01 rad/s) on the node ``motor``; the state
    ``theta_fm`` [rad] is the angle the shaft has turned, d theta_fm/dt = omega_m*tanh(omega_m/0.01 rad/s)
    (|omega_m| made smooth).  For a shaft turning one way from rest this is Dahl's friction with pre-sliding
    stiffness sigma = T_cm/theta_cm [N*m/rad].  No modes: zero at rest, so the shaft turns as soon as it is
    driven.  Output ``T_fm`` [N*m].
    """

    name = "motor_friction_building"
    summary = "motor friction built up over the shaft's rotation: -T_cm*(1 - exp(-theta_fm/theta_cm))"
    param_names = ("T_cm", "theta_cm")
    requires = ("dc_motor",)
    phase_after = "second_motor"
    parameters = (
        param("theta_cm", 0.5, "rad", "assumed: half a radian of the motor shaft (a Dahl friction's T_cm/sigma)",
              "motor rotation over which the motor friction builds up, T_cm/sigma in Dahl's model (component "
              "'motor_friction_building')", "effects", "positive"),
    )

    def declare(self, spec):
        spec.add_state("theta_fm", "rad", 1.0, "angle the motor shaft has turned (motor friction's build-up)")

    def loads(self, e, mode):
        w = e.x["omega_motor"]
        turning = ca.tanh(w / MOTOR_FRICTION_OMEGA)
        T = -e.p.T_cm * (1.0 - ca.exp(-e.x["theta_fm"] / e.p.theta_cm)) * turning
        e.add_torque("motor", T)
        e.sig["T_fm"] = T
        e.sig["theta_fm_dot"] = w * turning

    def finish(self, e, mode):
        e.set_rate("theta_fm", e.sig["theta_fm_dot"])
        e.add_output("T_fm", e.sig["T_fm"])
