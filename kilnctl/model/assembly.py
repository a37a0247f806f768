"""Assembling components into a plant and compiling its per-mode functions.

:class:`Plant` holds one structure (a list of components and the string
options); for each combination of component modes it builds, once and on
demand, the CasADi functions the simulator needs: the right-hand side, the
guards with their time derivatives, the outputs, and CVODES integrators.
Parameters are symbolic inputs, so a plant is reused for any numeric values.
"""

from __future__ import annotations

import time
from collections import defaultdict
from dataclasses import dataclass, field
from functools import lru_cache
from typing import Callable

import casadi as ca
import numpy as np

from ..errors import ModelError, close_matches_hint
from ..params import Parameters
from .base import REGISTRY, Component, Guard, ModelSpec, SymParams, numeric_names, option_names
from .compiled import compile_function
from .stepper import build_stepper

__all__ = ["Eqs", "Plant", "ModeFunctions", "get_plant"]

GROUND = "ground"
#: points per call of the (compiled) output function
OUTPUT_BATCH = 1024
#: how far (in the invariant's scaled units) a sliding motion may leave its surface before it ends
SLIDING_BAND = 1e-4


class Eqs:
    """Symbolic equations of one mode, filled in by the components.

    Attributes
    ----------
    p : SymParams
        Symbolic parameters.
    x : dict of str to casadi.SX
        States in physical units.
    t : casadi.SX
        Time [s].
    sig : dict
        Named signals (``e_v``, ``e_f``, ``i_a`` ...).
    accel : dict
        Angular accelerations of the nodes [rad/s^2], after assembly.
    """

    def __init__(self, p: SymParams, x: dict, t):
        self.p = p
        self.x = x
        self.t = t
        self.sig: dict[str, ca.SX] = {}
        self.inertia: dict[str, list] = defaultdict(list)
        self.torques: dict[str, list] = defaultdict(list)
        self.links: list[tuple[str, str, ca.SX]] = []
        self.rates: dict[str, ca.SX] = {}
        self.guards: list[Guard] = []
        self.outputs: dict[str, ca.SX] = {}
        self.accel: dict[str, ca.SX] = {}
        self.projection: dict[str, ca.SX] = {}
        self.controls: list[tuple] = []

    # --- Filippov sliding modes with an equivalent control -----------------
    def equivalent_control(self, name: str):
        """A symbol u that the plant will choose so that an invariant stays constant.

        A sliding mode of a component uses ``u`` (a fraction in [0, 1]) where
        its two neighbouring modes differ (for the current limit: how much of
        the time the integrator runs), and declares with
        :meth:`hold_constant` which expression the sliding motion keeps
        constant.  After the equations are complete the plant solves
        d(invariant)/dt = 0 for u (it enters affinely: Filippov's convex
        combination) and substitutes the solution everywhere.
        """
        u = ca.SX.sym(f"u_{name}")
        self.controls.append([u, None, None, None])
        return u

    def hold_constant(self, u, invariant, below: str, above: str, component: str) -> None:
        """Declare the invariant of the sliding mode that uses ``u``, and where it ends.

        Parameters
        ----------
        u : casadi.SX
            The symbol from :meth:`equivalent_control`.
        invariant : casadi.SX
            Expression (of states and time) the sliding motion keeps constant.
        below, above : str
            Modes of ``component`` entered when the sliding motion ends: when
            the invariant rises even with u = 0 (``below``), or falls even
            with u = 1 (``above``).
        component : str
            The component that owns the sliding mode.
        """
        for c in self.controls:
            if c[0] is u:
                c[1:] = [invariant, (below, above), component]
                return
        raise ModelError("hold_constant: u was not made by equivalent_control")

    def solve_controls(self, xs, scales, state_names) -> None:
        """Replace each equivalent control by the value that keeps its invariant constant.

        With c0, c1 the invariant's rate at u = 0 and u = 1, u* = -c0/(c1 - c0).
        Adds the guards -c0 > 0 (else to ``below``: even u = 0 raises the
        invariant) and c1 > 0 (else to ``above``: even u = 1 lowers it); the
        sliding motion exists while both hold, and u* is then in (0, 1).  It
        also ends when the invariant is thrown off its surface by more than
        :data:`SLIDING_BAND` (a jump elsewhere in the plant).
        """
        for u, inv, (below, above), comp in self.controls:
            if inv is None:
                raise ModelError(f"sliding mode of {comp!r}: equivalent control without an invariant")
            rate = ca.vertcat(*[self.rates[n] / scales[i] for i, n in enumerate(state_names)])
            cdot = ca.jtimes(inv, xs, rate) + ca.jacobian(inv, self.t)
            c0, c1 = ca.substitute(cdot, u, 0), ca.substitute(cdot, u, 1)
            den = c1 - c0
            ustar = ca.if_else(ca.fabs(den) > 1e-12 * (ca.fabs(c0) + ca.fabs(c1)) + 1e-300, -c0 / den, 0)
            self._substitute(u, ustar)
            # Filippov: the sliding motion exists while the two neighbouring vector fields point against each
            # other across the surface: the invariant falls with u = 0 (c0 < 0) and rises with u = 1 (c1 > 0).
            # (Guards on u* itself would be wrong when c1 < c0: integrating then lowers the invariant.)
            # the motion stays on the surface only while nothing jumps: an impact elsewhere (a mesh contact, the
            # end of the ramp) can throw the invariant off it; below the surface the neighbour ``above`` holds,
            # above it ``below``. These come first: off the surface, the rates below do not decide.
            self.guards.append(Guard("sliding_end", comp, inv + SLIDING_BAND, above))
            self.guards.append(Guard("sliding_end", comp, SLIDING_BAND - inv, below))
            self.guards.append(Guard("sliding_end", comp, -ca.substitute(c0, u, 0), below))
            self.guards.append(Guard("sliding_end", comp, ca.substitute(c1, u, 1), above))
        self.controls = []

    def _substitute(self, u, value) -> None:
        for d in (self.rates, self.outputs, self.sig, self.projection):
            for k, v in list(d.items()):
                if isinstance(v, ca.SX):
                    d[k] = ca.substitute(v, u, value)
        self.guards = [Guard(g.kind, g.component, ca.substitute(g.expr, u, value), g.target, g.alt_target,
                             None if g.selector is None else ca.substitute(g.selector, u, value))
                       for g in self.guards]

    # --- phase 2 ---------------------------------------------------------
    def add_inertia(self, node: str, J) -> None:
        """Add inertia ``J`` [kg*m^2] to ``node``."""
        self.inertia[node].append(J)

    def add_torque(self, node: str, T) -> None:
        """Apply torque ``T`` [N*m] to ``node`` (positive along its rotation)."""
        self.torques[node].append(T)

    def link(self, a: str, b: str, ratio) -> None:
        """Join two nodes rigidly: omega_a = ratio * omega_b."""
        self.links.append((a, b, ratio))

    # --- phase 3 ---------------------------------------------------------
    def set_rate(self, state: str, expr) -> None:
        """Set the time derivative of ``state`` (physical units per second)."""
        if state in self.rates:
            raise ModelError(f"two components set the rate of state {state!r}")
        self.rates[state] = expr

    def add_guard(self, guard: Guard) -> None:
        """Add a mode-switch guard of the current mode."""
        self.guards.append(guard)

    def add_output(self, name: str, expr) -> None:
        """Add a named output signal."""
        self.outputs[name] = expr

    def torque_sum(self, node: str):
        """Sum of external torques on ``node`` [N*m]."""
        return sum(self.torques.get(node, []), ca.SX(0))

    def link_torque(self, node: str):
        """Torque the rigid links deliver into ``node``: J*accel - external torques [N*m]."""
        J = sum(self.inertia.get(node, []), ca.SX(0))
        return J * self.accel[node] - self.torque_sum(node)

    def assemble(self, nodes: list[str]) -> None:
        """Compute node accelerations from inertias, torques and rigid links."""
        adj: dict[str, list] = defaultdict(list)
        for a, b, r in self.links:
            adj[a].append((b, 1.0 / r))  # omega_b = omega_a / r
            adj[b].append((a, r))
        rho: dict[str, object] = {}
        for root in nodes:
            if root in rho:
                continue
            group = {root: ca.SX(1)}
            queue = [root]
            while queue:
                u = queue.pop()
                for v, r in adj[u]:
                    if v not in group:
                        group[v] = group[u] * r
                        queue.append(v)
            rho.update(group)
            if GROUND in group:
                for nd in group:
                    self.accel[nd] = ca.SX(0)
                continue
            J = sum((group[nd] ** 2 * sum(self.inertia.get(nd, []), ca.SX(0)) for nd in group), ca.SX(0))
            T = sum((group[nd] * self.torque_sum(nd) for nd in group), ca.SX(0))
            acc = T / J
            # momentum of the group, to project speeds onto the rigid links at a mode switch
            H = sum((group[nd] * sum(self.inertia.get(nd, []), ca.SX(0)) * self.x[f"omega_{nd}"]
                     for nd in group), ca.SX(0))
            for nd in group:
                self.accel[nd] = group[nd] * acc
                if len(group) > 1:
                    self.projection[f"omega_{nd}"] = group[nd] * H / J
        for nd in nodes:
            if nd != GROUND:
                self.set_rate(f"omega_{nd}", self.accel[nd])


