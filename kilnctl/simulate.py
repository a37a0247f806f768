"""Hybrid (mode-switching) simulation of the kiln drive.

Each mode combination is smooth.  By default it is integrated by a compiled
ROS3P Rosenbrock stepper (:mod:`kilnctl.model.stepper`: CasADi-generated C for
the right-hand side, Jacobian and guards, driven by ``rosenbrock.c``) that
checks every guard at every grid point k*dt (on the step's interpolant) and at
every step end, and locates a crossing by Illinois root finding on real
integrator steps, to ``event_tol`` seconds.
The alternative (``method='cvodes'``) integrates with CVODES (BDF) over
chunks and samples the guards every ``dt``.  The mode then switches and, if the new mode is
itself left at once, the switch cascades; a zero-time cycle of modes is
resolved by the component's Filippov sliding mode (the burden's ``held``
mode) or reported as :class:`EventStormError` naming the mode pair.

Both engines check the guards at least every ``dt`` seconds, so an excursion
shorter than ``dt`` that starts and ends between two checks is not seen
(choose ``dt`` below the shortest effect you care about).
Outputs are sampled on the global grid k*dt plus every event point (twice:
before and after the switch).
"""

from __future__ import annotations

import math
import time
from collections import Counter
from collections.abc import Mapping

import numpy as np

from .errors import EventStormError, ModelError, SimulationError, close_matches_hint
from .gains import resolve_gains
from .model import Guard, component_names, get_plant
from .model.stepper import FIRST_STEP, GUARD_EPS, RUNAWAY, STATUS
from .params import Parameters
from .response import Event, Response

# resolve_gains lives in kilnctl.gains; it stays importable from here for existing callers
__all__ = ["simulate", "resolve_gains", "plant_structure", "DEFAULT_DT"]

#: a guard on its boundary counts as crossed at once when its rate takes it past -GUARD_EPS within
#: this time [s]; slower (grazing) guards are left to the integrator's crossing detection
GUARD_LOOKAHEAD = 1e-3
#: most samples the compiled stepper returns per call; when full, the run continues from the last accepted
#: step (results do not depend on this number: tests/test_differential.py)
OUTPUT_BUFFER = 16384
#: mode switches the recording buffers have room for from the start (more make them grow: results do not depend
#: on this number)
RESERVED_EVENTS = 64
#: default output and guard-sampling step per model [s] (the one definition: the sweeps and the measurement
#: runner use it; the compiled stepper gets it as its output grid)
DEFAULT_DT = {"macro": 5e-3, "micro": 1e-3}


def plant_structure(params: Parameters, model: str = "macro", effects=(), remove=(), components=None):
    """Split the structure arguments of :func:`simulate` into component names, parameters and a model label.

    Parameters
    ----------
    params : Parameters
        Values of the plant [units of :data:`kilnctl.params.SPECS`].
    model : str
        Model preset, used when ``components`` is None.
    effects, remove : sequence of str
        Components added to or taken out of ``model``.
    components : sequence of str or Structure, optional
        The full component list, or a :class:`kilnctl.structure.Structure`
        (used through its methods: this module sits below it).

    Returns
    -------
    names : tuple of str
        Components of the plant.
    params : Parameters
        With a Structure's effect options set (``friction_law`` ...).
    model : str
        The preset's name, or ``'custom'`` for a bare component list.

    Raises
    ------
    ModelError
        Unknown model or component, or a Structure given with ``effects`` or ``remove``.
    """
    if components is None:
        return component_names(model, effects, remove), params, model
    if hasattr(components, "components") and hasattr(components, "apply"):  # a kilnctl.structure.Structure
        if effects or remove:
            raise ModelError("give the effects inside the Structure (Structure.with_effects), not as effects= "
                             "or remove= beside it")
        return components.components(), components.apply(params), components.model
    if isinstance(components, str):
        raise ModelError(f"components = {components!r} must be a sequence of component names or a Structure")
    return tuple(components), params, "custom"


def _check_size(names, params, t_end, dt, max_events, max_samples, n_grid, rtol, atol, **names_for_message):
    """Refuse a run whose recorded output would exceed ``max_samples``, before any design or integration."""
    from .budget import check_run_size

    # the structure only depends on the string options; gains='given' is what the run itself uses
    plant = get_plant(names, params if params.gains == "given" else params.replace(gains="given"),
                      n_grid=n_grid, rtol=rtol, atol=atol)
    check_run_size(t_end, dt, len(plant.state_names), len(plant.output_names), len(plant.moded),
                   max_events=max_events, max_samples=max_samples, **names_for_message)


