"""Linearize any plant structure at an operating point, exactly, into python-control.

:mod:`kilnctl.linear` writes the paper's rigid two-inertia model (eq. 21) by
hand.  A model a measurement taught (a compliant drive train, a lagging speed
sensor, a second motor, backlash in contact ...) has other dynamics; this
module takes them from the one model definition: the exact CasADi Jacobian of
the compiled plant's right-hand side in one mode, at a state the nonlinear
plant actually reaches, as a python-control :class:`~control.StateSpace`
with named states, input and outputs.

The operating point is the end of a nonlinear start-up (``t_op`` seconds,
the drive at speed with the reference held), with the moded components in the
modes the start-up ends in, or in the paper's two load conditions (the burden
stuck to the shell or sliding on it, the mesh in contact, both limits free).  The input is the speed reference [rpm]; the
outputs are the motor speed [rpm] and the armature current [A], deviations
from the operating point.

>>> from kilnctl.linearize import linearize
>>> lin = linearize(model="macro", burden="stick")
>>> round(float(lin.damping()[0]), 2)  # the design sits on zeta_min = 0.7
0.7
"""

from __future__ import annotations

from dataclasses import dataclass, field

import casadi as ca
import control as ct
import numpy as np

from .errors import ModelError, SimulationError, close_matches_hint
from .gains import resolve_gains
from .model import get_plant
from .model.base import NUMERIC_NAMES
from .params import Parameters

__all__ = ["linearize", "LinearizedPlant", "OPERATING_MODES"]

#: modes of the moded components at the operating point, per burden condition
OPERATING_MODES = {"stick": {"ramp": "hold", "burden": "stick", "mesh": "contact", "current_limit": "free",
                             "current_limit_pi": "free", "voltage_limit": "free"},
                   "slip": {"ramp": "hold", "burden": "slip_pos", "mesh": "contact", "current_limit": "free",
                            "current_limit_pi": "free", "voltage_limit": "free"}}
#: outputs of the linear model (names of the plant's output signals) and their units
OUTPUTS = {"speed_rpm": "rpm", "i_a": "A"}


@dataclass
class LinearizedPlant:
    """A plant structure linearized at an operating point.

    Attributes
    ----------
    sys : control.StateSpace
        Closed loop (the PID is part of the plant) from the speed reference
        ``speed_ref`` [rpm] to ``speed_rpm`` [rpm] and ``i_a`` [A], states in
        physical units with the plant's state names.
    components : tuple of str
        The structure that was linearized.
    modes : dict
        Mode of each moded component at the operating point.
    x_op : dict
        The operating point: state values in physical units.
    t_op : float
        Time of the nonlinear start-up at which the point was taken [s].
    """

    sys: ct.StateSpace
    components: tuple
    modes: dict
    x_op: dict
    t_op: float
    params: Parameters = field(repr=False, default=None)
    _parts: tuple = field(repr=False, default=None)

    def with_gains(self, k_p: float, k_I: float, k_D: float) -> "LinearizedPlant":
        """The same structure and operating point with other PID gains (the Jacobian re-evaluated, exact).

        The operating state is kept: at speed the gains move only the
        integrator's value, on which the Jacobian does not depend.

        Parameters
        ----------
        k_p, k_I, k_D : float
            Gains [V/rpm, V/(rpm*s), V*s/rpm].

        Returns
        -------
        LinearizedPlant
        """
        plant, jac, xs_op, P = self._parts
        P2 = np.array(P, dtype=float)
        for nm, v in (("k_p", k_p), ("k_I", k_I), ("k_D", k_D)):
            P2[NUMERIC_NAMES.index(nm)] = v
        sys = _state_space(plant, jac, xs_op, self.t_op, P2, name=self.sys.name)
        params = self.params.replace(gains="given", k_p=k_p, k_I=k_I, k_D=k_D) if self.params is not None else None
        return LinearizedPlant(sys, self.components, self.modes, self.x_op, self.t_op, params, (plant, jac, xs_op, P2))

    def poles(self) -> np.ndarray:
        """Closed-loop poles [rad/s], sorted by real part (slowest first)."""
        p = np.asarray(self.sys.poles(), dtype=complex)
        return p[np.argsort(-p.real)]

    def damping(self) -> np.ndarray:
        """Damping ratio of each oscillatory pole pair (one entry per pair), lowest first.

        Returns
        -------
        numpy.ndarray
            zeta [-] of the poles with a positive imaginary part.
        """
        p = self.poles()
        osc = p[p.imag > 1e-9]
        z = -osc.real / np.abs(osc)
        return np.sort(z)

    def table(self) -> list[dict]:
        """One row per pole pair or real pole: s [rad/s], natural frequency [rad/s], damping [-], f [Hz].

        Poles at zero (kinematic states such as an angle, or a node speed
        tied to another by a rigid link) have damping NaN.

        Returns
        -------
        list of dict
        """
        rows = []
        scale = max(1.0, float(np.abs(self.poles()).max()))
        for s in self.poles():
            if s.imag < -1e-9:
                continue
            wn = abs(s)
            if wn < 1e-9 * scale:  # a kinematic state (an angle, a speed tied to another by a link): no dynamics
                rows.append({"pole": 0j, "omega_n_rad_s": 0.0, "f_hz": 0.0, "zeta": float("nan")})
                continue
            rows.append({"pole": complex(s), "omega_n_rad_s": float(wn), "f_hz": float(abs(s.imag) / (2 * np.pi)),
                         "zeta": float(-s.real / wn)})
        return rows