@dataclass
class ModeFunctions:
    """Compiled functions of one mode combination.

    Attributes
    ----------
    mode : tuple of str
        Mode of each moded component, in :attr:`Plant.moded` order.
    rhs : casadi.Function
        (xs, t, P) -> dxs/dt in scaled states.
    output : casadi.Function
        (xs, t, P) -> output vector at one point.
    project : casadi.Function
        (xs, t, P) -> xs made consistent with this mode's constraints: node
        speeds onto its rigid links (conserving each rigid group's angular
        momentum), a held current onto its limit.
    guard : casadi.Function
        (xs, t, P) -> (g, selector, dg/dt), one entry per guard.
    guard_map : casadi.Function
        ``guard`` g-values mapped over the ``n_grid`` chunk grid (compiled C
        where a compiler is available).
    output_map : casadi.Function
        (XS, T, P) -> outputs, mapped over :data:`OUTPUT_BATCH` points
        (compiled C where a compiler is available).
    integ_grid : casadi.Function
        CVODES over [t0, t0+T] returning ``n_grid`` equally spaced states.
    integ_one : casadi.Function
        CVODES over [t0, t0+T] returning the end state.
    step : casadi.Function
        (xs0, [t0, T], P) -> (X, G): ``integ_grid`` and ``guard_map`` in one call.
    stepper : Stepper or None
        Compiled ROS3P stepper of this mode (:mod:`kilnctl.model.stepper`),
        None without a C compiler.
    guards : list of Guard
        Guard declarations (kind, component, targets).

    Notes
    -----
    ``guard_map``, ``output_map``, ``integ_grid``, ``integ_one`` and ``step``
    serve the CVODES engine only: for a mode with a compiled stepper they are
    built when first asked for (most runs never do), by ``make_cvodes``.
    """

    mode: tuple
    rhs: ca.Function
    output: ca.Function
    project: ca.Function
    guard: ca.Function
    stepper: object
    guards: list
    make_cvodes: Callable[[], dict] = field(repr=False, compare=False)
    _cvodes: dict | None = field(default=None, repr=False, compare=False)

    def _cvodes_part(self, name: str) -> ca.Function:
        parts = self._cvodes
        if parts is None:  # two threads may both build them: the same functions, the last one kept
            parts = self._cvodes = self.make_cvodes()
        return parts[name]

    guard_map = property(lambda self: self._cvodes_part("guard_map"))
    output_map = property(lambda self: self._cvodes_part("output_map"))
    integ_grid = property(lambda self: self._cvodes_part("integ_grid"))
    integ_one = property(lambda self: self._cvodes_part("integ_one"))
    step = property(lambda self: self._cvodes_part("step"))


