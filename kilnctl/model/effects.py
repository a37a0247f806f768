"""Effects a measurement may reveal, as components to add to a base model.

Each is a physical effect with its parameters; the effect catalogue of
:mod:`kilnctl.measure` adds them by name (``second_motor``,
``drivetrain_compliance`` and ``current_limit`` live with the drive and drive
train).
"""

from __future__ import annotations

import math

import casadi as ca

from ..params import param
from .base import Component, register
from .catalogue import Effect, Form, FreeParameter, drag_scale, kiln_torque_scale


def _sensed(e, rate):
    """The speed sensor's reading (state ``omega_meas`` [rad/s]) as the controller's feedback and the logged
    speed, with its rate [rad/s^2] (the PID's derivative term): the same for every form of the sensor."""
    e.sig["omega_fb"] = e.x["omega_meas"]
    e.sig["omega_log"] = e.x["omega_meas"]
    e.sig["omega_fb_dot"] = rate


@register
class SpeedSensorLag(Component):
    """First-order lag of the speed sensor: the controller and the record see its reading.

    d(omega_meas)/dt = (omega_m - omega_meas)/tau_s; the PID sees omega_meas,
    and the model's ``speed_rpm`` output is omega_meas too (signal
    ``omega_log``): a drive logs the speed feedback its controller uses
    (the filtered tacho or encoder value), not the shaft's true speed.
    """

    name = "speed_sensor_lag"
    summary = "controller and record see the motor speed through a first-order lag tau_s"
    param_names = ("tau_s",)
    parameters = (
        param("tau_s", 0.05, "s", "assumed: first-order lag of a tacho-generator with filter",
              "speed sensor time constant (component 'speed_sensor_lag')", "effects"),
    )
    catalogue = (
        Effect(
            "speed_sensor_lag",
            "The controller and the record see the motor speed through a first-order lag (tacho filter, encoder "
            "averaging).",
            ("speed_sensor_lag",), {}, None,
            (FreeParameter("tau_s", 1e-4, 2.0, "log", 0.005),),
            "a less damped speed loop: current oscillation at the loop's crossover after the ramp starts and "
            "ends, larger overshoot of the speed; residual correlated with the speed error",
            starts=lambda params, m: [{"tau_s": 0.001}, {"tau_s": 0.003}, {"tau_s": 0.01}],
            plausible={"tau_s": (0.002, 0.006)}, null={"tau_s": 1e-4},
            notes="the record's speed_rpm is read as the sensor's reading, as a drive logs its speed feedback: "
                  "it lags the shaft like the controller's copy. "
                  "Large lags can destabilise the loop: such trial runs are cut short and count as a poor fit. "
                  "When it is supported, a second-order filter and a delay before the lag are tried in its place.",
            forms=(Form("second_order",
                        "a second-order speed filter (tau_s s)^2/(4 zeta_s^2) + tau_s s + 1: a tuned filter that "
                        "rings when zeta_s < 0.7, near a pure delay of tau_s at 0.87, a first-order lag of tau_s "
                        "above 3",
                        # below zeta_s 0.3 the filter's resonance peak exceeds 1.7 (4.8 dB): a resonator no
                        # drive's speed filter is designed as
                        ("speed_sensor_filter",), (FreeParameter("zeta_s", 0.3, 10.0, "log", 0.7),),
                        near={"zeta_s": 5.0},
                        # a lag fitted to a filter's record ends about 20 % short of its low-frequency delay
                        starts=lambda v: [{"tau_s": f * v["tau_s"], "zeta_s": z} for z in (0.5, 0.7, 1.0)
                                          for f in (0.8, 1.0, 1.25, 1.6)]),
                   Form("delay",
                        "a transport delay T_d (sampling, computation, a moving-average speed estimate) before "
                        "the first-order lag tau_s",
                        ("speed_sensor_delay",), (FreeParameter("T_d", 1e-3, 0.5, "log", 0.01),),
                        near={"T_d": 1e-3},
                        # the delay and the lag share the low-frequency delay the lag alone was fitted to
                        starts=lambda v: [{"T_d": c * v["tau_s"] * (1.0 - q), "tau_s": c * v["tau_s"] * q}
                                          for c in (1.0, 1.3, 1.6) for q in (0.05, 0.2, 0.5)])),
            ),
    )
    requires = ("pid",)

    def declare(self, spec):
        spec.add_state("omega_meas", "rad/s", 50.0, "measured motor speed seen by the controller")

    def signals(self, e, mode):
        rate = (e.x["omega_motor"] - e.x["omega_meas"]) / e.p.tau_s
        _sensed(e, rate)

    def finish(self, e, mode):
        e.set_rate("omega_meas", e.sig["omega_fb_dot"])