def linearize(params: Parameters | None = None, model: str = "macro", *, effects=(), remove=(), components=None,
              burden: str | None = None, modes: dict | None = None, t_op: float = 40.0) -> LinearizedPlant:
    """Linearize a plant structure at the end of a start-up, exactly (CasADi Jacobian).

    Parameters
    ----------
    params : Parameters, optional
        Parameters (default Table 1); ``gains = 'design'`` is resolved first.
    model : {'macro', 'micro'}
        Base model.
    effects, remove : sequence of str
        Components added to or taken out of the base model.
    components : sequence of str or Structure, optional
        The full component list, or a :class:`kilnctl.structure.Structure`, instead.
    burden : {None, 'stick', 'slip'}, default None
        None: every moded component in the mode the start-up ends in (the
        drive at speed as it really runs).  'stick' or 'slip': the burden
        stuck to the shell (its inertia rides with the kiln) or sliding on it
        (kinetic friction, a constant load), the paper's two load
        conditions, with the mesh in contact and both limits free
        (:data:`OPERATING_MODES`).
    modes : dict, optional
        Modes of moded components, overriding both.
    t_op : float, default 40.0
        Length of the nonlinear start-up whose end state is the operating
        point [s]; the reference must have been reached by then.

    Returns
    -------
    LinearizedPlant

    Raises
    ------
    ModelError
        Unknown burden condition or mode.
    SimulationError
        The start-up to the operating point fails.
    """
    from .simulate import plant_structure, simulate

    params = resolve_gains(Parameters() if params is None else params)
    if burden is not None and burden not in OPERATING_MODES:
        raise ModelError(f"burden = {burden!r}: choose 'stick', 'slip' or None (the mode the start-up ends in)")
    names, params, _ = plant_structure(params, model, effects, remove, components)
    plant = get_plant(names, params)
    r = simulate(params, components=names, t_end=t_op)
    if params.ramp_rate * t_op < params.omega_ref:
        raise SimulationError(f"t_op = {t_op} s ends before the ramp reaches omega_ref = {params.omega_ref} rpm: "
                              "choose a longer t_op")
    ended = {c.name: str(r.modes[c.name][-1]) for c in plant.moded}
    want = {**ended, **(OPERATING_MODES[burden] if burden else {}), **(modes or {})}
    mode = []
    for c in plant.moded:
        m = want.get(c.name, c.modes[0])
        if m not in c.modes:
            raise ModelError(f"mode {m!r} of component {c.name!r}: choose one of {c.modes}")
        mode.append(m)
    mode = tuple(mode)
    unknown = [k for k in (modes or {}) if k not in [c.name for c in plant.moded]]
    if unknown:
        raise ModelError(f"modes names {unknown[0]!r}, which has no modes in this structure: "
                         f"{close_matches_hint(unknown[0], [c.name for c in plant.moded])}")
    xs_op = np.array([r.states[n][-1] for n in plant.state_names]) / plant.scales
    P = plant.param_vector(params)
    mf = plant.functions(mode)
    xs_op = np.asarray(mf.project(xs_op, t_op, P)).ravel()  # consistent with the chosen mode's links
    jac = _jacobian_function(plant, mode)
    sys = _state_space(plant, jac, xs_op, t_op, P, name=f"{'+'.join(names)} ({burden or 'as running'})")
    S = plant.scales
    return LinearizedPlant(sys, names, plant.mode_dict(mode),
                           {n: float(xs_op[i] * S[i]) for i, n in enumerate(plant.state_names)}, float(t_op), params,
                           _parts=(plant, jac, xs_op, P))


_JAC_CACHE: dict = {}


def _jacobian_function(plant, mode):
    """(xs, t, P) -> (df/dxs, df/d omega_ref, dy/dxs, dy/d omega_ref) of one mode, built once per plant and mode."""
    key = (id(plant), mode)
    if key not in _JAC_CACHE:
        e, xs, t, sp = plant.equations(mode)
        f = ca.vertcat(*[e.rates[n] for n in plant.state_names])  # physical units per second
        y = ca.vertcat(*[e.outputs[n] for n in OUTPUTS])
        iref = NUMERIC_NAMES.index("omega_ref")
        _JAC_CACHE[key] = (plant, ca.Function("lin", [xs, t, sp.vector],
                                              [ca.jacobian(f, xs), ca.jacobian(f, sp.vector)[:, iref],
                                               ca.jacobian(y, xs), ca.jacobian(y, sp.vector)[:, iref]]))
    return _JAC_CACHE[key][1]


def _state_space(plant, jac, xs_op, t_op, P, name="") -> ct.StateSpace:
    As, Bp, Cs, Dp = (np.asarray(m) for m in jac(xs_op, t_op, P))
    S = plant.scales
    A = As / S[None, :]  # d(x)/dt over d(x) with x = S*xs
    C = Cs / S[None, :]
    return ct.ss(A, Bp, C, Dp, states=list(plant.state_names), inputs=["speed_ref"], outputs=list(OUTPUTS),
                 name=name)