def _check_horizon(t_end, dt):
    for name, v in (("t_end", t_end), ("dt", dt)):
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or v <= 0:
            raise SimulationError(f"{name} = {v!r} must be a finite number of seconds > 0")
    if dt > t_end:
        raise SimulationError(f"dt = {dt} s exceeds t_end = {t_end} s: choose a smaller output step")


def _check_tolerances(**values):
    """Refuse a tolerance or step that is not a finite number > 0 (None: the default) before the plant is built.

    rtol = -1 ran and returned a result; a string ended in a TypeError of the compiled stepper; max_step = -1 was
    reported as "the loop is probably unstable with these gains or parameters".
    """
    for name, v in values.items():
        if v is None and name == "max_step":
            continue
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or v <= 0:
            raise SimulationError(f"{name} = {v!r} must be a finite number > 0")


def _initial_rows(t_end, dt) -> int:
    """Samples the recording buffers have room for at the start: the grid, :data:`RESERVED_EVENTS` mode
    switches (two samples each) and some slack, so that most runs never grow them."""
    return int(t_end / dt) + 2 * RESERVED_EVENTS + 256


def _call_rows(t, t_end, dt, hmax) -> int:
    """Output rows to give one compiled-stepper call from time t: :data:`OUTPUT_BUFFER`, or fewer where the
    call could not fill it.

    The stepper caps its step at half its buffer (``0.5*max_out*dt``) and stops early when the buffer is
    full, so a smaller buffer changes the integration unless both are out of reach: this gives at least
    the grid points left after t (with a margin of 8) and at least ``2*hmax/dt + 1`` rows, and the full
    buffer whenever the cap would bind at that size.  The buffer given is always as large as the number
    passed, whatever these counts: they only decide whether the results are those of the full buffer.
    """
    if hmax > 0.5 * OUTPUT_BUFFER * dt:
        return OUTPUT_BUFFER
    k0 = math.floor(t / dt * (1 + 1e-14)) + 1  # first grid index after t, as rosenbrock.c counts it
    left = math.floor(t_end * (1 + 1e-15) / dt) - k0 + 1 + 8
    return int(min(OUTPUT_BUFFER, max(left, math.ceil(2 * hmax / dt) + 1)))


class _ModeArrays(Mapping):
    """Mode of each moded component at each sample (component -> array of str), spelled out when first read.

    A calibration runs the model thousands of times and reads only its outputs: the label arrays (one string
    per sample and component) cost about as much as the rest of the run's Python bookkeeping (0.16 ms of a
    5 ms run, profiled on the diagnosis tests), so each is built on its first access from the segments'
    mode codes and lengths, then kept.
    """

    def __init__(self, labels: dict, seg_mode, seg_len):
        self._labels, self._seg_mode, self._seg_len = labels, seg_mode, seg_len
        self._arrays = {}

    def __getitem__(self, name):
        if name not in self._arrays:
            # each segment's label repeated over its samples: the same as labels[code], without a gather per sample
            self._arrays[name] = np.repeat(self._labels[name][self._seg_mode], self._seg_len)
        return self._arrays[name]

    def __iter__(self):
        return iter(self._labels)

    def __len__(self):
        return len(self._labels)