class Plant:
    """A plant structure assembled from named components.

    Parameters
    ----------
    components : sequence of str
        Component names, in phase order (see :func:`kilnctl.model.build_plant`).
    options : dict
        Values of the string options (``friction_law`` ...).
    n_grid : int, default 500
        Output points per integrator call.
    rtol, atol : float
        CVODES relative tolerance and absolute tolerance on scaled states.
    compile : bool, default True
        Compile guards and outputs to C (cached on disk, see
        :mod:`kilnctl.model.compiled`); the numbers are the same either way.

    Raises
    ------
    ModelError
        Unknown component, a missing required component, or a state claimed
        twice.
    """

    def __init__(self, components, options: dict, n_grid: int = 500, rtol: float = 1e-8, atol: float = 1e-9,
                 compile: bool = True):
        names = list(components)
        for nm in names:
            if nm not in REGISTRY:
                raise ModelError(f"unknown component {nm!r}: {close_matches_hint(nm, REGISTRY)}")
        if len(set(names)) != len(names):
            raise ModelError(f"component list has duplicates: {names}")
        for nm in names:
            for req in REGISTRY[nm].requires:
                if req not in names:
                    raise ModelError(f"component {nm!r} needs component {req!r}: add it to the list")
        self.names = tuple(names)
        self.options = dict(options)
        #: numeric parameters in the order of every mode's parameter vector, fixed when the plant is made (a
        #: component registered later adds parameters to new plants, not to this one)
        self.numeric_names = numeric_names()
        self.components: list[Component] = [REGISTRY[nm]() for nm in names]
        self.spec = ModelSpec()
        for c in self.components:
            c.declare(self.spec)
        self.state_names = tuple(s.name for s in self.spec.states)
        self.scales = np.array([s.scale for s in self.spec.states])
        self.node_names = [n.name for n in self.spec.nodes]
        self.moded = [c for c in self.components if c.modes]
        self.n_grid = int(n_grid)
        self.rtol, self.atol = float(rtol), float(atol)
        self._cache: dict[tuple, ModeFunctions] = {}
        self._output_names: tuple[str, ...] | None = None
        self.build_seconds = 0.0
        self.compile = bool(compile)
        self.compiled = False

    # --- numeric helpers ----------------------------------------------------
    def param_vector(self, params: Parameters) -> np.ndarray:
        """Numeric parameter vector in :attr:`numeric_names` order."""
        return np.array([params[n] for n in self.numeric_names], dtype=float)

    def initial(self, params: Parameters) -> tuple[np.ndarray, tuple]:
        """Initial scaled state and mode at t = 0.

        Parameters
        ----------
        params : Parameters

        Returns
        -------
        xs0 : ndarray
            Scaled initial state.
        mode0 : tuple of str
            Initial mode of each moded component.
        """
        x0 = {n: 0.0 for n in self.state_names}
        for c in self.components:
            x0.update(c.initial_state(params))
        mode0 = tuple(c.initial_mode(params, x0) for c in self.moded)
        xs0 = np.array([x0[n] for n in self.state_names]) / self.scales
        return xs0, mode0

    def mode_dict(self, mode: tuple) -> dict[str, str]:
        """Map a mode tuple to {component name: mode}."""
        return {c.name: m for c, m in zip(self.moded, mode)}

    # --- symbolic build -------------------------------------------------------
    def equations(self, mode: tuple) -> tuple[Eqs, ca.SX, ca.SX, SymParams]:
        """Build the symbolic equations of one mode.

        Returns
        -------
        e : Eqs
        xs : casadi.SX
            Scaled state symbol.
        t : casadi.SX
            Time symbol.
        sp : SymParams
        """
        sp = SymParams(self.options, self.numeric_names)
        xs = ca.SX.sym("xs", len(self.state_names))
        t = ca.SX.sym("t")
        x = {n: xs[i] * self.scales[i] for i, n in enumerate(self.state_names)}
        e = Eqs(sp, x, t)
        md = self.mode_dict(mode)
        for c in self.components:
            c.signals(e, md.get(c.name))
        for c in self.components:
            c.loads(e, md.get(c.name))
        e.assemble(self.node_names)
        for c in self.components:
            c.finish(e, md.get(c.name))
        missing = [n for n in self.state_names if n not in e.rates]
        if missing:
            raise ModelError(f"no component sets the rate of states {missing}")
        if e.controls:
            e.solve_controls(xs, self.scales, self.state_names)
        return e, xs, t, sp

    @property
    def output_names(self) -> tuple[str, ...]:
        """Names of the output signals (the same in every mode)."""
        if self._output_names is None:
            xs0 = tuple(c.modes[0] for c in self.moded)
            e, *_ = self.equations(xs0)
            self._output_names = tuple(e.outputs)
        return self._output_names

    def functions(self, mode: tuple) -> ModeFunctions:
        """Compiled functions of a mode combination (built once, then cached)."""
        mf = self._cache.get(mode)
        if mf is None:
            t_start = time.perf_counter()
            mf = self._build(mode)
            self._cache[mode] = mf
            self.build_seconds += time.perf_counter() - t_start
        return mf

    def _build(self, mode: tuple) -> ModeFunctions:
        e, xs, t, sp = self.equations(mode)
        P = sp.vector
        f = ca.vertcat(*[e.rates[n] / self.scales[i] for i, n in enumerate(self.state_names)])
        rhs = ca.Function("rhs", [xs, t, P], [f])
        g = ca.vertcat(*[gd.expr for gd in e.guards]) if e.guards else ca.SX(0, 1)
        sel = ca.vertcat(*[(gd.selector if gd.selector is not None else ca.SX(1)) for gd in e.guards]) \
            if e.guards else ca.SX(0, 1)
        gdot = ca.jtimes(g, xs, f) + ca.jacobian(g, t) if e.guards else ca.SX(0, 1)
        guard = ca.Function("guard", [xs, t, P], [g, sel, gdot])
        names = self.output_names
        extra = [n for n in e.outputs if n not in names]
        if extra or len(e.outputs) != len(names):
            raise ModelError(f"mode {mode} defines outputs {sorted(e.outputs)}, expected {sorted(names)}")
        y = ca.vertcat(*[e.outputs[n] for n in names])
        out = ca.Function("out", [xs, t, P], [y])
        proj = ca.vertcat(*[e.projection.get(nm, e.x[nm]) / self.scales[i]
                            for i, nm in enumerate(self.state_names)])
        project = ca.Function("project", [xs, t, P], [proj])
        stepper = build_stepper(f, xs, t, P, g, y, sel, gdot, proj) if self.compile else None
        if stepper is not None:
            self.compiled = True

        def make_cvodes():
            t_start = time.perf_counter()
            parts = self._cvodes_functions(e, xs, t, P, f, g, out, stepper)
            if stepper is not None:  # built after the mode: counted as build time of the run that asks
                self.build_seconds += time.perf_counter() - t_start
            return parts

        mf = ModeFunctions(mode, rhs, out, project, guard, stepper, list(e.guards), make_cvodes)
        if stepper is None:  # the CVODES engine will run this mode: build (and compile) its functions now
            mf._cvodes = make_cvodes()
        return mf

    def _cvodes_functions(self, e, xs, t, P, f, g, out, stepper) -> dict:
        """The CVODES engine's functions of one mode (see :class:`ModeFunctions`)."""
        n = self.n_grid
        guard_g = ca.Function("guard_g", [xs, t, P], [g])
        guard_map = guard_g.map(n)
        output_map = out.map(OUTPUT_BATCH)
        tau = ca.SX.sym("tau")
        pint = ca.SX.sym("pint", 2)  # t0, T
        ode = pint[1] * ca.substitute(f, t, pint[0] + tau * pint[1])
        dae = {"x": xs, "t": tau, "p": ca.vertcat(pint, P), "ode": ode}
        opts = {"abstol": self.atol, "reltol": self.rtol, "max_num_steps": 20000}
        integ_grid = ca.integrator("ig", "cvodes", dae, 0.0, list(np.linspace(0, 1, n + 1)[1:]), opts)
        integ_one = ca.integrator("i1", "cvodes", dae, 0.0, 1.0, opts)
        if self.compile and stepper is None:  # the CVODES path's maps, compiled when no stepper is
            Xs, Ts = ca.MX.sym("X", xs.numel(), n), ca.MX.sym("T", 1, n)
            Ps = ca.MX.sym("P", P.numel())
            if e.guards:
                guard_map, _ = compile_function(
                    ca.Function(f"guards_{len(self.state_names)}x{n}", [Xs, Ts, Ps], [guard_map(Xs, Ts, Ps)]))
            Xo, To = ca.MX.sym("X", xs.numel(), OUTPUT_BATCH), ca.MX.sym("T", 1, OUTPUT_BATCH)
            output_map, self.compiled = compile_function(
                ca.Function(f"outputs_{len(self.state_names)}x{OUTPUT_BATCH}", [Xo, To, Ps],
                            [output_map(Xo, To, Ps)]))
        # one call per chunk: integrate, then evaluate every guard on the grid
        x0m, pm, Pm = ca.MX.sym("x0", xs.numel()), ca.MX.sym("pint", 2), ca.MX.sym("P", P.numel())
        Xm = integ_grid(x0=x0m, p=ca.vertcat(pm, Pm))["xf"]
        Tm = pm[0] + pm[1] * ca.DM(np.linspace(0, 1, n + 1)[1:]).T
        step = ca.Function("step", [x0m, pm, Pm], [Xm, guard_map(Xm, Tm, Pm)])
        return {"guard_map": guard_map, "output_map": output_map, "integ_grid": integ_grid, "integ_one": integ_one,
                "step": step}


@lru_cache(maxsize=64)
def _plant_cached(names: tuple, options: tuple, n_grid: int, rtol: float, atol: float, registry: int) -> Plant:
    # ``registry`` (REGISTRY.version) is only part of the key: a plant made before a component was registered
    # or replaced is not reused (its parameter vector and component classes are those of then)
    return Plant(names, dict(options), n_grid=n_grid, rtol=rtol, atol=atol)


def get_plant(names, params: Parameters, n_grid: int = 500, rtol: float = 1e-8, atol: float = 1e-9) -> Plant:
    """Return the (cached) plant structure for components and options.

    Parameters
    ----------
    names : sequence of str
        Component names.
    params : Parameters
        Only the string options are used (they select the structure).
    n_grid : int
        Output points per integrator call.
    rtol, atol : float
        Integrator tolerances.

    Returns
    -------
    Plant
    """
    options = tuple((k, params[k]) for k in option_names())
    return _plant_cached(tuple(names), options, int(n_grid), float(rtol), float(atol),
                         getattr(REGISTRY, "version", len(REGISTRY)))
