"""The smooth start-up model the optimizer works on, built from the plant's components.

:class:`SmoothStartup` assembles the micro model with the smoothed twins of
the non-smooth components (``mesh_smooth``, ``burden_smooth``, see
:mod:`kilnctl.model.smooth`) and the profile's reference component, without
the drive limits (they become constraints), and compiles from
:meth:`kilnctl.model.Plant.equations` the right-hand side and the outputs the
problem needs.  Nothing of the drive train is written again here: the
equations are the components'.

The decision variables and the smoothing widths are constant states of the
ramp and smooth components, so they enter through the initial state; CVODES
forward sensitivities with respect to the initial state give the gradients.

Outputs (rows of :meth:`SmoothStartup.outputs`): ``sigma`` [Pa], ``sigma_dyn``
[Pa] (:func:`load_stress` removed), ``i_a`` [A], ``e_a`` [V], ``speed_rpm``.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import casadi as ca
import numpy as np

from ..errors import ModelError, OptimizationError
from ..model import MODELS, REGISTRY, phase_rank
from ..model.assembly import Plant
from ..model.base import option_names
from ..model.drivetrain import lewis_stress
from ..model.kiln import bearing_torque
from ..model.smooth import SMOOTH_DS, SMOOTH_V, smooth_names
from ..params import Parameters

if TYPE_CHECKING:  # annotations only: the problem imports this module (no import cycle at run time)
    from .problem import Profile

__all__ = ["SmoothStartup", "load_stress", "OUTPUTS", "smooth_components", "hybrid_components", "check_effects"]

#: tolerance factors tried in turn when CVODES fails (seen: a trial Newton iterate at the backlash impact
#: made the right-hand side non-finite at rtol 1e-8, while 1e-7 and 1e-9 ran)
RETRY_TIGHTEN = (1.0, 0.1)


def integrate_retrying(integrator, theta, **inputs) -> dict:
    """Run a CasADi integrator, again at tighter tolerances (:data:`RETRY_TIGHTEN`) when CVODES fails.

    Parameters
    ----------
    integrator : callable
        ``integrator(tighten)`` -> the CasADi integrator with its tolerances times ``tighten`` [-].
    theta : sequence of float
        Profile numbers [units of the profile], for the message.
    **inputs
        The integrator's inputs (``x0``, ``p``).

    Returns
    -------
    dict
        The integrator's outputs.

    Raises
    ------
    OptimizationError
        CVODES failed at every tolerance tried (the message names the profile numbers).
    """
    why = ""
    for tighten in RETRY_TIGHTEN:
        try:
            return integrator(tighten)(**inputs)
        except RuntimeError as exc:
            why = str(exc).splitlines()[-1]
    raise OptimizationError(f"the smooth model failed to integrate at profile numbers {list(theta)} "
                            f"(also with tighter tolerances): {why}")


#: output rows of the smooth model
OUTPUTS = ("sigma", "sigma_dyn", "i_a", "e_a", "speed_rpm")

#: the paper's micro model (hybrid) without its ramp, from kilnctl.model.MODELS['micro']
_HYBRID_CORE = tuple(c for c in MODELS["micro"] if c != "ramp")
#: its smooth twin: each component with modes replaced by its smooth twin, the drive limits left out (they
#: become constraints), see kilnctl.model.smooth.smooth_names
_SMOOTH_CORE = smooth_names(_HYBRID_CORE)


def check_effects(effects) -> tuple[str, ...]:
    """Effects the ramp optimization can carry: components without modes, or with a smooth twin.

    The smooth model uses each effect's smooth twin where it has modes (:func:`smooth_components`), the
    hybrid verification the effect itself (:func:`hybrid_components`).

    Parameters
    ----------
    effects : sequence of str
        Component names (``second_motor``, ``speed_sensor_lag``, ``kiln_unbalance``, ``viscous_drag``,
        ``motor_coulomb_friction`` ...).

    Returns
    -------
    tuple of str
        The names, each once.

    Raises
    ------
    ModelError
        An unknown component, one with modes and no smooth twin, or one that replaces another.
    """
    from ..errors import close_matches_hint

    out = []
    for e in effects:
        if e not in REGISTRY:
            raise ModelError(f"effect {e!r} is not a component: {close_matches_hint(e, REGISTRY)}")
        comp = REGISTRY[e]
        if (comp.modes and not comp.smooth_twin) or comp.replaces:
            twins = {c.smooth_twin for c in REGISTRY.values()}
            base = {n for names in MODELS.values() for n in names}
            usable = sorted(n for n, c in REGISTRY.items() if n not in base and n not in twins
                            and not c.replaces and (not c.modes or c.smooth_twin) and not n.startswith("ramp_"))
            raise ModelError(f"effect {e!r} cannot be added to the ramp optimization: it "
                             + ("has modes and no smooth twin" if comp.modes and not comp.smooth_twin
                                else f"replaces {comp.replaces}")
                             + f"; the mode-free effects and those with a smooth twin can: {', '.join(usable)}")
        if e not in out:
            out.append(e)
    return tuple(out)


def _with(core, effects):
    names = list(core) + [e for e in effects if e not in core]
    return tuple(sorted(names, key=phase_rank))


def smooth_components(profile: Profile, effects=()) -> tuple[str, ...]:
    """Component list of the smooth optimization model for a profile family.

    Parameters
    ----------
    profile : Profile
    effects : sequence of str
        Effects to add (see :func:`check_effects`); one with modes enters as its smooth twin.

    Returns
    -------
    tuple of str
        ``ramp``, the profile's smooth reference component, then the smooth
        micro model without the drive limits, with the effects.
    """
    return ("ramp", profile.smooth_component) + _with(_SMOOTH_CORE, smooth_names(check_effects(effects)))


def hybrid_components(profile: Profile, effects=()) -> tuple[str, ...]:
    """Component list of the exact hybrid micro model driven by a profile.

    Parameters
    ----------
    profile : Profile
    effects : sequence of str
        Effects to add (see :func:`check_effects`), as they are.

    Returns
    -------
    tuple of str
        The paper's micro model with the effects; for a shaped profile its
        exact reference component follows ``ramp``.
    """
    extra = (profile.exact_component,) if profile.exact_component else ()
    return ("ramp",) + extra + _with(_HYBRID_CORE, check_effects(effects))


def load_stress(T_f, omega_kiln, p, tanh=np.tanh, fabs=np.abs):
    """Bending stress of the loads any ramp must carry: burden and bearing friction [Pa].

    The kiln shell obeys J_kiln*alpha = W*R_o - T_f - T_brg*tanh(omega/eps)
    in every mode of the burden (``T_f`` is the torque the burden takes from
    the wall), so sigma - load_stress = J_kiln*alpha*K_v/(R_o*b*m*Y): the
    stress spent accelerating the shell, which is what a ramp changes.

    Parameters
    ----------
    T_f : array or casadi.SX
        Wall torque on the burden [N*m] (output ``T_f``).
    omega_kiln : array or casadi.SX
        Kiln speed [rad/s].
    p : Parameters or SymParams
        Parameters (numeric or symbolic).
    tanh, fabs : callable
        ``numpy`` or ``casadi`` functions, matching the arguments.

    Returns
    -------
    array or casadi.SX
        Load stress [Pa].
    """
    T_load = T_f + bearing_torque(omega_kiln, p, tanh)
    return lewis_stress(T_load / p.R_o, omega_kiln, p, fabs)

class SmoothStartup:
    """Smooth micro model of the start-up for one profile family and option set.

    Parameters
    ----------
    profile : Profile
        Reference profile family.
    params : Parameters
        Only the string options are used (they select the structure).
    rtol, atol : float
        CVODES tolerances (atol on states scaled to order one).
    effects : sequence of str
        Mode-free effects added to the model (:func:`check_effects`).

    Attributes
    ----------
    plant : Plant
        The assembled smooth plant.
    rhs : casadi.Function
        (xs, t, P) -> dxs/dt, scaled states.
    outputs : casadi.Function
        (xs, t, P) -> the :data:`OUTPUTS` rows.
    """

    def __init__(self, profile: Profile, params: Parameters, rtol: float = 1e-8, atol: float = 1e-8, effects=()):
        self.profile = profile
        self.options = {k: params[k] for k in option_names()}
        self.plant = Plant(smooth_components(profile, effects), self.options, compile=False)
        if [c.name for c in self.plant.moded] != ["ramp"]:
            raise ModelError("the smooth start-up model must have no modes besides the ramp's")
        e, xs, t, sp = self.plant.equations(("rising",))  # the ramp's mode is overridden by the profile
        names = self.plant.state_names
        f = ca.vertcat(*[e.rates[n] / self.plant.scales[i] for i, n in enumerate(names)])
        o = e.outputs
        sig_dyn = o["sigma"] - load_stress(o["T_f"], e.x["omega_kiln"], sp, ca.tanh, ca.fabs)
        y = ca.vertcat(o["sigma"], sig_dyn, o["i_a"], o["e_a"], o["speed_rpm"])
        self.xs, self.t, self.P = xs, t, sp.vector
        self.f_expr, self.y_expr = f, y
        self.rhs = ca.Function("rhs", [xs, t, sp.vector], [f], ["xs", "t", "P"], ["f"])
        self.outputs = ca.Function("outputs", [xs, t, sp.vector], [y], ["xs", "t", "P"], ["y"])
        self.rtol, self.atol = float(rtol), float(atol)
        self.index = {n: i for i, n in enumerate(names)}
        self.theta_index = [self.index[n] for n in profile.names]
        self._integrators: dict = {}
        self._maps: dict = {}

    @property
    def width_names(self) -> tuple[str, ...]:
        """Smoothing widths of this model (constant states)."""
        return tuple(n for n in ("smooth_ds", "smooth_v", "ramp_corner") if n in self.index)

    def param_vector(self, params: Parameters) -> np.ndarray:
        """Numeric parameter vector P in :data:`kilnctl.model.base.NUMERIC_NAMES` order.

        Parameters
        ----------
        params : Parameters
            Parameter set with the gains resolved (``gains = 'given'``).

        Returns
        -------
        ndarray
        """
        if params.gains != "given":
            raise ModelError("resolve the PID gains first (kilnctl.simulate.resolve_gains)")
        return self.plant.param_vector(params)

    def x0(self, params: Parameters, theta, widths: dict):
        """Scaled initial state with the profile's numbers and the smoothing widths.

        Parameters
        ----------
        params : Parameters
            Parameter set (initial backlash position, burden angle).
        theta : array or casadi.MX
            Profile numbers in physical units (:attr:`Profile.names` order).
        widths : dict
            ``smooth_ds`` [m], ``smooth_v`` [rad/s], ``ramp_corner`` [s]
            (those the model has).

        Returns
        -------
        casadi.DM or casadi.MX
        """
        xs0, _ = self.plant.initial(params)
        given = {self.index[n]: v for n, v in widths.items() if n in self.index}
        given.update({i: theta[k] for k, i in enumerate(self.theta_index)})
        parts = [given[i] / self.plant.scales[i] if i in given else float(xs0[i]) for i in range(len(xs0))]
        return ca.vertcat(*parts)

    def integrator(self, t0: float, grid, quad=None, tighten: float = 1.0) -> ca.Function:
        """CVODES integrator from t0 returning the scaled states at each time of ``grid`` (cached).

        Parameters
        ----------
        t0 : float
            Start time [s].
        grid : sequence of float
            Output times [s], increasing, > t0.
        quad : tuple (name, casadi.SX q, casadi.SX pq), optional
            Quadrature integrands ``q`` (functions of :attr:`xs`, :attr:`t`,
            :attr:`P` and extra parameters ``pq``), integrated with error
            control; ``name`` keys the cache.
        tighten : float, default 1.0
            Factor on the tolerances (0.1: ten times tighter).

        Returns
        -------
        casadi.Function
            ``x0``, ``p`` (= P, or [P; pq] with quadratures) -> ``xf``
            (nx x len(grid)) and ``qf`` (cumulative quadratures at the grid).
        """
        key = (float(t0), tuple(np.round(np.asarray(grid, dtype=float), 12)), None if quad is None else quad[0],
               float(tighten))
        F = self._integrators.get(key)
        if F is None:
            dae = {"x": self.xs, "t": self.t, "p": self.P, "ode": self.f_expr}
            opts = {"abstol": self.atol * tighten, "reltol": self.rtol * tighten, "max_num_steps": 500000,
                    "fsens_err_con": True}
            if quad is not None:
                dae["p"] = ca.vertcat(self.P, quad[2])
                dae["quad"] = quad[1]
                opts["quad_err_con"] = True
            F = ca.integrator(f"F{len(self._integrators)}", "cvodes", dae, float(t0), [float(g) for g in grid], opts)
            self._integrators[key] = F
        return F

    def output_map(self, n: int) -> ca.Function:
        """The outputs mapped over ``n`` grid points (cached).

        Parameters
        ----------
        n : int
            Number of grid points.

        Returns
        -------
        casadi.Function
            (XS, T, P) -> Y, 5 x n rows in :data:`OUTPUTS` order.
        """
        m = self._maps.get(n)
        if m is None:
            m = self._maps[n] = self.outputs.map(n)
        return m

    def run(self, params: Parameters, theta, widths: dict, grid) -> dict:
        """Simulate the smooth model numerically and return the outputs on ``grid``.

        Parameters
        ----------
        params : Parameters
            Gains resolved.
        theta : sequence of float
            Profile numbers [units of the profile].
        widths : dict
            Smoothing widths.
        grid : ndarray
            Output times [s], > 0.

        Returns
        -------
        dict
            ``t`` and one array per name of :data:`OUTPUTS`.

        Raises
        ------
        OptimizationError
            CVODES failed at the model's tolerances and at ten times tighter ones.
        """
        grid = np.asarray(grid, dtype=float)
        P = self.param_vector(params)
        x0 = self.x0(params, np.asarray(theta, dtype=float), widths)
        X = integrate_retrying(lambda tighten: self.integrator(0.0, grid, tighten=tighten), theta, x0=x0, p=P)["xf"]
        Y = np.asarray(self.output_map(len(grid))(X, grid, P))
        out = {"t": grid}
        out.update({n: Y[i] for i, n in enumerate(OUTPUTS)})
        return out


#: default smoothing widths of the final (sharpest) stage
DEFAULT_WIDTHS = {"smooth_ds": SMOOTH_DS, "smooth_v": SMOOTH_V, "ramp_corner": 0.05}