class _Engine:
    """One simulation run: state, mode, recorded points and events."""

    def __init__(self, plant, P, event_tol, max_events):
        self.plant = plant
        self.P = P
        self.event_tol = event_tol
        self.max_events = max_events
        self.events: list[Event] = []
        self.pairs: Counter = Counter()
        # recorded samples: times and scaled states as rows (the compiled stepper's layout, which writes into
        # these buffers directly), the first n_rec rows used; a run of consecutive samples in one mode is a
        # segment: its mode code and length
        self.t_buf = np.empty(0)
        self.x_buf = np.empty((0, len(plant.state_names)))
        self.n_rec = 0
        self.seg_mode: list[int] = []
        self.seg_len: list[int] = []
        self.mode_index: dict[tuple, int] = {}
        self.n_steps = 0
        self.moded_index = {c.name: i for i, c in enumerate(plant.moded)}  # place of a component in a mode

    # --- recording ------------------------------------------------------------
    def _mid(self, mode):
        if mode not in self.mode_index:
            self.mode_index[mode] = len(self.mode_index)
        return self.mode_index[mode]

    def reserve(self, k: int) -> None:
        """Make room for k more samples in the recording buffers."""
        need = self.n_rec + int(k)
        if need <= len(self.t_buf):
            return
        cap = max(need, 2 * len(self.t_buf))
        t_buf, x_buf = np.empty(cap), np.empty((cap, self.x_buf.shape[1]))
        t_buf[:self.n_rec], x_buf[:self.n_rec] = self.t_buf[:self.n_rec], self.x_buf[:self.n_rec]
        self.t_buf, self.x_buf = t_buf, x_buf

    def _segment(self, mf, k: int) -> None:
        """Count k samples just written after the used rows as recorded in mode ``mf.mode``."""
        if k == 0:
            return
        mid = self._mid(mf.mode)
        if self.seg_mode and self.seg_mode[-1] == mid:
            self.seg_len[-1] += k
        else:
            self.seg_mode.append(mid)
            self.seg_len.append(k)
        self.n_rec += k

    def record(self, mf, t, X):
        """Record times t (1-d) and scaled states X (nx x k) in mode ``mf.mode``."""
        k = X.shape[1]
        if k == 0:
            return
        self.reserve(k)
        u = self.n_rec
        self.t_buf[u:u + k] = t
        self.x_buf[u:u + k] = X.T
        self._segment(mf, k)

    def outputs(self):
        """Times, scaled states (nx x N), mode codes and outputs (ny x N) of every recorded sample."""
        N = self.n_rec
        T, XR = self.t_buf[:N].copy(), self.x_buf[:N]  # T is kept by the response: not a view of the buffer
        M = np.repeat(np.array(self.seg_mode, dtype=np.intp), self.seg_len)
        Y = np.empty((N, len(self.plant.output_names)))  # rows, as the compiled outputs write them
        modes = {mid: mode for mode, mid in self.mode_index.items()}
        steppers = {mid: self.plant.functions(mode).stepper for mid, mode in modes.items()}
        others = {mid for mid, st in steppers.items() if st is None}
        # each sample is evaluated on its own, so the numbers do not depend on how samples are grouped into calls:
        # one call per segment, written in place; with many more segments than modes (a run that keeps
        # switching), one call per mode on its samples gathered by a stable sort, scattered back once
        if len(self.seg_mode) <= 4 * len(modes) + 32:
            a = 0
            for mid, k in zip(self.seg_mode, self.seg_len):
                if steppers[mid] is not None:
                    steppers[mid].outputs_rows(self.P, T[a:a + k], XR[a:a + k], out=Y[a:a + k])
                a += k
        else:
            order = np.argsort(M, kind="stable")
            bounds = np.concatenate([[0], np.cumsum(np.bincount(M, minlength=len(modes)))])
            Ts, Xs, Ys = T[order], XR[order], np.empty_like(Y)
            for mid, st in steppers.items():
                a, b = bounds[mid], bounds[mid + 1]
                if st is not None:
                    st.outputs_rows(self.P, Ts[a:b], Xs[a:b], out=Ys[a:b])
            Y[order] = Ys  # rows of the modes without a stepper are filled below
        X = XR.T
        for mid in sorted(others):  # modes without a compiled stepper: CasADi's batched output map
            idx = np.nonzero(M == mid)[0]
            fmap = self.plant.functions(modes[mid]).output_map
            B = fmap.size2_in(0)
            for s0 in range(0, len(idx), B):
                sl = idx[s0:s0 + B]
                k = len(sl)
                Xb = np.zeros((X.shape[0], B))
                Tb = np.full(B, T[sl[-1]])
                Xb[:, :k], Tb[:k] = X[:, sl], T[sl]
                Xb[:, k:] = X[:, sl[-1:]]
                Y[sl] = np.asarray(fmap(Xb, Tb, self.P))[:, :k].T
        return T, X, M, Y.T

    # --- guards -------------------------------------------------------------------
    def guards(self, mf, xs, t):
        if mf.stepper is not None:
            return mf.stepper.guard(self.P, xs, t)
        g, sel, gdot = mf.guard(xs, t, self.P)
        return np.asarray(g).ravel(), np.asarray(sel).ravel(), np.asarray(gdot).ravel()

    @staticmethod
    def first_violated(evaluated, tol=1e-10):
        """Index of the first violated guard of evaluated guards ``(g, sel, gdot)`` (None: no guards), or None.

        A guard is violated when it is below -GUARD_EPS, or when it is on its
        boundary (within ``tol``) and falling fast enough to pass -GUARD_EPS
        within :data:`GUARD_LOOKAHEAD` seconds.  A guard that sits on its
        boundary with a rate at round-off level (a grazing switch, where the
        rate's sign is noise) is left to the integrator, which switches when
        the guard really crosses; judging such a sign at the instant made
        the current limit alternate with free running without time passing.
        """
        if evaluated is None:
            return None
        g, _, gdot = evaluated
        # as Python floats (the same doubles): cheaper to compare one by one than numpy scalars
        for j, (gj, rj) in enumerate(zip(np.asarray(g).tolist(), np.asarray(gdot).tolist())):
            if gj < -GUARD_EPS or (gj <= tol and rj * GUARD_LOOKAHEAD < -GUARD_EPS):
                return j
        return None

    def apply(self, mode, mf, j, sel):
        """Mode after guard j of mode fires, with the guards' selectors ``sel`` at that point."""
        gd = mf.guards[j]
        target = gd.target
        if gd.alt_target is not None:
            target = gd.target if sel[j] >= 0 else gd.alt_target
        i = self.moded_index[gd.component]
        return mode[:i] + (target,) + mode[i + 1:], gd, i

    def settle(self, mode, xs, t, first=None):
        """Switch modes from (mode, xs) at time t until no guard is violated.

        Returns
        -------
        mode, xs, list of (guard, old mode, new mode)
        """
        plant = self.plant
        switched = []
        visited = [mode]
        tried_sliding = set()
        mf = plant.functions(mode)
        ev = self.guards(mf, xs, t) if mf.guards else None  # guards, selectors and rates: once per mode
        j = first if first is not None else self.first_violated(ev)
        for _hop in range(32):
            if j is None:
                return mode, xs, switched
            rate = float(ev[2][j])
            new, gd, i = self.apply(mode, mf, j, ev[1])
            if new in visited:
                comp = plant.moded[i]
                start = visited.index(new)
                cycle = frozenset(m[i] for m in visited[start:]) | {new[i]}
                sliding = comp.sliding_mode(cycle)
                key = (i, sliding)
                if sliding is None or key in tried_sliding:
                    raise EventStormError(
                        f"component {comp.name!r} switches between modes {sorted(cycle)} at t = {t:.6g} s without "
                        "time passing, and no sliding mode resolves it; check the parameters of that component")
                tried_sliding.add(key)
                new = mode[:i] + (sliding,) + mode[i + 1:]
                gd = Guard("sliding_mode", comp.name, gd.expr, sliding)
            switched.append((gd, mode, new, rate))
            visited.append(new)
            mode = new
            mf = plant.functions(mode)
            xs = (mf.stepper.project(self.P, xs, t) if mf.stepper is not None
                  else np.asarray(mf.project(xs, t, self.P)).ravel())
            ev = self.guards(mf, xs, t) if mf.guards else None
            j = self.first_violated(ev)
        raise EventStormError(f"more than 32 mode switches at t = {t:.6g} s without time passing "
                              f"(last: {switched[-1][1]} -> {switched[-1][2]})")

    def locate(self, mf, j, t0, x0, t1, g0, g1):
        """Time and state where guard j crosses zero in (t0, t1] (Illinois method).

        The compiled stepper has its own Illinois iteration in rosenbrock.c.  The two are kept apart on
        purpose: each engine locates events its own way, so when they agree (tests/test_engines_agree.py,
        tests/test_differential.py) neither shares the other's mistakes.
        """
        P = self.P

        def state_at(tt):
            if tt <= t0:
                return x0
            r = mf.integ_one(x0=x0, p=np.concatenate([[t0, tt - t0], P]))
            return np.asarray(r["xf"]).ravel()

        def gval(tt, xx):
            return float(np.asarray(mf.guard(xx, tt, P)[0]).ravel()[j])

        a, fa = t0, max(g0, 1e-300)
        b, fb = t1, g1
        xb = None
        side = 0
        for _ in range(100):
            if b - a <= self.event_tol:
                break
            c = b - fb * (b - a) / (fb - fa)
            if not (a < c < b):
                c = 0.5 * (a + b)
            xc = state_at(c)
            fc = gval(c, xc)
            if fc > 0:
                a, fa = c, fc
                if side == -1:
                    fb *= 0.5
                side = -1
            else:
                b, fb, xb = c, fc, xc
                if side == 1:
                    fa *= 0.5
                side = 1
        if xb is None:
            xb = state_at(b)
        return b, xb

    def log(self, switched, t):
        """Append the switches of one settle() call to the event list."""
        for gd, m_from, m_to, rate in switched:
            i = self.moded_index[gd.component]
            self.events.append(Event(t, gd.kind, gd.component, m_from[i], m_to[i], rate))
            self.pairs[(gd.component, m_from[i], m_to[i])] += 1

    # --- main loop -------------------------------------------------------------
    def run(self, xs, mode, t_end, advance):
        """The stepping loop of both engines: settle the initial mode, then advance and switch until t_end.

        ``advance(mf, t, xs)`` integrates mode ``mf`` from (t, xs) for one engine call and returns
        ``(t, xs, event)``: where it stopped, and ``(te, xe, j)`` when guard j fired at (te, xe), else
        None; it records the samples it passed.
        """
        plant = self.plant
        t = 0.0
        mode, xs, switched = self.settle(mode, xs, t)
        self.log(switched, t)
        self.record(plant.functions(mode), np.array([t]), xs[:, None])
        while t < t_end * (1 - 1e-12):
            mf = plant.functions(mode)
            t, xs, event = advance(mf, t, xs)
            if event is not None:
                mode, xs, t = self.switch(mode, mf, *event)
        return mode

    def ros3p(self, t_end, dt, rtol, atol, hmax):
        """``advance`` on the compiled ROS3P steppers (guards checked after every step, crossings located in C).

        The C stepper locates a crossing with its own Illinois iteration and :meth:`locate` does it again in
        Python for CVODES: kept apart on purpose, so the two engines check each other
        (tests/test_engines_agree.py) instead of sharing one root finder's mistakes.
        """
        h = 0.0  # step size carried across calls; 0 after a switch: start again from FIRST_STEP

        def advance(mf, t, xs):
            nonlocal h
            if mf.stepper is None:
                raise SimulationError("method 'ros3p' needs a C compiler (gcc or $CC); use method='cvodes'")
            # the stepper writes its samples straight into the recording buffers
            rows = _call_rows(t, t_end, dt, hmax)
            self.reserve(rows)
            u = self.n_rec
            r = mf.stepper.run(self.P, t, t_end, xs, dt, rtol, atol, hmax, h if h > 0 else FIRST_STEP,
                               self.event_tol, max_out=rows, runaway=RUNAWAY, guard_eps=GUARD_EPS,
                               out_t=self.t_buf[u:u + rows], out_x=self.x_buf[u:u + rows])
            st = r["status"]
            if st == -6:
                self.check_bounded(np.zeros((len(xs), 0)), r["x_ev"], r["t_ev"], mf.mode)
            self._segment(mf, len(r["t"]))
            self.n_steps += r["n_steps"]
            if st < 0:
                raise SimulationError(
                    f"integrator failed after t = {t:.6g} s in mode {self.plant.mode_dict(mf.mode)}: "
                    f"{STATUS.get(st, st)} (the loop is probably unstable with these gains or parameters)")
            h = r["h"]
            if st == 0:  # reached t_end
                return t_end, r["x_ev"], None
            if st == 2:  # output buffer full: continue from the last accepted step
                return r["t_ev"], r["x_ev"], None
            h = 0.0
            return r["t_ev"], r["x_ev"], (r["t_ev"], r["x_ev"], r["j_ev"])

        return advance

    def cvodes(self, t_end, dt):
        """``advance`` on CVODES chunks of n_grid*dt seconds (guards sampled on the output grid)."""
        n = self.plant.n_grid
        frac = np.linspace(0.0, 1.0, n + 1)[1:]
        T_long = n * dt

        def advance(mf, t, xs):
            # chunks start on the global grid k*dt (after an event: one step to the next grid point)
            t_grid = math.ceil(t / dt * (1 - 1e-14)) * dt
            partial = t_grid - t > 1e-12 * max(1.0, t)
            T = min(t_grid - t, t_end - t) if partial else min(T_long, t_end - t)
            try:
                if partial:
                    X = np.asarray(mf.integ_one(x0=xs, p=np.concatenate([[t, T], self.P]))["xf"])
                    Gd = self.guards(mf, X[:, 0], t + T)[0][:, None]
                else:
                    Xd, Gd = mf.step(xs, [t, T], self.P)
                    X = np.asarray(Xd)
            except RuntimeError as exc:
                lines = str(exc).splitlines()
                why = next((ln.strip() for ln in lines if "CVode returned" in ln or "CV_" in ln), lines[-1])
                hint = (" (CVODES gave up: the loop is probably unstable with these gains or parameters)"
                        if "CV_" in str(exc) else "")
                raise SimulationError(f"integrator failed at t = {t:.6g} s in mode "
                                      f"{self.plant.mode_dict(mf.mode)}{hint}: {why}") from None
            tg = np.array([t + T]) if partial else t + T * frac
            if mf.guards:
                G = np.asarray(Gd)
                bad = np.nonzero((G < -GUARD_EPS).any(axis=0))[0]
            else:
                bad = ()
            # only the samples before the first guard crossing belong to the run: the chunk goes on in a mode
            # that no longer holds, where a state may run away (a motor friction left in slip_neg after the
            # shaft stopped) -- the compiled stepper likewise checks only accepted steps before an event
            k = int(bad[0]) if len(bad) else X.shape[1]
            if not np.all(np.isfinite(X[:, :k])):
                raise SimulationError(f"state became non-finite after t = {t:.6g} s in mode "
                                      f"{self.plant.mode_dict(mf.mode)}: the parameters make the plant unstable")
            self.check_bounded(X[:, :k], X[:, k - 1] if k else xs, t, mf.mode)
            if len(bad) == 0:
                self.record(mf, tg, X)
                return tg[-1], X[:, -1].copy(), None
            t_left = t if k == 0 else tg[k - 1]
            x_left = xs if k == 0 else X[:, k - 1]
            g_left = self.guards(mf, x_left, t_left)[0]
            best = None
            for j in np.nonzero(G[:, k] < -GUARD_EPS)[0]:
                te, xe = self.locate(mf, int(j), t_left, x_left, tg[k], g_left[j], G[j, k])
                if best is None or te < best[0]:
                    best = (te, xe, int(j))
            if not np.all(np.isfinite(best[1])):
                raise SimulationError(f"state became non-finite after t = {t:.6g} s in mode "
                                      f"{self.plant.mode_dict(mf.mode)}: the parameters make the plant unstable")
            self.check_bounded(np.zeros((len(xs), 0)), best[1], best[0], mf.mode)
            self.record(mf, tg[:k], X[:, :k])
            return best[0], best[1], best

        return advance

    def switch(self, mode, mf, te, xe, j):
        """Guard j of ``mode`` fired at (te, xe): record the point on both sides of the switch, settle
        the cascade, log it; return the new mode, its (projected) state and te.  Shared by both engines."""
        self.record(mf, np.array([te]), xe[:, None])
        new_mode, xe, switched = self.settle(mode, xe, te, first=j)
        self.log(switched, te)
        if len(self.events) > self.max_events:
            self._storm(te)
        self.record(self.plant.functions(new_mode), np.array([te]), xe[:, None])
        return new_mode, xe, te

    def check_bounded(self, X, x_end, t, mode):
        """Raise if a (scaled) state ran away: beyond RUNAWAY times its nominal scale."""
        big = np.abs(x_end) > RUNAWAY
        if X.size:
            big |= (np.abs(X) > RUNAWAY).any(axis=1)
        if big.any():
            i = int(np.nonzero(big)[0][0])
            raise SimulationError(
                f"state {self.plant.state_names[i]!r} ran away (beyond {RUNAWAY:.0e} times its nominal scale "
                f"{self.plant.scales[i]:g}) after t = {t:.6g} s in mode {self.plant.mode_dict(mode)}: the loop is "
                "unstable with these gains or parameters")

    def _storm(self, te):
        (comp, a, b), cnt = self.pairs.most_common(1)[0]
        raise EventStormError(
            f"more than max_events = {self.max_events} mode switches by t = {te:.6g} s; most frequent: "
            f"component {comp!r} {a} -> {b} ({cnt} times). Raise max_events if this is real, or check the "
            "parameters of that component")