@register
class SpeedSensorFilter(Component):
    """Second-order filter of the speed sensor: the second-order form of ``speed_sensor_lag``.

    (tau_s^2 / (4 zeta_s^2)) d2y/dt2 + tau_s dy/dt + y = omega_m, with y =
    omega_meas: natural frequency omega_n = 2 zeta_s / tau_s [rad/s], and
    at low frequencies the same delay tau_s as the first-order lag of that
    time constant.  zeta_s = 0.5 rings (a peak of +15 % at 0.7 omega_n);
    0.87 is the maximally flat delay (Bessel); above 3 the faster pole lies
    more than 35 times further out and the filter is the first-order lag.
    The controller and the record see y, as with the lag.
    """

    name = "speed_sensor_filter"
    summary = "controller and record see the motor speed through a second-order filter (tau_s, zeta_s)"
    param_names = ("tau_s", "zeta_s")
    parameters = (
        param("zeta_s", 0.7, "-", "assumed: a Butterworth speed filter",
              "damping ratio of the second-order speed filter (component 'speed_sensor_filter')", "effects"),
    )
    requires = ("pid",)
    # the effect's form: the catalogue entry is speed_sensor_lag's (Form 'second_order'), not a candidate of its own

    def declare(self, spec):
        spec.add_state("omega_meas", "rad/s", 50.0, "measured motor speed seen by the controller")
        spec.add_state("omega_meas_dot", "rad/s^2", 10.0, "rate of the measured motor speed")

    def signals(self, e, mode):
        _sensed(e, e.x["omega_meas_dot"])

    def finish(self, e, mode):
        p = e.p
        w_n = 2.0 * p.zeta_s / p.tau_s
        e.set_rate("omega_meas", e.x["omega_meas_dot"])
        e.set_rate("omega_meas_dot", w_n ** 2 * (e.x["omega_motor"] - e.x["omega_meas"]
                                                 - p.tau_s * e.x["omega_meas_dot"]))


@register
class SpeedSensorDelay(Component):
    """Transport delay then first-order lag of the speed sensor: the ``delay`` form of ``speed_sensor_lag``.

    The delay e^(-s T_d) is the (2,2) Pade approximant (1 - s T_d/2 + (s T_d)^2/12) / (1 + s T_d/2 +
    (s T_d)^2/12), in phase with the true delay to within 1 degree up to omega T_d = 1.7 (a 6 Hz ring behind
    a 30 ms delay: omega T_d = 1.1, 0.12 degree) and of unit gain at every frequency; it is realised as u - T_d x_2 with
    T_d^2/12 x_2' = u - x_1 - (T_d/2) x_2, x_1' = x_2 (u: the motor speed).  The lag tau_s follows; the
    controller and the record see its output, as with the lag alone.
    """

    name = "speed_sensor_delay"
    summary = "controller and record see the motor speed through a transport delay T_d and a first-order lag tau_s"
    param_names = ("tau_s", "T_d")
    parameters = (
        param("T_d", 0.01, "s", "assumed: a speed estimate over a few controller samples",
              "transport delay of the speed sensor (component 'speed_sensor_delay')", "effects"),
    )
    requires = ("pid",)

    def declare(self, spec):
        spec.add_state("omega_meas", "rad/s", 50.0, "measured motor speed seen by the controller")
        spec.add_state("delay_x1", "rad/s", 50.0, "state of the delay's Pade approximant (low-passed motor speed)")
        spec.add_state("delay_x2", "rad/s^2", 10.0, "state of the delay's Pade approximant (its rate)")

    def signals(self, e, mode):
        delayed = e.x["omega_motor"] - e.p.T_d * e.x["delay_x2"]
        _sensed(e, (delayed - e.x["omega_meas"]) / e.p.tau_s)

    def finish(self, e, mode):
        T = e.p.T_d
        e.set_rate("omega_meas", e.sig["omega_fb_dot"])
        e.set_rate("delay_x1", e.x["delay_x2"])
        e.set_rate("delay_x2", (e.x["omega_motor"] - e.x["delay_x1"] - 0.5 * T * e.x["delay_x2"]) / (T * T / 12.0))


