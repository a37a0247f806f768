"""Verify a speed-loop design on the nonlinear plant.

The linear prediction (eq. 21 closed loop, stick and slip inertia, no load
torque) and the hybrid simulation of the same start-up ramp are compared on
what a drive engineer reads: speed overshoot after the ramp, settling time,
lag behind the ramp, peak and final current.  :func:`verify` also says where
and why the two part: the load torque the linear model does not carry, the
change of inertia when the burden breaks away, drive limits, and backlash.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import control as ct
import numpy as np

from .errors import SimulationError
from .figures import COLORS, Plotted, finish
from .params import Parameters
from .response import Response
from .units import RPM_PER_RAD_S
from .gains import resolve_gains
from .simulate import simulate

__all__ = ["Verification", "verify", "ramp_figures"]

#: the quantities of :meth:`Verification.table` as printed
QUANTITY_LABELS = {"overshoot_pct": "overshoot after the ramp [%]", "settle_time_s": "settled within 2 % from [s]",
                   "ramp_lag_rpm": "lag at the end of the ramp [rpm]", "peak_current_A": "peak current [A]",
                   "final_current_A": "final current [A]"}


def ramp_figures(t, speed_rpm, current_a, params: Parameters) -> dict:
    """Figures of a start-up ramp response.

    Parameters
    ----------
    t : array_like
        Time [s].
    speed_rpm : array_like
        Motor speed [rpm].
    current_a : array_like
        Armature current [A].
    params : Parameters
        For ``omega_ref`` [rpm] and ``ramp_rate`` [rpm/s].

    Returns
    -------
    dict
        ``overshoot_pct`` (above ``omega_ref`` after the ramp), ``settle_time_s``
        (speed within 2 % of ``omega_ref`` for good, or None), ``ramp_lag_rpm``
        (reference minus speed at the end of the ramp), ``peak_current_A``,
        ``final_current_A`` (mean of the last 5 s).
    """
    t, w, i = (np.asarray(a, dtype=float) for a in (t, speed_rpm, current_a))
    ref, t_r = params.omega_ref, params.omega_ref / params.ramp_rate
    after = t >= t_r
    out = np.abs(w - ref) > 0.02 * ref
    settle = None
    if not out[-1]:
        k = np.nonzero(out)[0]
        settle = float(t[k[-1] + 1]) if len(k) else float(t[0])
    last = t >= t[-1] - 5.0
    return {
        "overshoot_pct": float(max(0.0, (np.max(w[after]) - ref) / ref * 100.0)) if after.any() else None,
        "settle_time_s": settle,
        "ramp_lag_rpm": float(ref - np.interp(t_r, t, w)) if t[-1] >= t_r else None,
        "peak_current_A": float(np.max(np.abs(i))),
        "final_current_A": float(np.trapezoid(i[last], t[last]) / (t[last][-1] - t[last][0])),
    }


@dataclass
class Verification(Plotted):
    """Linear prediction against the nonlinear response of one start-up.

    Its figure (:meth:`plot`): speed and current, the linear stick/slip
    predictions and the nonlinear run.

    Attributes
    ----------
    params : Parameters
        Parameters with the gains used.
    linear : dict
        Per condition (``stick``, ``slip``): ``t``, ``speed_rpm``, ``i_a`` and
        ``figures`` (see :func:`ramp_figures`).
    nonlinear : Response
        The hybrid simulation.
    figures : dict
        Figures of the nonlinear run.
    reasons : list of str
        Where and why the nonlinear plant parts from the linear prediction.
    """

    params: Parameters
    linear: dict
    nonlinear: Response
    figures: dict
    reasons: list = field(default_factory=list)

    def table(self) -> list[dict]:
        """Rows ``quantity``, ``linear_stick``, ``linear_slip``, ``nonlinear``."""
        keys = ("overshoot_pct", "settle_time_s", "ramp_lag_rpm", "peak_current_A", "final_current_A")
        return [{"quantity": k, "linear_stick": self.linear["stick"]["figures"][k],
                 "linear_slip": self.linear["slip"]["figures"][k], "nonlinear": self.figures[k]} for k in keys]

    def to_dict(self) -> dict:
        """JSON-ready summary (no arrays)."""
        g = self.params
        return {"gains": {"kp": g.k_p, "ki": g.k_I, "kd": g.k_D}, "model": self.nonlinear.model,
                "table": self.table(), "reasons": list(self.reasons),
                "events": [{"t": e.t, "kind": e.kind, "component": e.component, "to": e.to_mode}
                           for e in self.nonlinear.events]}

    def __str__(self) -> str:
        def f(v):
            return "not reached" if v is None else f"{v:10.3f}"
        lines = [f"{'':<32} {'linear stick':>12} {'linear slip':>12} {'nonlinear':>12}"]
        for r in self.table():
            lines.append(f"{QUANTITY_LABELS.get(r['quantity'], r['quantity']):<32} {f(r['linear_stick']):>12} "
                         f"{f(r['linear_slip']):>12} {f(r['nonlinear']):>12}")
        lines.append("")
        lines += [f"- {r}" for r in self.reasons]
        return "\n".join(lines)

    figsize = (10, 7.4)

    def _draw(self, fig):
        ax1, ax2 = fig.subplots(2, 1, sharex=True)
        r = self.nonlinear
        # stick and slip predictions lie almost on each other: stick wide and pale, slip thin on top
        styles = {"stick": {"color": COLORS["model"], "lw": 3.5, "alpha": 0.45, "ls": "-"},
                  "slip": {"color": COLORS["model2"], "lw": 1.2, "alpha": 1.0, "ls": "--"}}
        for cond in ("stick", "slip"):
            lin = self.linear[cond]
            ax1.plot(lin["t"], lin["speed_rpm"], **styles[cond], label=f"linear, {cond} inertia")
            ax2.plot(lin["t"], lin["i_a"], **styles[cond], label=f"linear, {cond} inertia (no load torque)")
        ax1.plot(r.t, r["speed_ref_rpm"], color=COLORS["reference"], lw=0.8, label="speed reference")
        ax1.plot(r.t, r["speed_rpm"], color=COLORS["final"], lw=1.2, label=f"nonlinear {r.model} model")
        ax2.plot(r.t, r["i_a"], color=COLORS["final"], lw=1.2, label=f"nonlinear {r.model} model")
        kinds = {}
        for e in r.events:
            if (e.component in ("burden", "current_limit", "current_limit_pi", "voltage_limit")
                    and e.kind != "sliding_mode"):
                kinds.setdefault((e.component, e.kind), []).append(e.t)
        for n, ((comp, kind), times) in enumerate(kinds.items()):
            ls = (":", "-.", (0, (5, 2, 1, 2)))[n % 3]
            lab = f"{comp.replace('_', ' ')} {kind.replace('_', ' ')} at " + ", ".join(f"{t:.1f}" for t in times) + " s"
            for ax in (ax1, ax2):
                for k, t in enumerate(times):
                    ax.axvline(t, color=COLORS["event"], lw=0.9, ls=ls, label=lab if k == 0 else None)
        ax1.set_ylabel("motor speed [rpm]")
        ax2.set_ylabel("armature current [A]")
        ax2.set_xlabel("time [s]")
        ax1.set_title("speed", fontsize=10)
        ax2.set_title("current: the linear model carries no load torque, so it predicts only the "
                      "accelerating current", fontsize=10)
        for ax in (ax1, ax2):
            ax.grid(True, alpha=0.3)
            ax.legend(loc="lower right", fontsize=8)
        g = self.params
        return finish(fig, f"Design verified on the nonlinear {r.model} model (k_p = {g.k_p:.4g} V/rpm, "
                           f"k_I = {g.k_I:.4g} V/(rpm·s), k_D = {g.k_D:.4g} V·s/rpm)")


def _linear_run(params, gains, condition, t):
    from .linear import closed_loop_ss

    sys = closed_loop_ss(params, gains, condition)
    ev = np.minimum(params.ramp_rate * t, params.omega_ref)
    resp = ct.forced_response(sys, T=t, U=np.vstack([ev, np.zeros_like(t)]))
    w = np.asarray(resp.outputs[0]) * RPM_PER_RAD_S
    i = np.asarray(resp.outputs[1])
    return {"t": t, "speed_rpm": w, "i_a": i, "figures": ramp_figures(t, w, i, params)}


def verify(params: Parameters | None = None, model: str = "macro", t_end: float = 40.0, *, effects=(),
           components=None) -> Verification:
    """Run the designed (or given) gains on the nonlinear plant and compare with the linear design.

    Parameters
    ----------
    params : Parameters, optional
        Parameter set; with ``gains = 'design'`` the root-locus design is used.
    model : {'macro', 'micro'}
        Nonlinear model to verify on.
    t_end : float
        Simulated time [s]; must cover the ramp (omega_ref / ramp_rate).
    effects : sequence of str
        Components added to the nonlinear model (a structure a diagnosis
        learned: ``second_motor``, ``speed_sensor_lag`` ...); the linear
        prediction stays the design's rigid model.
    components : sequence of str or Structure, optional
        The full nonlinear component list, or a
        :class:`kilnctl.structure.Structure` (its effects' options set on the
        nonlinear run), instead of ``model``/``effects``.

    Returns
    -------
    Verification
    """
    from .gains import PIDGains

    params = resolve_gains(Parameters() if params is None else params)
    t_r = params.omega_ref / params.ramp_rate
    if not t_end > t_r:
        raise SimulationError(f"t_end = {t_end} s must exceed the ramp time omega_ref/ramp_rate = {t_r:.3g} s")
    gains = PIDGains(params.k_p, params.k_I, params.k_D)
    nl = simulate(params, model, t_end, effects=effects, components=components)
    t = np.linspace(0.0, t_end, int(round(t_end / 5e-3)) + 1)
    linear = {c: _linear_run(params, gains, c, t) for c in ("stick", "slip")}
    tt, uniq = np.unique(nl.t, return_index=True)
    figs = ramp_figures(tt, nl["speed_rpm"][uniq], nl["i_a"][uniq], params)
    reasons = []
    load = figs["final_current_A"] - linear["stick"]["figures"]["final_current_A"]
    lin_final = linear["stick"]["figures"]["final_current_A"]
    reasons.append(
        f"current: the linear model carries no load torque (T_l = 0) and ends at {lin_final:.0f} A; the nonlinear "
        f"plant ends at {figs['final_current_A']:.0f} A, "
        + ("all of which" if abs(lin_final) < 0.005 * abs(figs["final_current_A"])
           else f"and the difference, {load:.0f} A,")
        + f" holds the burden and bearing friction ({load * params.k_i * params.n / 1e6:.2f} MN*m at the kiln)")
    brk = [e for e in nl.events if e.component == "burden" and e.kind == "breakaway"]
    if brk:
        reasons.append(
            f"inertia: the burden breaks away at t = {brk[0].t:.2f} s; the motor then sees J_slip = "
            f"{params.J_slip:.2f} kg*m^2 instead of J_stick = {params.J_stick:.2f} kg*m^2, and the wall "
            "friction torque varies with the burden angle, which the linear load-free model does not show")
    lim = [e for e in nl.events if e.component in ("current_limit", "current_limit_pi", "voltage_limit")
           and "release" not in e.kind]
    if lim:
        reasons.append(f"limits: {lim[0].component} reached at t = {lim[0].t:.2f} s "
                       f"({len(lim)} times in all); the linear model has no limits")
    else:
        reasons.append(f"limits: neither current (I_max = {params.I_max:.0f} A) nor voltage (V_max = "
                       f"{params.V_max:.0f} V) limit was reached")
    if model == "micro":
        contacts = [e for e in nl.events if e.component == "mesh" and e.kind == "contact"]
        if contacts:
            reasons.append(f"backlash: the teeth engage at t = {contacts[0].t:.3f} s after taking up "
                           f"{params.delta_x * params.gap_0 * 1e3:.1f} mm, with {len(contacts)} contacts in all")
    ov_l, ov_n = linear["stick"]["figures"]["overshoot_pct"], figs["overshoot_pct"]
    if ov_l is not None and ov_n is not None:
        reasons.append(f"overshoot after the ramp: linear (stick) {ov_l:.2f} %, nonlinear {ov_n:.2f} %")
    return Verification(params, linear, nl, figs, reasons)