def simulate(params: Parameters | None = None, model: str = "macro", t_end: float = 40.0, *,
             effects=(), remove=(), components=None, dt: float | None = None,
             rtol: float = 1e-7, atol: float = 1e-8, event_tol: float = 1e-9,
             max_events: int = 5000, n_grid: int = 500, initial=None, initial_mode=None,
             method: str = "auto", max_step: float | None = None, max_samples: int | None = None,
             held: bool = False) -> Response:
    """Simulate a start-up of the kiln drive on the nonlinear hybrid plant.

    Parameters
    ----------
    params : Parameters, optional
        Parameter set (defaults: the paper's Table 1).  With
        ``gains = 'design'`` the PID gains come from the root-locus design.
    model : {'macro', 'micro'}, default 'macro'
        The paper's macro model (rigid reducer) or micro model (coupling,
        pinion, mesh with backlash).
    t_end : float, default 40.0
        Simulated time [s], > 0.
    effects : sequence of str
        Components to add to the model (``second_motor``,
        ``drivetrain_compliance`` ...).
    remove : sequence of str
        Components to take out (``current_limit`` ...).
    components : sequence of str or Structure, optional
        The full component list, or a :class:`kilnctl.structure.Structure`
        (its components, its effects' options, its model), instead of
        ``model``/``effects``/``remove``.
    dt : float, optional
        Output and guard-sampling step [s] (default 5 ms macro, 1 ms micro).
    rtol, atol : float, default 1e-7, 1e-8
        Integrator tolerances (atol on states scaled to order one).  At the
        defaults, peak current and peak stress are within 2e-4 (relative) of
        CVODES at rtol 1e-10, the mode switches are the same, and event times
        agree within 5 ms (in stick-slip cycling they drift by about 1e-4 s
        per cycle, and a current read at a fixed instant inherits that drift);
        use rtol=1e-10 for event timing, where the two engines agree within
        1e-5 and 1e-5 s (``benchmarks/differential.py``, docs/benchmarks.md).
        Not on a speed loop that hunts (a speed-sensor delay from about
        15 ms with the designed gains, hundreds of current-limit hits): there
        the error grows cycle by cycle, a final current read inside a limit
        cycle was 1-8 % off and one peak stress 1.4 % low at the defaults,
        and where the hunting with mesh impacts is chaotic no tolerance gives
        a reproducible peak (the two engines part after 2-5 s even at 1e-12).
    event_tol : float, default 1e-9
        Width [s] to which a mode switch is located.
    max_events : int, default 5000
        Mode switches allowed before :class:`EventStormError`.
    method : {'auto', 'ros3p', 'cvodes'}, default 'auto'
        ``'ros3p'``: the compiled stepper (:mod:`kilnctl.model.stepper`,
        guards checked after every integrator step); ``'cvodes'``: CasADi's
        CVODES over chunks, guards sampled every ``dt``; ``'auto'``: ros3p
        when a C compiler is available.  The two agree to about 1e-6 at tight
        tolerances (tests/test_engines_agree.py, tests/test_differential.py).
    max_step : float, optional
        ``method='ros3p'`` only: largest step [s] (default 100*dt); guards are
        checked every ``dt`` on the step's interpolant whatever the step.
    n_grid : int, default 500
        ``method='cvodes'`` only: grid points per integrator call (chunks of
        n_grid*dt seconds).
    initial : dict, optional
        Initial values of states by name, in physical units (e.g.
        ``{"omega_kiln": 0.05}``); the others start as the components say.
    initial_mode : dict, optional
        Initial mode by component name (e.g. ``{"burden": "slip_pos"}``).
    held : bool, default False
        Start with the drive holding the kiln at rest (a drive switched on before the ramp, its speed loop
        balancing the kiln's load at rest, such as an unbalance): the current and the speed controller's
        integrator start where they hold it (:func:`kilnctl.model.rest.held_state`); ``initial`` still wins.
        Default: from zero current, as a drive switched on with the ramp.
    max_samples : int, optional
        Largest number of output samples (``t_end/dt`` plus two per mode
        switch) the run may record; checked before anything runs.  Default:
        the environment variable ``KILNCTL_MAX_SAMPLES`` or 1 000 000 (about
        0.4 GB for the micro model), see :mod:`kilnctl.budget`.

    Returns
    -------
    Response
        Time series of currents, speeds, burden angle and mode, torques,
        mesh force and stress, and the event list.

    Raises
    ------
    SimulationError
        Bad horizon, a run above ``max_samples``, integrator failure or an
        unstable (non-finite) run.
    EventStormError
        Mode switches without end; names the component and mode pair.
    ModelError
        Unknown model or component.
    """
    params = Parameters() if params is None else params
    Parameters.require(params)
    names, params, label = plant_structure(params, model, effects, remove, components)
    dt = DEFAULT_DT.get(label if label != "custom" else model, 1e-3) if dt is None else dt
    _check_horizon(t_end, dt)
    if method not in ("auto", "cvodes", "ros3p"):
        raise SimulationError(f"method = {method!r}: choose 'auto', 'ros3p' (compiled stepper) or 'cvodes'")
    if isinstance(max_events, bool) or not isinstance(max_events, int) or max_events < 1:
        raise SimulationError(f"max_events = {max_events!r} must be a positive integer")
    _check_tolerances(rtol=rtol, atol=atol, event_tol=event_tol, max_step=max_step)
    if isinstance(n_grid, bool) or not isinstance(n_grid, int) or n_grid < 1:
        raise SimulationError(f"n_grid = {n_grid!r} must be a positive integer")
    _check_size(names, params, t_end, dt, max_events, max_samples, n_grid, rtol, atol)
    if "pid" in names:
        params = resolve_gains(params)
    plant = get_plant(names, params, n_grid=n_grid, rtol=rtol, atol=atol)
    build0 = plant.build_seconds
    P = plant.param_vector(params)
    xs0, mode0 = plant.initial(params)
    if held:
        from .model.rest import held_state
        initial = dict(held_state(params, names), **(initial or {}))
    for name, value in (initial or {}).items():
        if name not in plant.state_names:
            raise SimulationError(f"initial state {name!r} is not a state of this plant: "
                                  f"{close_matches_hint(name, plant.state_names)}")
        if not math.isfinite(value):
            raise SimulationError(f"initial state {name!r} = {value!r} must be finite")
        i = plant.state_names.index(name)
        xs0[i] = value / plant.scales[i]
    moded = [c.name for c in plant.moded]
    for comp, m in (initial_mode or {}).items():
        if comp not in moded:
            raise SimulationError(f"initial_mode names {comp!r}, which has no modes here: "
                                  f"{close_matches_hint(comp, moded)}")
        i = moded.index(comp)
        if m not in plant.moded[i].modes:
            raise SimulationError(f"initial_mode {comp!r} = {m!r}: choose one of {plant.moded[i].modes}")
        mode0 = mode0[:i] + (m,) + mode0[i + 1:]
    eng = _Engine(plant, P, event_tol, max_events)
    eng.reserve(_initial_rows(t_end, dt))
    wall0 = time.perf_counter()
    if method == "auto":
        method = "ros3p" if plant.functions(mode0).stepper is not None else "cvodes"
    if method == "ros3p":
        hmax = 100 * dt if max_step is None else float(max_step)
        advance = eng.ros3p(float(t_end), float(dt), rtol, atol, hmax)
    else:
        advance = eng.cvodes(float(t_end), float(dt))
    eng.run(xs0, mode0, float(t_end), advance)
    T, X, _, Y = eng.outputs()
    wall = time.perf_counter() - wall0
    build = plant.build_seconds - build0
    modes = {v: k for k, v in eng.mode_index.items()}
    labels = {c.name: np.array([modes[i][ci] for i in range(len(modes))]) for ci, c in enumerate(plant.moded)}
    mode_arrays = _ModeArrays(labels, np.array(eng.seg_mode, dtype=np.intp), np.array(eng.seg_len, dtype=np.intp))
    return Response(
        t=T,
        outputs=dict(zip(plant.output_names, Y)),
        states=dict(zip(plant.state_names, X * plant.scales[:, None])),
        modes=mode_arrays,
        events=eng.events,
        params=params,
        model=label,
        components=names,
        info={"wall_s": wall - build, "build_s": build, "n_events": len(eng.events), "dt": dt,
              "rtol": rtol, "event_tol": event_tol, "compiled": plant.compiled, "method": method,
              "n_steps": eng.n_steps},
    )
