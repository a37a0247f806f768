"""Effects a measurement may reveal, as components to add to a base model.

Each is a physical effect with its parameters; the effect catalogue of
:mod:`kilnctl.measure` adds them by name (``second_motor``,
``drivetrain_compliance`` and ``current_limit`` live with the drive and drive
train).
"""

from __future__ import annotations

import casadi as ca

from .base import Component, register


@register
class SpeedSensorLag(Component):
    """First-order lag of the speed measurement used by the controller.

    d(omega_meas)/dt = (omega_m - omega_meas)/tau_s; the PID sees omega_meas.
    """

    name = "speed_sensor_lag"
    summary = "controller sees the motor speed through a first-order lag tau_s"
    param_names = ("tau_s",)
    requires = ("pid",)

    def declare(self, spec):
        spec.add_state("omega_meas", "rad/s", 50.0, "measured motor speed seen by the controller")

    def signals(self, e, mode):
        rate = (e.x["omega_motor"] - e.x["omega_meas"]) / e.p.tau_s
        e.sig["omega_fb"] = e.x["omega_meas"]
        e.sig["omega_fb_dot"] = rate

    def finish(self, e, mode):
        e.set_rate("omega_meas", e.sig["omega_fb_dot"])


@register
class KilnUnbalance(Component):
    """Once-per-revolution torque on the kiln (eccentric mass or shell crank).

    Torque -T_unb*sin(theta_o + phi_unb) on the kiln; state ``theta_o`` is the
    kiln angle [rad] (it grows slowly: 0.048 rad/s at 500 rpm motor speed).
    """

    name = "kiln_unbalance"
    summary = "once-per-revolution kiln torque T_unb*sin(theta_o + phi_unb)"
    param_names = ("T_unb", "phi_unb")
    requires = ("kiln",)

    def declare(self, spec):
        spec.add_state("theta_o", "rad", 1.0, "kiln angle")

    def loads(self, e, mode):
        e.add_torque("kiln", -e.p.T_unb * ca.sin(e.x["theta_o"] + e.p.phi_unb))

    def finish(self, e, mode):
        e.set_rate("theta_o", e.x["omega_kiln"])


@register
class ViscousDrag(Component):
    """Viscous drag on the kiln, torque -B_o*omega_o (seals, tyre slip, lubricant)."""

    name = "viscous_drag"
    summary = "viscous drag torque -B_o*omega_o on the kiln"
    param_names = ("B_o",)
    requires = ("kiln",)

    def loads(self, e, mode):
        e.add_torque("kiln", -e.p.B_o * e.x["omega_kiln"])