@register
class KilnUnbalance(Component):
    """Once-per-revolution torque on the kiln (eccentric mass or shell crank).

    Torque -T_unb*sin(theta_o + phi_unb) on the kiln; state ``theta_o`` is the
    kiln angle [rad] (it grows slowly: 0.048 rad/s at 500 rpm motor speed).
    """

    name = "kiln_unbalance"
    summary = "once-per-revolution kiln torque T_unb*sin(theta_o + phi_unb)"
    param_names = ("T_unb", "phi_unb")
    parameters = (
        param("T_unb", 2.0e5, "N*m", "assumed: about 5 % of the 4.2 MN*m kiln running torque",
              "amplitude of the once-per-revolution kiln torque (component 'kiln_unbalance')", "effects",
              "nonnegative"),
        param("phi_unb", 0.0, "rad", "assumed: phase of the eccentric mass or shell crank at t = 0",
              "phase of the once-per-revolution torque (component 'kiln_unbalance')", "effects", "finite"),
    )
    catalogue = (
        Effect(
            "kiln_unbalance",
            "A once-per-revolution torque on the kiln from an eccentric mass (coating, accretion) or a "
            "cranked shell: T_unb sin(theta_o + phi_unb).",
            ("kiln_unbalance",), {}, None,
            (FreeParameter("T_unb", 0.0, 2e7, "polar", 2e5, partner="phi_unb"),),
            "a slow sinusoidal drift of the current with the kiln angle (one period per kiln revolution, "
            "about 130 s at 500 rpm): in a short record, a slowly rising or falling offset",
            starts=lambda params, m: [{"T_unb": 1e4, "phi_unb": 0.0}],
            plausible={"T_unb": (1e5, 4e5), "phi_unb": (0.0, 2 * math.pi)}, null={"T_unb": 0.0, "phi_unb": 0.0},
            scale=kiln_torque_scale,
            period=lambda params, omega_ref: 60.0 * params.n / omega_ref,  # one kiln revolution at the set speed
            short_record_note="a slow drift, which a current-sensor offset or gain error, or slowly correlated "
                              "noise, also produce",
            notes="fitted as the pair (T cos phi, T sin phi), which is linear in the torque; T_unb and phi_unb "
                  "and their standard errors follow.  A load with a second harmonic beside the first (a shell's "
                  "ovality) is its 'two_harmonic' form, tried in the final check in place of another selected "
                  "effect.",
            forms=(Form("two_harmonic",
                        "a kiln load periodic in the kiln angle with a second harmonic beside the first (a shell's "
                        "ovality, two eccentric masses): T_unb sin(theta_o + phi_unb) + T_unb2 sin(2 theta_o + "
                        "phi_unb2)",
                        ("kiln_unbalance", "kiln_second_harmonic"),
                        (FreeParameter("T_unb2", 0.0, 2e7, "polar", 1e5, partner="phi_unb2"),),
                        near={"T_unb2": 0.0, "phi_unb2": 0.0},
                        # the second harmonic at half the first's amplitude, in four phases
                        starts=lambda v: [{"T_unb2": 0.5 * v["T_unb"], "phi_unb2": k * math.pi / 2}
                                          for k in range(4)],
                        # no second harmonic is the effect's own form, not a stand-in's bound
                        ends={"T_unb2": "lower"},
                        # over a start-up of 40 s (a third of a revolution) a second harmonic is a slow drift
                        # like the first: in the rounds it would fit the noise; in the final check it must take
                        # the place of a selected effect
                        in_rounds=False),)),
    )
    requires = ("kiln",)

    def declare(self, spec):
        spec.add_state("theta_o", "rad", 1.0, "kiln angle")

    def loads(self, e, mode):
        e.add_torque("kiln", -e.p.T_unb * ca.sin(e.x["theta_o"] + e.p.phi_unb))

    def rest_kiln_torque(self, params):
        return -params.T_unb * math.sin(params.phi_unb)

    def finish(self, e, mode):
        e.set_rate("theta_o", e.x["omega_kiln"])


