"""Run the model on the experiment of a measured record and sample it at the measured times.

This is the one place where the measurement tools call the simulator, so that
compare, calibrate and diagnose reproduce an experiment in the same way: the
gains are resolved once (the plant's controller does not change when a
parameter is calibrated), the ramp comes from the record when it was logged,
and the model's outputs are interpolated onto the measured times after the
duplicate times at mode switches are removed.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import KilnctlError, ModelError, name_list
from ..model.ramps import knots_component
from ..params import Parameters
from ..simulate import DEFAULT_DT as _DT  # default simulation output step per model [s], defined there once
from .io import Experiment, Measurement

__all__ = ["CHANNELS", "ModelRun", "run_model", "kiln_angle"]

#: measured column -> model output, unit
CHANNELS: dict[str, tuple[str, str]] = {"current_A": ("i_a", "A"), "speed_rpm": ("speed_rpm", "rpm")}


@dataclass
class ModelRun:
    """Model outputs at the measured times.

    Attributes
    ----------
    t : ndarray
        Measured times that are compared (at or after the start ``t0``) [s].
    outputs : dict of str to ndarray
        ``current_A`` [A], ``speed_rpm`` [rpm], ``speed_ref_rpm`` [rpm],
        ``kiln_angle`` [rad], ``psi`` [rad] at those times.
    events : list
        The simulator's mode switches (times relative to ``t0``).
    response : kilnctl.response.Response
        The raw simulation.
    outside : dict or None
        A change outside the catalogue added to the current by a calibration
        that allows one (see :class:`~kilnctl.measure.calibrate.Calibration`,
        ``outside``).
    """

    t: np.ndarray
    outputs: dict
    events: list
    response: object
    outside: dict | None = None


def _last_of_each_time(t) -> np.ndarray:
    """Indices that keep the last sample at each duplicated time (the state after a switch), in time order.

    The simulator's times never decrease, so a duplicate is equal to its successor.
    """
    t = np.asarray(t, float)
    if t.size and np.all(np.diff(t) >= 0):
        return np.nonzero(np.append(t[1:] != t[:-1], True))[0]
    rev = t[::-1]
    _, idx = np.unique(rev, return_index=True)
    return len(t) - 1 - idx



def kiln_angle(t, speed_rpm, n) -> np.ndarray:
    """Kiln angle from the motor speed by trapezoidal integration [rad].

    Parameters
    ----------
    t : ndarray
        Times [s].
    speed_rpm : ndarray
        Motor speed [rpm].
    n : float
        Total reduction motor to kiln [-].

    Returns
    -------
    ndarray
        theta_o(t) - theta_o(t[0]) [rad].
    """
    w = np.asarray(speed_rpm) * (2.0 * math.pi / 60.0) / n
    return np.concatenate([[0.0], np.cumsum(0.5 * (w[1:] + w[:-1]) * np.diff(t))])


def run_model(params: Parameters, measurement: Measurement, experiment: Experiment, *, model: str = "macro",
              effects=(), remove=(), dt: float | None = None, max_events: int = 3000,
              t_stop: float | None = None) -> ModelRun:
    """Simulate the experiment of ``measurement`` and sample the model at its times.

    Parameters
    ----------
    params : Parameters
        Parameters of the model (gains fixed, see :func:`kilnctl.simulate.resolve_gains`).
    measurement : Measurement
        The record.
    experiment : Experiment
        Start time [s], ramp rate [rpm/s] and final reference [rpm] (and the
        jerk limit of an S-curve reference [rpm/s^2], or the knots of a reference that is not one ramp and
        hold, and whether the drive holds the kiln at rest before it, see :class:`Experiment`).
    model : {'macro', 'micro'}, default 'macro'
        Base model.
    effects : sequence of str
        Components to add.
    remove : sequence of str
        Components to take out.
    dt : float, optional
        Simulation output step [s]; the simulator's default for the model.
    max_events : int, default 3000
        Mode switches allowed before the run is refused (a runaway fit).
    t_stop : float, optional
        Record time [s] after which the model need not run (a fit on the
        first part of the record: the model is causal, so its outputs up to
        ``t_stop`` do not depend on what follows).  Later samples hold the
        last simulated value; default: the whole record.

    Returns
    -------
    ModelRun
    """
    from ..simulate import simulate

    p = params
    if params.ramp_rate != experiment.ramp_rate or params.omega_ref != experiment.omega_ref:
        p = params.replace(ramp_rate=experiment.ramp_rate, omega_ref=experiment.omega_ref)
    active = measurement.t >= experiment.t0 - 1e-9
    t = measurement.t[active]
    t_end = float(t[-1] - experiment.t0)
    if t_end <= 0:
        raise KilnctlError(f"{measurement.source}: the start-up begins at {experiment.t0:g} s, after the last sample")
    if t_stop is not None:
        t_end = min(t_end, max(float(t_stop) - experiment.t0, 4 * (t[1] - t[0]) if t.size > 1 else t_end))
    dt = _DT.get(model, 1e-3) if dt is None else dt
    effects, remove = name_list(effects, "effects", ModelError), name_list(remove, "remove", ModelError)
    initial = None
    jerk = getattr(experiment, "jerk", None)  # (an experiment built by hand may not have one)
    knots = getattr(experiment, "knots", None)
    if knots:  # a recorded reference that is not one ramp and hold: the model follows it through its knots
        effects = (knots_component(len(knots)),) + tuple(effects)
        initial = {f"ramp_{x}{i}": v for i, kt in enumerate(knots, 1) for x, v in zip("tw", kt)}
    elif jerk is not None:  # a recorded S-curve reference: the model follows it
        effects = ("ramp_scurve",) + tuple(effects)
        initial = {"ramp_a": experiment.ramp_rate, "ramp_j": jerk}
    resp = simulate(p, model, t_end=t_end, effects=tuple(effects), remove=tuple(remove), dt=min(dt, t_end / 4),
                    max_events=max_events, initial=initial, held=bool(getattr(experiment, "held", False)))
    ts = np.asarray(resp.t, dtype=float)
    rel = t - experiment.t0
    keep = _last_of_each_time(ts)  # one index for every signal of the run
    tu = ts[keep]
    out = {}
    for col, (name, _unit) in CHANNELS.items():
        out[col] = np.interp(rel, tu, np.asarray(resp.outputs[name], dtype=float)[keep])
    for name, key in (("speed_ref_rpm", "speed_ref_rpm"), ("psi", "psi"), ("kiln_rpm", "kiln_rpm")):
        if key in resp.outputs:
            out[name] = np.interp(rel, tu, np.asarray(resp.outputs[key], dtype=float)[keep])
    if not all(np.all(np.isfinite(v)) for v in out.values()):
        raise KilnctlError("the model produced non-finite outputs")
    return ModelRun(t=t, outputs=out, events=list(resp.events), response=resp)
