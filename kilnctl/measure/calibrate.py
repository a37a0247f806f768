"""Calibration: fit chosen parameters to a measured record by simulation-error least squares.

The model is simulated over the whole experiment for each trial parameter
set (simulation error, also called output error: the model is never reset to
the measured state), and ``scipy.optimize.least_squares`` minimises

    sum over channels c of  sum_k ((y_c[k] - yhat_c[k]) / s_c)^2

where ``s_c`` is the measured channel's standard deviation (or a given scale).
Standard errors come from the Jacobian at the optimum,
``cov = (J^T J)^-1 s^2`` with ``s^2`` the residual variance, mapped through the
parameter scaling by the delta method.

Estimator style (after pysindy): configure, ``fit``, then read the fitted
attributes, which end in ``_``; ``predict`` and ``score`` need a fit first.

>>> cal = Calibration(params, ["mu_c", "mu_s", "m_v"]).fit(record)   # doctest: +SKIP
>>> print(cal.summary())                                               # doctest: +SKIP
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field, replace

import numpy as np

from ..errors import KilnctlError, ModelError, NotFittedError, name_list
from ..params import Parameters
from ..simulate import resolve_gains
from .breakaways import BreakawayTiming
from .effects import DEFAULT_CALIBRATE, FreeParameter, free_parameter
from .evidence import score_covariance
from .io import Experiment, Measurement
from .runner import CHANNELS, ModelRun, run_model
from .stats import fit_percent

__all__ = ["Calibration", "Starts", "Horizons", "Smoothing", "default_starts", "holdout_masks", "bic", "sweep", "unspiked"]

#: a trial run slower than this many times the median run [-] (and than MIN_LIMIT_S [s]) counts as failed:
#: a destabilised loop that chatters is a poor fit, and the optimizer is steered away from it
SLOW_FACTOR = 30.0
MIN_LIMIT_S = 4.0
#: mode switches allowed in one trial run (a destabilised loop chatters on its limits).  A loop that hunts in
#: a limit cycle against its current limit is real behaviour, not chatter: an 18 ms speed-sensor lag makes
#: about 10 switches per second, 400 in a 40 s record, where 300 refused every run of the true structure.
#: A run that chatters is also stopped by the time limit (SLOW_FACTOR)
MAX_EVENTS = 3000
#: residual value given to a failed trial run, in scaled units
PENALTY = 30.0
#: lags [s] at which the phase-free residual compares autocovariances (see _Problem.cycle_residual): above the
#: correlation time of measurement noise, up to a few stick-slip periods
CYCLE_LAGS_S = (1.0, 10.0)


def holdout_masks(measurement: Measurement, kind: str = "blocks", fraction: float = 0.3, n_blocks: int = 15,
                  t0: float | None = None):
    """Split the samples of a record into a fitting part and a held-out part.

    Parameters
    ----------
    measurement : Measurement
        The record.
    kind : {'blocks', 'tail'}, default 'blocks'
        ``tail``: fit on the first 1 - fraction of the record, hold out the
        rest.  ``blocks``: cut the record into ``n_blocks`` equal blocks and
        hold out every k-th one (k = round(1/fraction)), so that every phase
        of the start-up (ramp, breakaway, steady speed) is in both parts;
        blocks several seconds long keep coloured noise from leaking across.
    fraction : float, default 0.3
        Share of the record held out [-].
    n_blocks : int, default 15
        Number of blocks for ``kind='blocks'``.
    t0 : float, optional
        Start of the experiment [s]; samples before it belong to neither part.

    Returns
    -------
    train, test : ndarray of bool
        Masks over the samples of ``measurement``.
    """
    t = measurement.t
    start = t[0] if t0 is None else t0
    # samples at a level the logger clipped a channel at, or in a spike, are in neither part (Measurement.kept)
    active = (t >= start - 1e-9) & _kept(measurement)
    span = t[-1] - start
    rel = (t - start) / span if span > 0 else np.zeros_like(t)
    if kind == "tail":
        test = active & (rel > 1.0 - fraction)
    elif kind == "blocks":
        block = np.minimum((rel * n_blocks).astype(int), n_blocks - 1)
        k = max(2, int(round(1.0 / fraction)))
        test = active & (block % k == k // 2)
    else:
        raise ModelError(f"unknown hold-out kind {kind!r}: choose 'blocks' or 'tail'")
    return active & ~test, test


def unspiked(measurement) -> np.ndarray:
    """The record's samples outside the logger's spikes.

    Parameters
    ----------
    measurement : Measurement
        The record (:attr:`Measurement.unspiked <kilnctl.measure.io.Measurement.unspiked>`); a stand-in
        without the reader's checks has no spikes.

    Returns
    -------
    numpy.ndarray of bool
        One entry per sample, False inside a spike: where stick-slip falls are looked for.
    """
    keep = getattr(measurement, "unspiked", None)
    return np.ones(measurement.n, bool) if keep is None else keep


def _kept(measurement) -> np.ndarray:
    """The record's samples where no channel is clipped or in a spike (:attr:`Measurement.kept
    <kilnctl.measure.io.Measurement.kept>`; all, for a record built without the checks)."""
    keep = getattr(measurement, "kept", None)
    return np.ones(measurement.t.size, bool) if keep is None else keep


def bic(rss: dict, n: dict, k: int) -> float:
    """Bayesian information criterion of a multi-channel Gaussian fit.

    BIC = sum_c n_c ln(RSS_c / n_c) + k ln(sum_c n_c): each channel has its
    own (estimated) noise variance, so the value does not depend on units.

    Parameters
    ----------
    rss : dict of str to float
        Residual sum of squares per channel [unit^2].
    n : dict of str to int
        Samples per channel.
    k : int
        Number of fitted parameters.

    Returns
    -------
    float
    """
    total = sum(n.values())
    val = sum(n[c] * math.log(max(rss[c], 1e-300) / n[c]) for c in rss)
    return float(val + k * math.log(total))


# --- parameter space ----------------------------------------------------------------
class _Space:
    """Map between the optimizer's scaled vector u and parameter values."""

    def __init__(self, free: list[FreeParameter], params: Parameters):
        self.free = list(free)
        names = [f.name for f in free]
        self.coords = []  # (label, lo, hi)
        self.reported = []
        for f in free:
            if f.kind == "polar":
                r = f.upper / f.typical
                self.coords += [(f"{f.name}*cos({f.partner})", -r, r), (f"{f.name}*sin({f.partner})", -r, r)]
                self.reported += [f.name, f.partner]
            elif f.kind == "log":
                if f.lower <= 0:
                    raise ModelError(f"log-scaled parameter {f.name!r} needs a lower bound > 0")
                self.coords.append((f"ln({f.name}/{f.typical:g})", math.log(f.lower / f.typical),
                                    math.log(f.upper / f.typical)))
                self.reported.append(f.name)
            elif f.name == "mu_s" and "mu_c" in names:
                self.coords.append(("mu_s/mu_c", 1.0, max(1.0 + 1e-6, f.upper / free_parameter("mu_c").lower)))
                self.reported.append(f.name)
            else:
                lo, hi = f.lower, f.upper
                if f.name == "mu_c" and "mu_s" not in names:
                    hi = min(hi, params.mu_s)
                if f.name == "mu_s" and "mu_c" not in names:
                    lo = max(lo, params.mu_c)
                self.coords.append((f.name, lo / f.typical, hi / f.typical))
                self.reported.append(f.name)
        self.lower = np.array([c[1] for c in self.coords])
        self.upper = np.array([c[2] for c in self.coords])
        self._order = sorted(range(len(self.free)), key=lambda i: self.free[i].name == "mu_s")

    def decode(self, u) -> dict:
        u = np.asarray(u, float)
        vals = {}
        pos = self._positions()
        for i in self._order:
            f, j = self.free[i], pos[i]
            if f.kind == "polar":
                a, b = u[j] * f.typical, u[j + 1] * f.typical
                vals[f.name] = math.hypot(a, b)
                vals[f.partner] = math.atan2(b, a)
            elif f.kind == "log":
                vals[f.name] = f.typical * math.exp(u[j])
            elif self.coords[j][0] == "mu_s/mu_c":
                vals["mu_s"] = vals["mu_c"] * u[j]
            else:
                vals[f.name] = u[j] * f.typical
        return vals

    def encode(self, values: dict) -> np.ndarray:
        u = []
        for f in self.free:
            if f.kind == "polar":
                amp, ph = values[f.name], values.get(f.partner, 0.0)
                u += [amp * math.cos(ph) / f.typical, amp * math.sin(ph) / f.typical]
            elif f.kind == "log":
                u.append(math.log(max(values[f.name], f.lower) / f.typical))
            elif f.name == "mu_s" and any(g.name == "mu_c" for g in self.free):
                u.append(values["mu_s"] / max(values["mu_c"], 1e-9))
            else:
                u.append(values[f.name] / f.typical)
        u = np.array(u, float)
        span = self.upper - self.lower
        return np.clip(u, self.lower + 1e-6 * span, self.upper - 1e-6 * span)

    def _positions(self):
        pos, j = [], 0
        for f in self.free:
            pos.append(j)
            j += 2 if f.kind == "polar" else 1
        return pos

    def jacobian(self, u) -> np.ndarray:
        """d(reported values)/du by central differences (no simulation)."""
        u = np.asarray(u, float)
        G = np.zeros((len(self.reported), u.size))
        for j in range(u.size):
            h = 1e-6 * max(1.0, abs(u[j]))
            up, um = u.copy(), u.copy()
            up[j] += h
            um[j] -= h
            vp, vm = self.decode(up), self.decode(um)
            G[:, j] = [(vp[r] - vm[r]) / (2 * h) for r in self.reported]
        return G


# --- the problem: simulate, sample, weight ----------------------------------------------
class _Problem:
    """One record, one model structure: residuals of trial parameter values."""

    def __init__(self, measurement, experiment, params, model, effects, scales, mask):
        self.m = measurement
        self.exp = experiment
        # the record's ramp set once (run_model would otherwise build the parameter set twice per trial run)
        self.params = params.replace(ramp_rate=experiment.ramp_rate, omega_ref=experiment.omega_ref)
        self.model = model
        self.effects = tuple(effects)
        active = measurement.t >= experiment.t0 - 1e-9
        self.mask = ((mask if mask is not None else np.ones(measurement.n, bool)) & _kept(measurement))[active]
        self.meas = {c: measurement.channels[c][active] for c in CHANNELS}
        # the samples outside the record's spikes, where its stick-slip falls are looked for
        self.unspiked = unspiked(measurement)[active]
        self.scales = scales
        self.walls: list[float] = []
        self.n_failed = 0
        self.last_error = None
        t_act = measurement.t[active]
        self.dt = float(np.median(np.diff(t_act))) if t_act.size > 1 else 1.0
        self.smooth_n = 1  # moving-average width of the residual [samples] (see Calibration.fit, smoothing)
        self.deadline = None  # time.perf_counter() value after which no further trial is run
        self._limit = None  # wall time [s] above which a trial run counts as failed
        self.outside = None  # a change outside the catalogue fitted to the current (kilnctl.measure.outside)
        self.horizon_end = None  # record time [s] of the last fitted sample when the fit is on a shorter horizon
        self.t_act = measurement.t[active]
        self.cycles_from = None  # record time [s] from which the residual is phase-free (see cycle_residual)
        self.timing = None  # BreakawayTiming: the falls of stick-slip cycles compared by their times (timing_residual)

    def set_smoothing(self, width_s: float) -> None:
        """Compare moving averages of ``width_s`` seconds of the residual (0: the residual itself)."""
        self.smooth_n = max(1, int(round(width_s / self.dt))) if width_s > 0 else 1

    def run(self, values: dict) -> ModelRun | None:
        try:
            p = self.params.replace(**values)
        except KilnctlError as exc:
            self.n_failed += 1
            self.last_error = str(exc)
            return None
        if self.deadline is not None and time.perf_counter() > self.deadline:
            # the fit's time is up: every further trial is a failed one, so the optimizer stops where it is
            # (checked here, between runs: safe in threads, worker processes and library calls, unlike a signal)
            self.n_failed += 1
            self.last_error = "the calibration's time limit was reached"
            return None
        limit = None
        if len(self.walls) >= 3:
            if self._limit is None or len(self.walls) % 25 == 0:  # the median moves slowly: not at every run
                self._limit = max(MIN_LIMIT_S, SLOW_FACTOR * float(np.median(self.walls[-200:])))
            limit = self._limit
        t_start = time.perf_counter()
        try:
            # on a shorter horizon the model runs only as far as the (smoothed) residual looks: it is causal
            t_stop = None if self.horizon_end is None else self.horizon_end + (self.smooth_n // 2 + 2) * self.dt
            run = run_model(p, self.m, self.exp, model=self.model, effects=self.effects, max_events=MAX_EVENTS,
                            t_stop=t_stop)
        except KilnctlError as exc:
            self.n_failed += 1
            self.last_error = str(exc)
            return None
        wall = time.perf_counter() - t_start
        if limit is not None and wall > limit:
            self.n_failed += 1
            self.last_error = f"trial run slower than {limit:.0f} s ({wall:.0f} s): counted as a failed run"
            return None
        self.walls.append(wall)
        if self.outside is not None:
            self._add_outside(run)
        return run

    def _add_outside(self, run: ModelRun) -> None:
        """Add to the model's current the term ``outside`` fitted to its residual on the fitted samples
        (variable projection: the term is fitted in closed form at every trial of the others)."""
        t = self.m.t[self.m.t >= self.exp.t0 - 1e-9]
        cur = run.outputs["current_A"]
        e = self.meas["current_A"] - cur
        sel = self.mask
        fitted = self.outside.fit(t[sel], e[sel])
        if fitted is None:
            return
        run.outputs["current_A"] = cur + self.outside.shape(t, fitted)
        run.outside = fitted

    def residual(self, run: ModelRun | None, mask=None) -> np.ndarray:
        mask = self.mask if mask is None else mask
        if self.cycles_from is not None:
            return self.cycle_residual(run, mask)
        if self.timing is not None:
            return self.timing_residual(run, mask)
        parts = []
        for c in CHANNELS:
            if run is None:
                parts.append(np.full(int(mask.sum()), PENALTY))
            else:
                e = (self.meas[c] - run.outputs[c]) / self.scales[c]
                if self.smooth_n > 1:  # a short event (an impact) misplaced in time then costs in proportion
                    e = np.convolve(e, np.full(self.smooth_n, 1.0 / self.smooth_n), mode="same")
                parts.append(e[mask])
        return np.concatenate(parts)

    def cycle_residual(self, run: ModelRun | None, mask) -> np.ndarray:
        """A residual that does not depend on the phase of self-sustained cycles after ``cycles_from``.

        Before ``cycles_from`` (the ramp and the first breakaway) the scaled residual itself, smoothed like the
        plain residual when a smoothing width is set (:meth:`set_smoothing`); after it, per channel, the
        difference of the mean levels and of the autocovariances at lags from :data:`CYCLE_LAGS_S` (model
        minus measurement, over the fitted samples).  Stick-slip cycles whose period
        is slightly wrong drift out of phase, so that the simulation-error cost of a long record has a valley
        for every whole number of cycles; their mean level, period and amplitude -- which is what the
        autocovariance holds -- change smoothly with the friction and the burden's inertia.  Lags below the
        lower end skip the measurement noise's own correlation (tenths of a second).
        """
        head = mask & (self.t_act < self.cycles_from)
        tail = mask & (self.t_act >= self.cycles_from)
        n_tail = int(tail.sum())
        k_lo, k_hi = (int(round(v / self.dt)) for v in CYCLE_LAGS_S)
        k_hi = min(k_hi, n_tail // 2)
        parts = []
        for c in CHANNELS:
            if run is None:
                parts.append(np.full(int(head.sum()) + 1 + max(0, k_hi - k_lo + 1), PENALTY))
                continue
            e = (self.meas[c] - run.outputs[c]) / self.scales[c]
            if self.smooth_n > 1:  # the ramp's impacts misplaced in time: as in residual()
                e = np.convolve(e, np.full(self.smooth_n, 1.0 / self.smooth_n), mode="same")
            parts.append(e[head])
            if n_tail < 2:
                continue
            ym, yo = self.meas[c][tail], run.outputs[c][tail]
            parts.append(np.array([math.sqrt(n_tail) * (yo.mean() - ym.mean()) / self.scales[c]]))
            if k_hi >= k_lo:
                w = tail.astype(float)
                cm = _autocov(np.where(tail, self.meas[c] - ym.mean(), 0.0), w, k_lo, k_hi)
                co = _autocov(np.where(tail, run.outputs[c] - yo.mean(), 0.0), w, k_lo, k_hi)
                # weighted like n_tail samples of the residual: sum over lags ~ n_tail (dC / s^2)^2
                parts.append(math.sqrt(n_tail / (k_hi - k_lo + 1)) * (co - cm) / self.scales[c] ** 2)
        return np.concatenate(parts)

    def timing_residual(self, run: ModelRun | None, mask) -> np.ndarray:
        """The scaled residual with the current's falls compared by their times (see :mod:`.breakaways`).

        The current's samples around the record's stick-slip falls are left out; in their place, for each
        paired fall, its time error weighted by what that error costs the simulation-error residual.  Where
        the falls agree to a fraction of a sample the two residuals are nearly equal; further off, this one
        changes smoothly with the parameters where the other has a cusp for every fall crossing a sample.
        """
        tm = self.timing
        parts = []
        for c in CHANNELS:
            sel = mask & ~tm.near if c == "current_A" else mask
            if run is None:
                parts.append(np.full(int(sel.sum()), PENALTY))
            else:
                parts.append(((self.meas[c] - run.outputs[c]) / self.scales[c])[sel])
        parts.append(np.full(tm.size, PENALTY) if run is None else tm.residual(run, self.scales["current_A"]))
        return np.concatenate(parts)

    def rss(self, run: ModelRun, mask=None) -> dict:
        mask = self.mask if mask is None else mask
        return {c: float(np.sum((self.meas[c][mask] - run.outputs[c][mask]) ** 2)) for c in CHANNELS}

    def fits(self, run: ModelRun, mask=None) -> dict:
        mask = self.mask if mask is None else mask
        return {c: fit_percent(self.meas[c][mask], run.outputs[c][mask]) for c in CHANNELS}


@dataclass
class _Trial:
    values: dict
    run: ModelRun | None
    cost: float


# --- how a fit is searched: small strategies ---------------------------------------------------
@dataclass(frozen=True)
class Starts:
    """Where the local fits of a calibration begin.

    The given values and every further point are compared by cost (one
    simulation each, on the first horizon and the widest smoothing); local
    fits run from the given values (when ``n_local > 1``), from the best
    point however close it lies (a narrow valley next to a good guess is
    common: a backlash impact, a current limit), and from the next best
    that lie apart from those chosen.  A point equal to one already chosen
    (a grid point at the given values) is passed over: its local fit would
    repeat one that runs anyway.

    Attributes
    ----------
    points : tuple of dict or None
        Further starting points [units of each parameter], each completing
        the given values; None: :func:`default_starts`.
    n_local : int
        Local fits to run.
    separation : float
        Least distance (largest scaled-coordinate difference) between two
        chosen points [-]: 1 is a factor e for a log-scaled parameter.
    spread : str or None
        A parameter whose points are spread over its range: besides the
        points chosen by cost, a local fit also runs from the best point of
        each decade of it that no chosen point lies in.  Where the parameter
        sets a mode's frequency, the cost at a starting point ranks by the
        mode's phase, and the base values may have made up for the missing
        mode: a soft drive train's stiffness 5 % off fits worse than a rigid
        one, while a local fit from there ends at the record's noise
        (see :attr:`~kilnctl.model.catalogue.Effect.spread`).
    """

    points: tuple | None = None
    n_local: int = 2
    separation: float = 1.0
    spread: str | None = None

    def points_from(self, names, given: dict) -> list[dict]:
        """The given values, then each further point completed by them."""
        extra = default_starts(names, given) if self.points is None else list(self.points)
        return [dict(given)] + [dict(given, **p) for p in extra]

    def decades(self, points) -> list | None:
        """The decade (floor of log10) of :attr:`spread` at each point, None where it is not positive; None
        without a spread."""
        if self.spread is None:
            return None
        return [math.floor(math.log10(v)) if (v := float(p.get(self.spread, 0.0))) > 0 else None for p in points]

    def choose(self, u0s, costs, decades=None) -> list:
        """The scaled points the local fits start from (``u0s[0]`` is the given one); ``decades`` (from
        :meth:`decades`): beyond ``n_local``, one more from the best point of each decade no chosen point lies
        in that lies apart from those chosen (``separation``)."""
        if len(u0s) <= 1:
            return list(u0s)
        order = np.argsort(costs, kind="stable")
        given = [0] if self.n_local > 1 else []
        chosen: list[int] = []
        for i in order:
            if i in given:
                continue
            if any(np.max(np.abs(u0s[i] - u0s[j]), initial=0.0) <= 1e-12 for j in given + chosen):
                continue  # the same point again (a grid point at the given values): the same local fit
            if all(np.max(np.abs(u0s[i] - u0s[j])) > self.separation for j in chosen):
                chosen.append(int(i))
            if len(given) + len(chosen) >= max(1, self.n_local):
                break
        if decades is not None:
            covered = {decades[j] for j in given + chosen}
            for i in order:
                if decades[i] is None or decades[i] in covered:
                    continue
                if any(np.max(np.abs(u0s[i] - u0s[j])) <= self.separation for j in given + chosen):
                    continue  # next to a chosen point (across a decade's edge): the decade's next best
                covered.add(decades[i])
                chosen.append(int(i))
        return [u0s[i] for i in given + chosen]


@dataclass(frozen=True)
class Horizons:
    """Growing fitting horizons, fractions of the record after the start [-].

    The fit on each warm-starts the next, after probing a 3^p grid of small
    steps around it (the friction pair, or up to four coordinates).  Stick-slip cycles make the
    simulation-error cost of a long record rugged (a small change of friction
    shifts every later cycle); a short horizon first finds the right basin.

    Attributes
    ----------
    fractions : tuple of float
        Horizons [-]; 1 (the whole record) is always the last.
    """

    fractions: tuple = (1.0,)

    def schedule(self) -> list[float]:
        """The horizons in order, ending with 1."""
        hs = sorted({float(h) for h in self.fractions if 0 < float(h) <= 1.0} | {1.0})
        return hs


@dataclass(frozen=True)
class Smoothing:
    """Moving-average widths of the residual, widest first, for effects whose trace is an event in time.

    A short event misplaced in time (a backlash impact one sample early)
    costs as much as one missing altogether, and a jump misplaced by dt (a
    stick-slip breakaway) costs in proportion to |dt|: a cusp a gradient
    method cannot descend.  On a smoothed residual both costs fall smoothly as
    the event moves closer.  Starting points are compared on the widest; on
    every horizon the local fit runs through all of them in turn.

    Attributes
    ----------
    widths_s : tuple of float
        Widths [s]; 0 (the residual itself) is always the last.
    later_s : tuple of float or None
        Widths on the horizons after the first [s] (None: ``widths_s``):
        there the fit starts from the previous horizon's, whose events are
        aligned already, and only the new part needs the narrower widths.
    """

    widths_s: tuple = (0.0,)
    later_s: tuple | None = None

    def schedule(self, first: bool = True, last: bool = True) -> list[float]:
        """The widths on a horizon, widest first (``first``, ``last``: on the first, the last horizon).

        The residual itself (width 0) ends the last horizon; on a shorter one the fit only has to find the
        basin of the next, which the smoothed residual shows."""
        ws = self.widths_s if first or self.later_s is None else self.later_s
        out = sorted({float(w) for w in ws if float(w) > 0}, reverse=True)
        return out + [0.0] if last or not out else out


@dataclass
class _Local:
    """The end of one local fit."""

    u: np.ndarray
    jac: np.ndarray | None
    message: str
    cost: float
    start: np.ndarray
    fit_percent: dict = field(default_factory=dict)

    def to_dict(self, space) -> dict:
        return {"start": {k: float(v) for k, v in space.decode(self.start).items()} if self.start.size else {},
                "end": {k: float(v) for k, v in space.decode(self.u).items()} if self.u.size else {},
                "cost": float(self.cost), "fit_percent": dict(self.fit_percent)}


class _Search:
    """Trial runs (cached), local trust-region fits and probes of one calibration problem."""

    def __init__(self, prob: _Problem, space: _Space, t_active, t0, diff_step, max_nfev, tol):
        self.prob, self.space = prob, space
        self.cache: dict[bytes, _Trial] = {}
        self.full_mask = prob.mask.copy()
        self.t_act, self.t0 = t_active, t0
        self.span = t_active[-1] - t0
        self.diff_step, self.max_nfev, self.tol = diff_step, max_nfev, tol
        self.nfev = 1
        self.horizon = 1.0
        self.log_coord = np.array([c[0].startswith("ln(") for c in space.coords], bool)
        self.cycles_from = None  # record time [s]: each local fit starts with a phase-free stage (cycle_stage)

    def trial(self, u) -> _Trial:
        key = np.asarray(u, float).tobytes()
        if key not in self.cache:
            vals = self.space.decode(u)
            run = self.prob.run(vals)
            r = self.prob.residual(run)
            self.cache[key] = _Trial(vals, run, 0.5 * float(r @ r))
            if len(self.cache) > 64:
                self.cache.pop(next(iter(self.cache)))
        return self.cache[key]

    def fun(self, u):
        return self.prob.residual(self.trial(u).run)

    def set_horizon(self, h):
        self.horizon = h
        end = self.t0 + h * self.span
        self.prob.mask = self.full_mask & (self.t_act <= end + 1e-9)
        self.prob.horizon_end = end if h < 1.0 else None
        self.cache.clear()

    def set_smoothing(self, w):
        self.prob.set_smoothing(w)
        self.cache.clear()

    def jacobian(self, u) -> np.ndarray:
        self.nfev += u.size
        return _forward_jacobian(self.fun, u, self.diff_step, self.space.upper)

    def fit_all(self, firsts, horizons: Horizons, smoothing: Smoothing) -> list[_Local]:
        """A local fit from each starting point through every horizon and smoothing width.

        With stick-slip cycles (``cycles_from`` set) each local fit begins with the phase-free stage and
        the timing stage.  They bring cycles that drift out of phase back into step, but from a start whose
        cycles are already in step (a candidate refitted from a model whose friction fits) they can lead into
        another valley: when the staged fit ends above the cost it started from, the fit is run again from
        the same start without the stages, and the lower end is kept.
        """
        prob, out = self.prob, []
        hs = horizons.schedule()
        for u in firsts:
            if out and prob.deadline is not None and time.perf_counter() > prob.deadline:
                break  # out of time: no further local fit
            start = u
            if self.cycles_from is not None and self.space.coords:
                start_cost = self._end(u).cost
                u, J, msg = self._through(self.timing_stage(self.cycle_stage(u)), hs, smoothing)
                end_cost = self._end(u).cost
                if not end_cost <= start_cost:
                    u2, J2, msg2 = self._through(start, hs, smoothing)
                    if self._end(u2).cost < end_cost:
                        u, J, msg = u2, J2, f"{msg2} (without the phase-free and timing stages)"
            else:
                u, J, msg = self._through(u, hs, smoothing)
            end = self._end(u)
            out.append(_Local(u, J, msg, end.cost, start, prob.fits(end.run) if end.run is not None else {}))
        self.set_smoothing(0.0)
        prob.deadline = None
        return out

    def _through(self, u, hs, smoothing):
        """The simulation-error fits from u through every horizon and smoothing width: (u, J, message)."""
        J, msg = np.zeros((0, 0)), "nothing to fit"
        for i, h in enumerate(hs):
            if not self.space.coords:
                break
            self.set_horizon(h)
            if i > 0:
                u = self.probe(u)
            for w in smoothing.schedule(first=i == 0, last=i == len(hs) - 1):
                self.set_smoothing(w)
                u, J, msg = self.local(u)
        return u, J, msg

    def _end(self, u) -> _Trial:
        """The trial at u judged as the end of a fit: the whole record, no smoothing, past any deadline."""
        if self.horizon < 1.0:
            self.set_horizon(1.0)
        if self.prob.smooth_n > 1:
            self.set_smoothing(0.0)
        deadline, self.prob.deadline = self.prob.deadline, None  # the end of a fit is always evaluated
        try:
            return self.trial(u)
        finally:
            self.prob.deadline = deadline

    def _local_with(self, attribute: str, value, u):
        """A local fit on the whole record with the problem's residual switched by ``attribute`` = ``value``
        (``cycles_from`` or ``timing``), switched back afterwards whatever happens."""
        self.set_horizon(1.0)
        self.set_smoothing(0.0)
        setattr(self.prob, attribute, value)
        self.cache.clear()
        try:
            u, _, _ = self.local(u, tol=self.tol)
        finally:
            setattr(self.prob, attribute, None)
            self.cache.clear()
        return u

    def screen(self, candidates, n_keep: int, keep_first: bool) -> list:
        """The ``n_keep`` candidates whose phase-free stage (:meth:`cycle_stage`) ends with the lowest cost on
        the record itself, each at the stage's end (the first candidate, the given values, kept when
        ``keep_first``).

        The phase-free cost at a starting point says where cycles of the right period and amplitude lie, but
        not which of those points a fit from it leads into the record's valley: with a soft drive train the
        second-best start by that cost ended at 76 %, the third at 98 % (plain costs 124 and 0.73 after the
        stage).  The stage costs about a tenth of a whole staged fit, and its end's plain cost tells them
        apart."""
        if len(candidates) <= n_keep:
            return list(candidates)
        ends = [self.cycle_stage(u) for u in candidates]
        costs = [self._end(u).cost for u in ends]
        order = [i for i in np.argsort(costs, kind="stable") if not (keep_first and i == 0)]
        chosen = ([0] if keep_first else []) + order
        return [ends[i] for i in chosen[:n_keep]]

    def cycle_stage(self, u):
        """A local fit of the phase-free residual on the whole record (see _Problem.cycle_residual): it sets
        the cycles' period, amplitude and mean level, from where the simulation-error fits track their phase."""
        return self._local_with("cycles_from", self.cycles_from, u)

    def timing_stage(self, u):
        """A local fit on the whole record with the stick-slip falls compared by their times
        (:meth:`_Problem.timing_residual`), from the phase-free stage's values: it aligns every fall, from where
        the simulation-error fits only polish.  Skipped when the record or the model at u has fewer than two
        falls after the ramp."""
        self.set_horizon(1.0)
        self.set_smoothing(0.0)
        run = self.trial(u).run
        if run is None:
            return u
        timing = BreakawayTiming.pair(self.t_act, self.prob.meas["current_A"], run, t0=self.t0,
                                      t_from=self.cycles_from, mask=self.full_mask, keep=self.prob.unspiked)
        if timing is None:
            return u
        return self._local_with("timing", timing, u)

    def local(self, u, tol=None):
        """One trust-region fit from u; coordinates without influence at u stay where they are
        (a Gauss-Newton step along a zero Jacobian column is unbounded, and would throw the parameter
        across a regime boundary, e.g. mu_s while the burden is held)."""
        from scipy.optimize import least_squares

        space = self.space
        r0 = self.fun(u)
        cols_j = _forward_jacobian(self.fun, u, self.diff_step, space.upper)
        cols = np.linalg.norm(cols_j, axis=0)
        self.nfev += 1 + u.size
        live = cols > 1e-7 * max(cols.max(), 1e-300)
        if not live.any():
            return u, np.zeros((r0.size, u.size)), "no parameter influences the fit"

        def f_live(v):
            w = u.copy()
            w[live] = v
            return self.fun(w)

        J0 = cols_j[:, live]
        u_live0 = u[live].copy()

        def jac_live(v):
            # the first Jacobian is the one just computed for the influence check (same steps, same runs)
            if np.array_equal(v, u_live0):
                return J0
            w = u.copy()
            w[live] = v
            self.nfev += int(live.sum())
            return _forward_jacobian(self.fun, w, self.diff_step, space.upper, live)[:, live]

        # on a smoothed residual or a shorter horizon the fit only has to find the basin of the next stage
        if tol is None:
            tol = self.tol if self.prob.smooth_n <= 1 and self.horizon >= 1.0 else 10 * self.tol
        res = least_squares(f_live, u[live], jac=jac_live, bounds=(space.lower[live], space.upper[live]),
                            x_scale=1.0, max_nfev=self.max_nfev, method="trf", ftol=tol, xtol=tol)
        self.nfev += int(res.nfev)
        w = u.copy()
        w[live] = res.x
        Jf = np.zeros((res.jac.shape[0], u.size))
        Jf[:, live] = res.jac
        return w, Jf, res.message

    def probe(self, u):
        """Best of a 3^p grid of small steps around u (3 % linear, 10 % log), run before each longer horizon,
        where the next stick-slip cycle may sit in a neighbouring valley.  The cycles' timing is set by the
        friction: the grid spans mu_c and mu_s/mu_c when they are fitted (p = 2), else every coordinate
        when there are at most four."""
        if u.size == 0:
            return u
        import itertools

        space = self.space
        friction = [j for j, c in enumerate(space.coords) if c[0] in ("mu_c", "mu_s/mu_c", "mu_s")]
        axes = friction if friction else (list(range(u.size)) if u.size <= 4 else [])
        if not axes:
            return u
        steps = np.where(self.log_coord, 0.1, 0.03 * np.maximum(1.0, np.abs(u)))
        best_u, best_c = u, self.trial(u).cost
        for d_axes in itertools.product((-1.0, 0.0, 1.0), repeat=len(axes)):
            d = np.zeros(u.size)
            d[axes] = d_axes
            v = np.clip(u + steps * d, space.lower, space.upper)
            c = self.trial(v).cost
            if c < best_c:
                best_u, best_c = v, c
        return best_u


# --- the estimator -------------------------------------------------------------------------
class Calibration:
    """Fit chosen parameters of a model to a measured record.

    Parameters
    ----------
    params : Parameters
        Setup of the experiment and starting values.  The PID gains are fixed
        once (designed from the setup if ``gains = 'design'``).
    parameters : sequence of str or FreeParameter, default ('mu_c', 'mu_s', 'm_v', 'J_v')
        What to fit: names (bounds from :data:`~kilnctl.measure.effects.BASE_PARAMETERS`
        or the catalogue) or full declarations.
    model : {'macro', 'micro'}, default 'macro'
        Model structure.
    effects : sequence of str
        Components added to the model.
    bounds : dict of str to (float, float), optional
        Bounds that replace the declared ones [unit of each parameter].
    scales : dict of str to float or 'std', default 'std'
        Residual scale per channel [A, rpm]; ``'std'``: each measured
        channel's standard deviation.
    t0 : float, optional
        Start of the experiment in record time [s] (default: from the record).
    max_nfev : int, default 40
        Largest number of optimizer iterations' function evaluations
        (each one simulation, plus one per parameter for the Jacobian).
    diff_step : float, default 1e-3
        Finite-difference step of the Jacobian, in scaled units [-].
    tol : float, default 1e-4
        A local fit stops when a step changes the cost, or the scaled
        parameters, by less than this fraction [-] (``ftol`` and ``xtol`` of
        ``scipy.optimize.least_squares``).  Structures are told apart by BIC
        differences of 10 on thousands of samples, i.e. cost changes of a
        few tenths of a per cent: finer convergence buys nothing.
    outside : CurrentStep or CurrentDrift, optional
        Add to the model's current a change that no model component
        describes (:mod:`kilnctl.measure.outside`: an abrupt step, a slow
        drift), fitted in closed form at every trial (variable projection).
        The fitted term is ``outside_`` and counts as its ``n_params``
        parameters in ``bic_``.
    time_limit_s : float, optional
        Wall time of a fit [s]: after it, every further trial run counts as
        failed, so the local fits end at the best values found so far
        (checked between runs, so safe in threads and worker processes).

    Attributes
    ----------
    values_ : dict of str to float
        Fitted values [unit of each parameter].
    stderr_ : dict of str to float
        Standard errors [same units] (inf when not identifiable).
    corr_ : ndarray
        Correlation matrix of the fitted values, in the order of ``names_``.
    names_ : list of str
        Names of the fitted values.
    on_bound_ : list of str
        Parameters that ended on (or within 0.1 % of) a bound.
    not_identifiable_ : list of str
        Parameters with a standard error above half their value (or half
        their range) or a correlation above 0.99 with another.
    params_ : Parameters
        The setup with the fitted values.
    fit_percent_ : dict of str to float
        Fit % per channel on the fitted samples.
    rss_, n_ : dict
        Residual sum of squares [unit^2] and sample count per channel.
    bic_ : float
        :func:`bic` of the fit.
    cost_ : float
        Final value of the scaled least-squares cost.
    nfev_ : int
        Simulations run by the optimizer (without the Jacobian's).
    n_starts_ : int
        Starting points compared by cost (one simulation each).
    local_fits_ : list of dict
        One per local fit: ``start`` and ``end`` values [units of each],
        final ``cost`` [-] and ``fit_percent`` per channel [%] on the fitted
        samples; the lowest cost is the fit kept.
    n_failed_ : int
        Trial runs that failed (counted as a poor fit).
    run_ : ModelRun
        The fitted model sampled at the measured times.
    experiment_ : Experiment
        The experiment simulated.
    message_ : str
        Optimizer status.
    kept_start_ : bool
        True when no local fit ended below the starting values' cost and
        those values were kept.
    outside_ : dict or None
        The fitted ``outside`` term (its ``fit``), or None.
    """

    def __init__(self, params: Parameters | None = None, parameters=DEFAULT_CALIBRATE, *,
                 model: str = "macro", effects=(), bounds: dict | None = None, scales="std",
                 t0: float | None = None, max_nfev: int = 40, diff_step: float = 1e-3, tol: float = 1e-4,
                 time_limit_s: float | None = None, outside=None):
        self.params = Parameters() if params is None else params
        self.parameters = name_list(parameters, "parameters")
        self.model = model
        self.effects = name_list(effects, "effects", ModelError)
        self.bounds = dict(bounds or {})
        self.scales = scales
        self.t0 = t0
        self.max_nfev = max_nfev
        self.diff_step = diff_step
        self.tol = tol
        if time_limit_s is not None and not (isinstance(time_limit_s, (int, float)) and time_limit_s > 0):
            raise ModelError(f"time_limit_s = {time_limit_s!r} must be a positive number of seconds (or None)")
        self.time_limit_s = time_limit_s
        self.outside = outside

    # --- helpers --------------------------------------------------------------------
    def _free(self) -> list[FreeParameter]:
        out = []
        for p in self.parameters:
            fp = p if isinstance(p, FreeParameter) else free_parameter(p, self.params)
            if fp.name in self.bounds:
                lo, hi = self.bounds[fp.name]
                fp = FreeParameter(fp.name, float(lo), float(hi), fp.kind, fp.typical, fp.partner)
            out.append(fp)
        return out

    def _check_fitted(self):
        if not hasattr(self, "values_"):
            raise NotFittedError("this Calibration is not fitted yet: call fit(measurement) first")

    def _scales(self, measurement, active) -> dict:
        if isinstance(self.scales, dict):
            return {c: float(self.scales[c]) for c in CHANNELS}
        out = {}
        active = active & _kept(measurement)
        for c in CHANNELS:
            s = float(np.std(measurement.channels[c][active]))
            out[c] = s if s > 0 else 1.0
        return out

    # --- estimator API --------------------------------------------------------------
    def fit(self, measurement: Measurement, mask=None, *, init: dict | None = None,
            starts=None, experiment: Experiment | None = None, horizons=(1.0,), n_local: int = 2,
            separation: float = 1.0, smoothing=(0.0,), cycles: bool = False, screen: int = 1,
            spread: str | None = None) -> "Calibration":
        """Fit the parameters to a record.

        Parameters
        ----------
        measurement : Measurement
            The record.
        mask : ndarray of bool, optional
            Samples to fit (e.g. the ``train`` part of :func:`holdout_masks`);
            default all from the start of the experiment.
        init : dict, optional
            Starting values [units of the parameters] (default: the setup's).
        starts : list of dict or Starts, optional
            Further candidate starting points, compared by cost (one
            simulation each); a :class:`Starts` also sets ``n_local`` and
            ``separation``.  Default: a grid over the burden friction and
            mass when they are fitted (mu_c x 0.7 ... 1.3, mu_s/mu_c 1.02 ...
            1.7, m_v x 0.9/1/1.1, J_v x 0.7 ... 1.4): the printed friction law
            has regimes (held, stick-slip) whose costs are separate valleys,
            and the burden inertia sets the phase of its oscillation.
        experiment : Experiment, optional
            The experiment (default: inferred from the record).
        horizons : sequence of float or Horizons, default (1.0,)
            Growing fitting horizons, as fractions of the record after the
            start [-]: the fit on each warm-starts the next (after probing a
            3^p grid of small steps around it: the friction pair, or up to four
            coordinates), and the starting
            points are compared on the first.  Stick-slip cycles make the
            simulation-error cost of a long record rugged (a small change of
            friction shifts every later cycle); a short horizon first finds
            the right basin.
        n_local : int, default 2
            Local fits run: from ``init`` (when n_local > 1) and from the best
            other starting points that lie apart from each other (more than
            one scaled unit, i.e. a factor e for log-scaled parameters, unless
            ``separation`` says otherwise; the best one is taken however close
            it lies to ``init``); the lowest final cost wins.  0: no local fit,
            the statistics at ``init`` (to judge a structure at values fitted
            in a larger one).
        separation : float, default 1.0
            Least distance (largest scaled-coordinate difference) between two
            starting points of local fits [-].
        smoothing : sequence of float or Smoothing, default (0.0,)
            Moving-average widths of the residual [s], widest first: the
            starting points are compared on the first, and on every horizon
            the local fit runs through them in turn.  A short event misplaced
            in time (a backlash impact one sample early) costs as much as one
            missing altogether, and a jump misplaced by dt (a stick-slip
            breakaway) costs in proportion to |dt|: a cusp a gradient method
            cannot descend.  On a smoothed residual both costs fall smoothly
            as the event moves closer.  The last width is always 0 (the
            residual itself).
        cycles : bool, default False
            Begin every local fit with a phase-free stage on the whole
            record: up to 1.5 s after the ramp the residual itself, after
            that the mean level and the autocovariance of each channel (at
            lags of 1-10 s).  For self-sustained cycles (torque-law
            stick-slip): when their period is slightly off they drift out
            of phase, and the simulation-error cost has a valley for every
            whole number of cycles; their period, amplitude and level
            change smoothly with the parameters.  The starting points are
            compared on this residual, its ramp part smoothed by the first
            ``smoothing`` width.  Then a timing stage on
            the whole record: the current's samples around the record's
            stick-slip falls replaced by the time errors of the model's
            burden switches (:class:`~kilnctl.measure.breakaways.BreakawayTiming`;
            skipped when fewer than two falls are found after the ramp).
        spread : str or None, default None
            A parameter whose starting points are spread over its range
            (see :class:`Starts`): one more local fit from the best point in
            each decade of it that no chosen point lies in (not with
            ``cycles``, whose screening already compares points apart).
        screen : int, default 1
            With ``cycles``: ``screen`` times ``n_local`` starting points, the
            best by the phase-free cost, are each run through the phase-free
            stage, and the local fits continue from those that end it with the
            lowest cost on the record itself (1: no screening).  The phase-free
            cost at a point says where cycles of the right period lie, not
            which of those points leads into the record's valley.

        Returns
        -------
        Calibration
            ``self``, fitted.
        """
        Measurement.require(measurement, "Calibration.fit")
        params = resolve_gains(self.params)
        exp = experiment or measurement.experiment(params, t0=self.t0)
        active = measurement.t >= exp.t0 - 1e-9
        scales = self._scales(measurement, active)
        free = self._free()
        space = _Space(free, params)
        prob = _Problem(measurement, exp, params, self.model, self.effects, scales, mask)
        prob.outside = self.outside
        start_vals = {r: params[r] for r in space.reported}
        start_vals.update(init or {})
        starts = starts if isinstance(starts, Starts) else Starts(None if starts is None else tuple(starts),
                                                                  n_local, separation, spread)
        horizons = horizons if isinstance(horizons, Horizons) else Horizons(tuple(horizons))
        smoothing = smoothing if isinstance(smoothing, Smoothing) else Smoothing(tuple(smoothing))
        t_wall = time.perf_counter()
        prob.deadline = None if self.time_limit_s is None else t_wall + self.time_limit_s
        search = _Search(prob, space, measurement.t[active], exp.t0, self.diff_step, self.max_nfev, self.tol)
        if cycles:
            search.cycles_from = exp.steady_from
        points = starts.points_from(space.reported, start_vals)
        u0s = [space.encode(v) for v in points]
        # the spread over decades on costs without stick-slip cycles (their screening compares points apart)
        decades = starts.decades(points) if not cycles else None
        search.set_horizon(horizons.schedule()[0])
        search.set_smoothing(smoothing.schedule()[0])
        if search.cycles_from is not None:
            # starting points compared on the phase-free residual, on the whole record, its ramp part smoothed
            # by the widest width: a backlash impact train 30 ms off costs as much as none at all, and the
            # valley of the gap is a few tenths of a millimetre wide unsmoothed (torque law + backlash: the
            # grid's points 0.4 mm either side of it ranked below the gap's null value)
            search.set_horizon(1.0)
            prob.cycles_from = search.cycles_from
        costs = [search.trial(u).cost for u in u0s] if len(u0s) > 1 and starts.n_local > 0 else [0.0]
        wide = search.cycles_from is not None and starts.n_local > 0 and space.coords and screen > 1
        firsts = [] if starts.n_local == 0 else \
            (replace(starts, n_local=screen * starts.n_local) if wide else starts).choose(u0s, costs, decades)
        prob.cycles_from = None
        search.cache.clear()
        if wide:
            firsts = search.screen(firsts, starts.n_local, keep_first=starts.n_local > 1)
        results = search.fit_all(firsts, horizons, smoothing)
        # the given starting point stays a candidate: a refit is never worse than the values it started from
        # (a local fit on a rugged cost, or through a smoothed residual, can end above where it began)
        if space.coords or not results:
            results.append(_Local(u0s[0], None, "the starting values: no local fit improved on them" if firsts
                                  else "the starting values (no local fit asked for)",
                                  search.trial(u0s[0]).cost, u0s[0]))
        best_fit = min(results, key=lambda r: r.cost)
        u = best_fit.u if space.coords else np.zeros(0)
        J = best_fit.jac if best_fit.jac is not None else search.jacobian(u)
        best = search.trial(u)
        if best.run is None:
            raise KilnctlError(f"calibration failed: the model cannot be run at the fitted values "
                               f"({prob.last_error})")
        self.wall_s_ = time.perf_counter() - t_wall
        self.local_fits_ = [r.to_dict(space) for r in results if r.jac is not None]
        self.n_starts_ = len(u0s)
        self.nfev_ = search.nfev
        self.message_ = str(best_fit.message)
        self.kept_start_ = best_fit.jac is None
        self._set_statistics(space, prob, free, params, best, u, J)
        self.experiment_ = exp
        self.scales_ = scales
        self.measurement_ = measurement
        self._problem = prob
        return self

    def _set_statistics(self, space, prob, free, params, best, u, J) -> None:
        """Fitted values, standard errors, correlations, flags and fit figures at the kept optimum."""
        self.names_ = list(space.reported)
        self.values_ = {k: float(best.values[k]) for k in self.names_}
        r = prob.residual(best.run)
        m_res, p = r.size, u.size
        s2 = float(r @ r) / max(m_res - p, 1)
        # the standard errors allow for the residual's autocorrelation (the sandwich covariance): coloured noise
        # and a structure's own misfit leave a residual correlated over seconds, where s^2 (J^T J)^-1 understated
        # the spread ten-fold (a drag under the generator's coloured noise, tests/test_measure_calibrate.py)
        meat = (score_covariance(J, r, len(CHANNELS), p) if p and J.shape[0] == m_res and m_res >= 8 * len(CHANNELS)
                else s2 * (J.T @ J) if p else None)
        cov_phys, singular = _covariance(J, meat, space.jacobian(u) if p else np.zeros((0, 0)))
        se = np.sqrt(np.clip(np.diag(cov_phys), 0, None)) if p else np.zeros(0)
        se = np.where(singular, np.inf, se) if p else se
        self.stderr_ = {k: float(v) for k, v in zip(self.names_, se)}
        with np.errstate(invalid="ignore", divide="ignore"):
            d = np.sqrt(np.diag(cov_phys)) if p else np.zeros(0)
            corr = cov_phys / np.outer(d, d) if p else np.zeros((0, 0))
        corr = np.where(np.isfinite(corr), corr, 0.0)
        if p:
            # a value on a singular direction has no defined correlation: it must not taint the others
            corr[singular, :] = 0.0
            corr[:, singular] = 0.0
            np.fill_diagonal(corr, 1.0)
        self.corr_ = corr
        span = space.upper - space.lower
        near = (u - space.lower < 1e-3 * span) | (space.upper - u < 1e-3 * span) if p else np.zeros(0, bool)
        if p and near.any():
            # a value within 1e-3 of a wide range from a bound, but many of its standard errors away from it, did
            # not stop there (red team 9: B_o 6.08e5 of 0-1e9, 18 standard errors above 0, read as "the fit
            # wanted to go further"): on the bound is within two standard errors (in the optimizer's scaling, by
            # the same covariance rule as the reported errors; a coordinate on a singular direction stays on it)
            cov_u, singular_u = _covariance(J, meat, np.eye(p))
            se_u = np.where(singular_u, np.inf, np.sqrt(np.clip(np.diag(cov_u), 0.0, None)))
            gap = np.minimum(u - space.lower, space.upper - u)
            near &= ~(np.isfinite(se_u) & (gap > 2.0 * se_u))
        self.on_bound_ = sorted({self._coord_owner(space, j) for j in np.nonzero(near)[0]})
        self.not_identifiable_ = self._unidentifiable(free, corr)
        self.params_ = params.replace(**self.values_)
        self.fit_percent_ = prob.fits(best.run)
        self.rss_ = prob.rss(best.run)
        self.n_ = {c: int(prob.mask.sum()) for c in CHANNELS}
        self.outside_ = getattr(best.run, "outside", None)
        self.bic_ = bic(self.rss_, self.n_, p + (self.outside.n_params if self.outside is not None else 0))
        self.cost_ = best.cost
        self.n_failed_ = prob.n_failed
        self.run_ = best.run

    @staticmethod
    def _coord_owner(space, j) -> str:
        pos = space._positions()
        owner = max(i for i, p in enumerate(pos) if p <= j)
        return space.free[owner].name

    def _unidentifiable(self, free, corr) -> list[str]:
        out = set()
        for i, k in enumerate(self.names_):
            se, v = self.stderr_[k], self.values_[k]
            fp = next((f for f in free if f.name == k or f.partner == k), None)
            if not math.isfinite(se):
                out.add(k)
            elif fp is not None and fp.partner == k:  # a phase: meaningless when its amplitude is
                if se > 1.0:
                    out.add(k)
            elif se > 0.5 * abs(v) and (fp is None or se > 0.5 * (fp.upper - fp.lower) or v != 0):
                out.add(k)
            for j in range(len(self.names_)):
                if j != i and abs(corr[i, j]) > 0.99:
                    out.add(k)
        return sorted(out)

    def predict(self, measurement: Measurement | None = None) -> dict:
        """Model outputs of the fitted parameters at the measured times.

        Parameters
        ----------
        measurement : Measurement, optional
            Another record of the same plant (default: the fitted one).

        Returns
        -------
        dict of str to ndarray
            ``current_A`` [A], ``speed_rpm`` [rpm] and further model signals
            at the record's times from the start of the experiment on.
        """
        self._check_fitted()
        if measurement is None or measurement is self.measurement_:
            return dict(self.run_.outputs)
        exp = measurement.experiment(self.params_, t0=self.t0)
        return dict(run_model(self.params_, measurement, exp, model=self.model, effects=self.effects).outputs)

    def score(self, measurement: Measurement | None = None, mask=None) -> float:
        """Scaled fit % of the fitted model on a record (both channels together).

        100 (1 - ||e|| / ||y - mean(y)||) over the stacked channels, each
        divided by its scale: the fit % of the calibration's own objective.

        Parameters
        ----------
        measurement : Measurement, optional
            Record (default: the fitted one).
        mask : ndarray of bool, optional
            Samples to score, over the record's samples (default: all from the
            start of the experiment).

        Returns
        -------
        float
            Percent; 100 is a perfect fit.
        """
        self._check_fitted()
        m = self.measurement_ if measurement is None else measurement
        exp = self.experiment_ if m is self.measurement_ else m.experiment(self.params_, t0=self.t0)
        active = m.t >= exp.t0 - 1e-9
        sel = ((np.ones(m.n, bool) if mask is None else np.asarray(mask, bool)) & _kept(m))[active]
        out = self.predict(m)
        e = np.concatenate([(m.channels[c][active][sel] - out[c][sel]) / self.scales_[c] for c in CHANNELS])
        y = np.concatenate([(m.channels[c][active][sel] - m.channels[c][active][sel].mean()) / self.scales_[c]
                            for c in CHANNELS])
        return float(100.0 * (1.0 - np.linalg.norm(e) / np.linalg.norm(y)))

    def summary(self) -> str:
        """Return a readable table of what was found."""
        self._check_fitted()
        lines = [f"calibration of {', '.join(self.names_) or 'nothing'} on the {self.model} model"
                 + (f" + {', '.join(self.effects)}" if self.effects else "")
                 + f" ({self.nfev_} runs, {self.wall_s_:.1f} s; {self.message_})"]
        from ..params import SPECS

        for k in self.names_:
            unit = SPECS[k].unit if k in SPECS else ""
            flags = [f for f, on in (("on bound", k in self.on_bound_),
                                     ("not identifiable", k in self.not_identifiable_)) if on]
            lines.append(f"  {k:<8} = {self.values_[k]:<12.5g} +- {self.stderr_[k]:<10.3g} {unit:<10} "
                         + (f"[{', '.join(flags)}]" if flags else ""))
        lines.append("  fit % " + ", ".join(f"{c} {v:.1f}" for c, v in self.fit_percent_.items()))
        high = [(self.names_[i], self.names_[j], self.corr_[i, j]) for i in range(len(self.names_))
                for j in range(i + 1, len(self.names_)) if abs(self.corr_[i, j]) > 0.9]
        for a, b, c in high:
            lines.append(f"  correlation {a}-{b} = {c:+.3f}")
        return "\n".join(lines)

    def to_dict(self) -> dict:
        """Return the fitted values, standard errors and flags as a JSON-ready dictionary."""
        self._check_fitted()
        fin = lambda v: float(v) if math.isfinite(v) else None  # noqa: E731
        return {"model": self.model, "effects": list(self.effects),
                "values": dict(self.values_), "stderr": {k: fin(v) for k, v in self.stderr_.items()},
                "correlation": [[float(x) for x in row] for row in self.corr_],
                "names": list(self.names_), "on_bound": list(self.on_bound_),
                "not_identifiable": list(self.not_identifiable_), "fit_percent": dict(self.fit_percent_),
                "bic": self.bic_, "n_runs": self.nfev_, "n_failed_runs": self.n_failed_, "message": self.message_}


def default_starts(names, vals) -> list[dict]:
    """Starting points over the friction regimes and the burden's mass and inertia, for those being fitted.

    The friction pair is crossed in full (mu_c x 0.7 ... 1.3 by mu_s/mu_c
    1.02 ... 1.7: the printed law's regimes, held or sliding or stick-slip,
    are separate valleys of the cost).  The burden mass (x 0.9, 1, 1.1) and
    inertia (x 0.7 ... 1.4, which sets the phase of its oscillation) are
    not crossed with it and with each other in full but laid over the
    friction grid as a Latin square (level (i + j) mod 3 and (i + 2 j) mod 5
    at friction point (i, j)): every level of each appears with every level
    of mu_c and of the ratio, in 25 points instead of 375.

    Parameters
    ----------
    names : sequence of str
        Names of the fitted values.
    vals : dict of str to float
        Their given values [units of each]; the grid is relative to them.

    Returns
    -------
    list of dict
        Starting points [units of each].
    """
    f_c = (0.7, 0.85, 1.0, 1.15, 1.3) if "mu_c" in names else (None,)
    ratios = (1.02, 1.15, 1.3, 1.5, 1.7) if "mu_s" in names else (None,)
    f_m = (0.9, 1.0, 1.1)
    f_j = (0.7, 0.85, 1.0, 1.2, 1.4)
    out = []
    if f_c == (None,) and ratios == (None,):  # no friction: the mass and inertia levels alone
        ms = [{"m_v": f * vals["m_v"]} for f in f_m] if "m_v" in names else [{}]
        js = [{"J_v": f * vals["J_v"]} for f in f_j] if "J_v" in names else [{}]
        return [dict(a, **b) for a in ms for b in js if a or b]
    for i, fc in enumerate(f_c):
        for j, r in enumerate(ratios):
            d = {}
            if fc is not None:
                d["mu_c"] = fc * vals["mu_c"]
            if r is not None:
                d["mu_s"] = r * d.get("mu_c", vals.get("mu_c", 0.4))
            if "m_v" in names:
                d["m_v"] = f_m[(i + j) % 3] * vals["m_v"]
            if "J_v" in names:
                d["J_v"] = f_j[(i + 2 * j) % 5] * vals["J_v"]
            out.append(d)
    return out


def _forward_jacobian(fun, u, step, upper, cols=None) -> np.ndarray:
    """Jacobian of the residual by forward differences (backward at an upper bound), scaled step ``step``;
    only the columns ``cols`` (a boolean mask; default all), the others zero."""
    r0 = fun(u)
    J = np.zeros((r0.size, u.size))
    for j in range(u.size):
        if cols is not None and not cols[j]:
            continue
        h = step * max(1.0, abs(u[j]))
        if u[j] + h > upper[j]:
            h = -h
        up = u.copy()
        up[j] += h
        J[:, j] = (fun(up) - r0) / h
    return J


def _autocov(x, w, k_lo, k_hi) -> np.ndarray:
    """Autocovariance of a gapped series at lags k_lo..k_hi [samples]: sum x_i x_(i+k) over the pairs whose
    samples are both present (weights w of 1 or 0), divided by their number."""
    n = x.size
    size = 1 << int(math.ceil(math.log2(2 * n)))
    fx, fw = np.fft.rfft(x * w, size), np.fft.rfft(w, size)
    num = np.fft.irfft(fx * np.conj(fx), size)[k_lo:k_hi + 1]
    den = np.fft.irfft(fw * np.conj(fw), size)[k_lo:k_hi + 1]
    return num / np.maximum(np.round(den), 1.0)


def _covariance(J, meat, G):
    """Covariance of the reported values: G (J^T J)^-1 S (J^T J)^-1 G^T (the sandwich; S = s^2 J^T J for white
    residuals gives G (J^T J)^-1 G^T s^2), the inverse taken on the non-singular directions of J^T J, which are
    flagged."""
    p = J.shape[1] if J.ndim == 2 else 0
    if p == 0:
        return np.zeros((0, 0)), np.zeros(0, bool)
    JTJ = J.T @ J
    w, V = np.linalg.eigh(JTJ)
    tol = max(w.max(), 1e-300) * 1e-10
    bad = w <= tol
    inv = (V[:, ~bad] / w[~bad]) @ V[:, ~bad].T
    cov_u = inv @ meat @ inv
    cov = G @ cov_u @ G.T
    # a reported value that loads noticeably (> 5 %) on a singular direction is not identifiable
    if bad.any():
        load_bad = np.linalg.norm(G @ V[:, bad], axis=1)
        load_all = np.linalg.norm(G @ V, axis=1)
        singular = load_bad > 0.05 * (load_all + 1e-300)
    else:
        singular = np.zeros(G.shape[0], bool)
    return cov, singular


def sweep(measurement: Measurement, params: Parameters, grid: dict, *, model: str = "macro", effects=(),
          t0: float | None = None) -> list[dict]:
    """Fit % of the model over a grid of parameter values (the paper's parametric study, Fig. 4).

    Parameters
    ----------
    measurement : Measurement
        The record.
    params : Parameters
        Setup.
    grid : dict of str to sequence
        Values per parameter; every combination is run (e.g.
        ``{"mu_c": [0.3, 0.4], "mu_s": [0.45, 0.51]}``).  Combinations the
        parameter rules refuse (mu_c > mu_s) are skipped.
    model : str, default 'macro'
        Model.
    effects : sequence of str
        Components added.
    t0 : float, optional
        Start of the experiment [s].

    Returns
    -------
    list of dict
        One row per combination: the values, ``fit_current_A`` and
        ``fit_speed_rpm`` [%], ``final_current_A`` [A] (model, mean of the
        last 5 s), or ``error``.
    """
    import itertools

    params = resolve_gains(params)
    exp = measurement.experiment(params, t0=t0)
    keys = list(grid)
    rows = []
    for combo in itertools.product(*(grid[k] for k in keys)):
        vals = dict(zip(keys, (float(v) for v in combo)))
        row = dict(vals)
        try:
            p = params.replace(**vals)
            run = run_model(p, measurement, exp, model=model, effects=effects)
        except KilnctlError as exc:
            row["error"] = str(exc)
            rows.append(row)
            continue
        active = measurement.t >= exp.t0 - 1e-9
        for c in CHANNELS:
            row[f"fit_{c}"] = fit_percent(measurement.channels[c][active], run.outputs[c])
        tt = run.t
        row["final_current_A"] = float(np.mean(run.outputs["current_A"][tt >= tt[-1] - 5.0]))
        rows.append(row)
    return rows