@register
class KilnSecondHarmonic(Component):
    """Twice-per-revolution torque on the kiln (shell ovality, two eccentric masses), beside the unbalance.

    Torque -T_unb2*sin(2 theta_o + phi_unb2) on the kiln, on the kiln angle ``theta_o`` that
    :class:`KilnUnbalance` integrates: the second harmonic of a kiln-angle-periodic load whose first is the
    unbalance.  Not a catalogue effect of its own: the ``two_harmonic`` form of ``kiln_unbalance`` (tried in
    the diagnosis' final check); add it with ``kiln_unbalance`` (``--effects
    kiln_unbalance,kiln_second_harmonic``) to compare or simulate a load of two harmonics.
    """

    name = "kiln_second_harmonic"
    summary = "twice-per-revolution kiln torque T_unb2*sin(2 theta_o + phi_unb2)"
    param_names = ("T_unb2", "phi_unb2")
    parameters = (
        param("T_unb2", 0.0, "N*m", "assumed: none unless fitted (a shell's ovality, two eccentric masses)",
              "amplitude of the twice-per-revolution kiln torque (component 'kiln_second_harmonic')", "effects",
              "nonnegative"),
        param("phi_unb2", 0.0, "rad", "assumed: phase of the ovality at t = 0",
              "phase of the twice-per-revolution torque (component 'kiln_second_harmonic')", "effects", "finite"),
    )
    requires = ("kiln_unbalance",)

    def loads(self, e, mode):
        e.add_torque("kiln", -e.p.T_unb2 * ca.sin(2.0 * e.x["theta_o"] + e.p.phi_unb2))

    def rest_kiln_torque(self, params):
        return -params.T_unb2 * math.sin(params.phi_unb2)


@register
class ViscousDrag(Component):
    """Viscous drag on the kiln, torque -B_o*omega_o (seals, tyre slip, lubricant)."""

    name = "viscous_drag"
    summary = "viscous drag torque -B_o*omega_o on the kiln"
    param_names = ("B_o",)
    parameters = (
        param("B_o", 1.0e6, "N*m*s/rad", "assumed: about 1 % of the running torque at 0.46 rpm (seals, tyre slip)",
              "viscous drag on the kiln (component 'viscous_drag')", "effects", "nonnegative"),
    )
    catalogue = (
        Effect(
            "viscous_drag",
            "A torque proportional to the kiln speed (seals, tyre and roller slip, lubricant drag): "
            "-B_o omega_o.",
            ("viscous_drag",), {}, None,
            (FreeParameter("B_o", 0.0, 1e9, "lin", 1e6),),
            "current above the model in proportion to the speed: growing along the ramp, then a constant "
            "offset at steady speed (which alone a burden mass or friction change could also explain)",
            starts=lambda params, m: [{"B_o": 1e5}, {"B_o": 3e6}],
            plausible={"B_o": (2e6, 1e7)}, null={"B_o": 0.0}, scale=drag_scale, steady_load=True),
    )
    requires = ("kiln",)

    def loads(self, e, mode):
        e.add_torque("kiln", -e.p.B_o * e.x["omega_kiln"])
