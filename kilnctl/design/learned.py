"""Gains checked and retuned on a learned plant structure (a compliant drive train, a lagging sensor ...).

The root-locus design of :mod:`kilnctl.design.pid` works on the paper's rigid
two-inertia model.  A measurement may teach a structure with more dynamics
(``kilnctl diagnose``).  :func:`check_gains` linearizes that structure exactly
(:func:`kilnctl.linearize.linearize`, both load conditions) with the given
gains, lists every closed-loop mode the controller acts on and holds the loop
to every requirement the rigid design was held to (:class:`Requirements`:
damping ``zeta_min``, dominant natural frequency ``wn_max``, settling time and
overshoot of the speed after a reference step), in both burden conditions.
:func:`retune` then searches an overall gain scale and a further factor on
k_D for the smallest change from the given gains that meets them all, and
reports what changed and why (or which requirement no setting meets).

A mode the controller cannot move (the sliding burden's pendulum, eq. 25; a
kinematic angle) is listed apart: no gain changes it, so it does not count
against the gains.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..errors import DesignError
from ..gains import PIDGains, resolve_gains
from ..params import Parameters
from ..structure import Structure, diagnosis_dict
from .requirements import Requirements

__all__ = ["LoopCheck", "check_gains", "retune", "Retuned", "learned_structure", "diagnosis_cautions", "gain_change"]

#: a damping this close below the requirement still meets it (the root-locus design places poles on the limit)
ZETA_TOL = 5e-4
#: sensitivity (relative pole shift per relative gain change) below which the gains barely act on a mode: it
#: is not counted against the gains (no gain can damp it) but named when lightly damped
WEAK = 0.01
#: relative excess of the dominant natural frequency over wn_max still counted as meeting it: the rigid design
#: places the pole on wn_max by eq. 21, which leaves out the bearing friction's slope the exact linearization
#: keeps (it moves the stuck-burden pole by up to 0.1 %)
WN_TOL = 2e-3


@dataclass
class LoopCheck:
    """Closed-loop modes of a structure with given gains, in both load conditions.

    Attributes
    ----------
    gains : PIDGains
    components : tuple of str
    modes : dict
        ``{condition: [row, ...]}``, each row ``pole`` [rad/s], ``omega_n_rad_s``, ``f_hz``,
        ``zeta`` [-], ``moved`` (True when the gains move the mode) and ``sensitivity``
        (relative pole shift per relative gain change [-]: below about 0.01 the gains barely act on it).
    zeta_min : float
        Least damping ratio over the modes the gains act on (sensitivity >= WEAK; -inf when one is unstable).
    requirements : Requirements
        Resolved (``wn_max`` a number [rad/s]).
    figures : dict
        ``{condition: {'dominant_wn': rad/s, 'settling_time': s, 'overshoot': %}}``: the dominant mode (the
        mode the gains act on nearest the imaginary axis) and the step of the speed ``speed_rpm`` after a
        step of ``speed_ref`` on the linear model (None: not computed, or unstable).
    """

    gains: PIDGains
    components: tuple
    modes: dict
    zeta_min: float
    requirements: Requirements
    figures: dict = field(default_factory=dict)

    @property
    def stable(self) -> bool:
        """True when no mode has a positive real part."""
        return all(r["pole"].real <= 1e-9 for rows in self.modes.values() for r in rows)

    @property
    def safe(self) -> bool:
        """True when stable and every moved mode is damped at least ``requirements.zeta_min``."""
        return self.stable and self.zeta_min >= self.requirements.zeta_min - ZETA_TOL

    @property
    def ok(self) -> bool:
        """True when every requirement is met in both burden conditions (:meth:`unmet` is empty)."""
        return not self.unmet()

    def unmet(self) -> list[tuple[str, str, float]]:
        """The requirements these gains miss on this structure.

        Returns
        -------
        list of (str, str, float)
            ``(requirement name, sentence with the numbers, relative violation [-])``, as
            :func:`kilnctl.design.analysis.unmet_requirements`; empty when all are met.
        """
        req, out = self.requirements, []
        if not self.stable:
            return [("stability", "closed loop unstable on this structure", 1e3)]
        if self.zeta_min < req.zeta_min - ZETA_TOL:
            cond, r = self.weakest()
            out.append(("zeta_min", f"damping ratio {r['zeta']:.3f} < zeta_min = {req.zeta_min:g} ({cond})",
                        (req.zeta_min - r["zeta"]) / max(req.zeta_min, 1e-3)))
        for cond, f in self.figures.items():
            wn, ts, os_ = f.get("dominant_wn"), f.get("settling_time"), f.get("overshoot")
            if wn is not None and req.wn_max is not None and wn > req.wn_max * (1 + WN_TOL):
                out.append(("wn_max", f"dominant natural frequency {wn:.3f} rad/s > wn_max = {req.wn_max:.3f} "
                            f"rad/s ({cond})", (wn - req.wn_max) / req.wn_max))
            if ts is not None and ts > req.settling_time_max * (1 + 1e-6):
                out.append(("settling_time_max", f"settling time {ts:.3f} s > settling_time_max = "
                            f"{req.settling_time_max:g} s ({cond})",
                            (ts - req.settling_time_max) / req.settling_time_max))
            if os_ is not None and os_ > req.overshoot_max + 1e-6:
                out.append(("overshoot_max", f"overshoot {os_:.3f} % > overshoot_max = {req.overshoot_max:g} % "
                            f"({cond})", (os_ - req.overshoot_max) / max(req.overshoot_max, 1.0)))
        return out

    def weakest(self) -> tuple[str, dict] | None:
        """The condition and row of the least damped mode the gains move."""
        best = None
        for cond, rows in self.modes.items():
            for r in rows:
                if r["moved"] and r["omega_n_rad_s"] > 0 and (best is None or r["zeta"] < best[1]["zeta"]):
                    best = (cond, r)
        return best

    def verdict(self) -> str:
        """Plain sentences on whether these gains are safe on this structure."""
        w = self.weakest()
        if w is None:
            text = "no closed-loop mode depends on the gains"
        else:
            cond, r = w
            what = (f"the {r['f_hz']:.2f} Hz mode" if r["f_hz"] > 0 else f"the real pole at {r['pole'].real:.3g} rad/s")
            if not self.stable:
                text = (f"UNSAFE: the loop is UNSTABLE on this structure ({what}, burden {cond}, has a positive real "
                        "part): do not use these gains on this kiln")
            elif not self.safe:
                text = (f"UNSAFE: {what} (burden {cond}) is damped only zeta = {r['zeta']:.3f}, below the required "
                        f"{self.requirements.zeta_min:.2f}: these gains will excite it")
            else:
                text = (f"safe: every mode the gains act on is damped at least zeta = {self.zeta_min:.3f} ({what}, "
                        f"burden {cond})")
                other = [s for name, s, _ in self.unmet() if name != "zeta_min"]
                text += (f"; but it misses: {'; '.join(other)}" if other else
                         "; every requirement met in both burden conditions" if self.figures else "")
        for cond, rows in self.modes.items():
            for r in rows:
                if (not r["moved"] and r["f_hz"] > 0.05 and r["zeta"] < self.requirements.zeta_min
                        and r["sensitivity"] > 0):
                    text += (f". Note: the {r['f_hz']:.2f} Hz mode (burden {cond}) is damped only zeta = "
                             f"{r['zeta']:.3f} and the gains barely act on it (a 1 % gain change moves it "
                             f"{r['sensitivity']:.1e} %): damp it mechanically or with a filter, and keep the loop "
                             "well below it")
                    break
        return text

    def summary(self) -> str:
        """Table of the modes per load condition, and the verdict."""
        lines = [f"gains {self.gains} on {'+'.join(self.components)}"]
        for cond, rows in self.modes.items():
            lines.append(f"  burden {cond}:")
            for r in rows:
                if r["omega_n_rad_s"] == 0:
                    continue
                kind = "" if r["moved"] else "   (not moved by the gains)"
                lines.append(f"    omega_n {r['omega_n_rad_s']:8.3f} rad/s  f {r['f_hz']:6.3f} Hz  "
                             f"zeta {r['zeta'] + 0.0:7.3f}{kind}")
            f = self.figures.get(cond)
            if f and f.get("settling_time") is not None:
                lines.append(f"    dominant omega_n {f['dominant_wn']:.3f} rad/s (<= {self.requirements.wn_max:.3f}), "
                             f"speed step: settling {f['settling_time']:.3f} s (<= "
                             f"{self.requirements.settling_time_max:g}), overshoot {f['overshoot']:.2f} % (<= "
                             f"{self.requirements.overshoot_max:g})")
        lines.append("  " + self.verdict())
        return "\n".join(lines)

    def to_dict(self) -> dict:
        """JSON-ready form (a damping that is not defined, at a pole at zero, is null)."""
        def num(v):
            return float(v) if isinstance(v, (float, np.floating)) and np.isfinite(v) else (
                v if not isinstance(v, (float, np.floating)) else None)

        return {"gains": self.gains.as_dict(), "components": list(self.components), "stable": self.stable,
                "ok": self.ok, "safe": self.safe, "zeta_min": num(self.zeta_min), "verdict": self.verdict(),
                "unmet": [s for _, s, _ in self.unmet()],
                "figures": {c: {k: num(v) for k, v in f.items()} for c, f in self.figures.items()},
                "modes": {c: [{**{k: num(v) for k, v in r.items() if k != "pole"}, "re": float(r["pole"].real),
                               "im": float(r["pole"].imag)} for r in rows if r["omega_n_rad_s"] > 0]
                          for c, rows in self.modes.items()}}


def _rows(lin_a, lin_b, exclude=None):
    """Rows of lin_a's modes; ``moved`` False for a mode the gains barely act on (with ``exclude``: only
    for modes near the natural frequencies [rad/s] listed there, the ones found so at the reference gains)."""
    pb = lin_b.poles()
    rows = []
    for r in lin_a.table():
        s = r["pole"]
        shift = float(np.min(np.abs(pb - s)) / max(abs(s), 1.0)) if abs(s) > 0 else 0.0
        weak = shift / 0.01 < WEAK
        if exclude is not None:
            weak = weak and any(abs(r["omega_n_rad_s"] - w) <= 0.1 * w for w in exclude)
        rows.append({**r, "moved": not weak, "sensitivity": shift / 0.01})
    return rows


def check_gains(params: Parameters, components, gains: PIDGains | None = None,
                requirements: Requirements | None = None, conditions=("stick", "slip")) -> LoopCheck:
    """Closed-loop modes of a structure with the given gains, both load conditions, against every requirement.

    Parameters
    ----------
    params : Parameters
        Parameters of the structure (e.g. a diagnosis' calibrated values).
    components : Structure or sequence of str
        The plant structure (:class:`kilnctl.structure.Structure`, or the
        component names of :func:`kilnctl.model.component_names`).
    gains : PIDGains, optional
        Gains to check (default: those of ``params`` after design resolution).
    requirements : Requirements, optional
        Requirements (default: :class:`Requirements` defaults; ``wn_max`` resolved from ``params``).
    conditions : sequence of {'stick', 'slip'}
        Burden conditions to linearize in.

    Returns
    -------
    LoopCheck
    """
    params = resolve_gains(params)
    req = (Requirements() if requirements is None else requirements).resolve(params)
    bases = _linearized(params, components, conditions)
    return _check(bases, PIDGains(params.k_p, params.k_I, params.k_D) if gains is None else gains, req, step=True)


def _linearized(params, components, conditions=("stick", "slip")):
    """The structure linearized in each burden condition (the gains are swapped in later, exactly)."""
    from ..linearize import linearize

    return {c: linearize(params, components=components, burden=c) for c in conditions}


def _step_figures(lin, rows) -> dict:
    """Dominant natural frequency [rad/s], settling time [s] and overshoot [%] of ``speed_rpm`` after a step of
    ``speed_ref`` on one linearized closed loop (the same step information as :func:`analysis.analyse`)."""
    import control as ct

    from .analysis import step_samples

    moved = [r for r in rows if r["moved"] and r["omega_n_rad_s"] > 0]
    if not moved or any(r["pole"].real > 1e-9 for r in moved):
        return {"dominant_wn": None, "settling_time": None, "overshoot": None}
    dom = max(moved, key=lambda r: r["pole"].real)
    slowest = -dom["pole"].real
    fastest = max(r["omega_n_rad_s"] for r in moved)
    t_final = 8.0 / slowest
    t = np.linspace(0.0, t_final, int(min(20_000, max(3000, 20 * t_final * fastest))))
    y = step_samples(lin.sys[list(lin.sys.output_labels).index("speed_rpm"), 0], t)
    info = ct.step_info(y, timepts=t)
    return {"dominant_wn": float(dom["omega_n_rad_s"]), "settling_time": float(info["SettlingTime"]),
            "overshoot": float(info["Overshoot"])}


def _check(bases, gains, requirements=None, exclude=None, step=False) -> LoopCheck:
    """check_gains on structures already linearized (``bases``: condition -> LinearizedPlant); with
    ``exclude`` (condition -> natural frequencies [rad/s]) only modes near those may count as not moved; with
    ``step`` the step of the speed too (settling time, overshoot), else only the poles."""
    req = Requirements() if requirements is None else requirements
    if req.wn_max is None:
        req = req.resolve(next(iter(bases.values())).params)
    bumped = gains.scaled(1.01)
    modes, figures = {}, {}
    zmin = np.inf
    for cond, base in bases.items():
        la = base.with_gains(gains.k_p, gains.k_I, gains.k_D)
        lb = base.with_gains(bumped.k_p, bumped.k_I, bumped.k_D)
        rows = _rows(la, lb, None if exclude is None else exclude.get(cond, []))
        modes[cond] = rows
        for r in rows:
            if r["moved"] and r["omega_n_rad_s"] > 0:
                zmin = min(zmin, r["zeta"] if r["pole"].real <= 1e-9 else -np.inf)
        if step:
            figures[cond] = _step_figures(la, rows)
        else:
            moved = [r for r in rows if r["moved"] and r["omega_n_rad_s"] > 0]
            figures[cond] = {"dominant_wn": (max(moved, key=lambda r: r["pole"].real)["omega_n_rad_s"]
                                             if moved else None)}
    return LoopCheck(gains, tuple(next(iter(bases.values())).components), modes, float(zmin), req, figures)


#: gain scales (all three gains) and further k_D factors of the coarse search of :func:`retune` [-]
KAPPAS = np.unique(np.concatenate([np.geomspace(0.05, 2.0, 41), [1.0]]))
KD_FACTORS = np.unique(np.concatenate([np.geomspace(0.1, 5.0, 15), [1.0]]))


def gain_change(kappa: float, kd_factor: float) -> float:
    """Size of a change of the gains: the root sum of squares of the log ratios of k_p, k_I and k_D [-].

    Parameters
    ----------
    kappa : float
        Factor on all three gains [-].
    kd_factor : float
        Further factor on k_D [-].

    Returns
    -------
    float
        ``sqrt(2 ln(kappa)^2 + ln(kappa kd_factor)^2)``: 0 for the given gains; about the relative change
        for small ones.
    """
    return float(np.sqrt(2 * np.log(kappa) ** 2 + np.log(kappa * kd_factor) ** 2))


def _violation(check: LoopCheck) -> float:
    """Sum of the relative violations of the requirements [-] (0: all met)."""
    return float(sum(v for _, _, v in check.unmet()))


@dataclass
class Retuned:
    """Gains retuned on a learned structure.

    Attributes
    ----------
    before, after : LoopCheck
        The rigid design's gains and the retuned ones, checked on the learned structure.
    kappa : float
        Factor on all three of the rigid design's gains.
    kd_factor : float
        Further factor on k_D (1: the PID zeros stay where the rigid design put them).
    scan : list of tuple
        (kappa, kd_factor, least damping [-], largest dominant natural frequency [rad/s]) of every pair tried.
    best_found : tuple or None
        When no setting meets every requirement: ``(kappa, kd_factor, LoopCheck)`` of the closest one (the
        least summed relative violation); the gains are then not changed (``after is before``).
    """

    before: LoopCheck
    after: LoopCheck
    kappa: float
    kd_factor: float
    scan: list = field(default_factory=list)
    best_found: tuple | None = None

    def summary(self) -> str:
        """What changed and why, in words and two tables."""
        b, a = self.before, self.after
        w = b.weakest()
        why = ""
        if w is not None:
            cond, r = w
            why = (f" The least damped mode is {'the %.2f Hz pair' % r['f_hz'] if r['f_hz'] > 0 else 'a real pole'} "
                   f"with the burden {cond}.")
        missed = "; ".join(s for _, s, _ in b.unmet())
        rng = (f"no setting with the gains x {KAPPAS[0]:g} to {KAPPAS[-1]:g} and k_D x {KD_FACTORS[0]:g} to "
               f"{KD_FACTORS[-1]:g} meets every requirement")
        if a is b and self.best_found is None:
            return ("On the learned structure the rigid design's gains meet every requirement in both burden "
                    "conditions: kept. " + b.verdict() + "\n\n" + b.summary())
        if a is b:
            k, d, best = self.best_found
            return (f"On the learned structure the rigid design's gains miss: {missed}. {rng[0].upper() + rng[1:]}: the "
                    f"closest, gains x {k:.3g} and k_D x {d:.3g}, still misses: "
                    + "; ".join(s for _, s, _ in best.unmet()) + ". Gains NOT changed. Loosen the requirement, "
                    "remove the effect at its source (a faster speed sensor, a stiffer coupling), or add a filter "
                    "to the loop.\n\n" + b.summary() + "\n\nclosest setting:\n" + best.summary())
        head = (f"On the learned structure the rigid design's gains give least damping zeta = {b.zeta_min:.3f} "
                f"({'meets' if b.safe else 'MISSES'} the required {b.requirements.zeta_min:.2f}).{why}"
                + (f" They miss: {missed}." if missed else "")
                + f" Gains x {self.kappa:.3g}" + (f" and k_D x {self.kd_factor:.3g}" if self.kd_factor != 1 else
                                                  " (zeros kept)")
                + f" (the smallest change found that meets every requirement): {a.gains}, least damping zeta = "
                f"{a.zeta_min:.3f}, dominant omega_n "
                + " and ".join(f"{f['dominant_wn']:.2f} rad/s ({c})" for c, f in a.figures.items())
                + f" (<= {a.requirements.wn_max:.2f}).")
        return head + "\n\nbefore:\n" + b.summary() + "\n\nafter:\n" + a.summary()

    def to_dict(self) -> dict:
        """JSON-ready form."""
        out = {"kappa": self.kappa, "kd_factor": self.kd_factor, "before": self.before.to_dict(),
               "after": self.after.to_dict(), "scan": [list(x) for x in self.scan]}
        if self.best_found is not None:
            k, d, c = self.best_found
            out["best_found"] = {"kappa": k, "kd_factor": d, **c.to_dict()}
        return out


def retune(params: Parameters, components, gains: PIDGains | None = None,
           requirements: Requirements | None = None, kappas=None) -> Retuned:
    """Change the gains as little as possible until the learned structure meets every requirement.

    Parameters
    ----------
    params : Parameters
        Parameters of the structure.
    components : Structure or sequence of str
        The learned plant structure.
    gains : PIDGains, optional
        Starting gains (default: the rigid root-locus design for ``params``).
    requirements : Requirements, optional
        The requirements the rigid design was held to (default: :class:`Requirements` defaults; ``wn_max``
        resolved from ``params``).
    kappas : sequence of float, optional
        Scales of all three gains to try (default :data:`KAPPAS`: 0.05 to 2, log spaced, and 1), each with
        k_D scaled further by :data:`KD_FACTORS` (0.1 to 5, and 1).

    Returns
    -------
    Retuned

    Raises
    ------
    DesignError
        When no scale gives a stable loop.

    Notes
    -----
    Two parameters: the scale keeps the PID zeros and moves the poles along the root locus of the learned
    loop (speed, ``wn_max``, settling); the k_D factor moves the zeros (damping). Every pair of the grid is
    checked on the poles (``zeta_min``, ``wn_max``, both burden conditions); the grid is refined around the
    smallest change (:func:`gain_change`) that meets them, and the candidates are then checked in order of
    change on the speed step too (settling time, overshoot) until one meets every requirement. When none
    does, the gains are kept (``after is before``) and ``best_found`` gives the closest setting and what it
    still misses.
    """
    params = resolve_gains(params)
    gains = PIDGains(params.k_p, params.k_I, params.k_D) if gains is None else gains
    req = (Requirements() if requirements is None else requirements).resolve(params)
    bases = _linearized(params, components)
    before = _check(bases, gains, req, step=True)
    # modes the reference gains barely act on (a drive-train resonance, the burden's pendulum) stay out of the
    # objective for every candidate: no gain damps them, and a loop mode must not drop out because slower
    # gains act on it less
    exclude = {c: [r["omega_n_rad_s"] for r in rows if not r["moved"]] for c, rows in before.modes.items()}
    if before.ok:
        return Retuned(before, before, 1.0, 1.0, [])
    ks = KAPPAS if kappas is None else np.asarray(kappas, float)
    checks = {}

    def pole_check(k, d):
        key = (round(float(k), 12), round(float(d), 12))
        if key not in checks:
            checks[key] = _check(bases, PIDGains(k * gains.k_p, k * gains.k_I, k * d * gains.k_D), req, exclude)
        return checks[key]

    for k in ks:
        for d in KD_FACTORS:
            pole_check(k, d)
    feasible = sorted((key for key, c in checks.items() if c.ok), key=lambda key: gain_change(*key))
    if feasible:  # refine around the smallest change: one coarse step each way, 9 x 9
        k0, d0 = feasible[0]
        sk = np.log(ks[1] / ks[0]) if len(ks) > 1 else 0.1
        sd = np.log(KD_FACTORS[1] / KD_FACTORS[0])
        for k in k0 * np.exp(np.linspace(-sk, sk, 9)):
            for d in d0 * np.exp(np.linspace(-sd, sd, 9)):
                pole_check(k, d)
        feasible = sorted((key for key, c in checks.items() if c.ok), key=lambda key: gain_change(*key))
    scan = [(k, d, c.zeta_min, max((f["dominant_wn"] or 0.0) for f in c.figures.values()))
            for (k, d), c in checks.items()]
    for k, d in feasible[:40]:  # the step of the speed too, smallest change first
        full = _check(bases, PIDGains(k * gains.k_p, k * gains.k_I, k * d * gains.k_D), req, exclude, step=True)
        if full.ok:
            return Retuned(before, full, float(k), float(d), scan)
    stable = [key for key, c in checks.items() if c.stable and np.isfinite(c.zeta_min) and c.zeta_min >= 0]
    if not stable:
        raise DesignError("no scale of the gains gives a stable loop on this structure "
                          f"({'+'.join(before.components)}); the PID structure itself has to change")
    # nothing meets every requirement: keep the rigid design, and say what the closest setting still misses
    k, d = min(stable, key=lambda key: (_violation(checks[key]), gain_change(*key)))
    best = _check(bases, PIDGains(k * gains.k_p, k * gains.k_I, k * d * gains.k_D), req, exclude, step=True)
    return Retuned(before, before, 1.0, 1.0, scan, best_found=(float(k), float(d), best))


def learned_structure(path, model: str | None = None, base: Parameters | None = None):
    """The plant structure and calibrated parameters a ``kilnctl diagnose --json`` file describes.

    Parameters
    ----------
    path : path-like, dict or Diagnosis
        JSON written by ``kilnctl diagnose --json`` (or ``diagnose.json`` of its ``--report`` folder), its
        content, or a fitted :class:`~kilnctl.measure.diagnose.Diagnosis`.
    model : str, optional
        Base model (default: the one the diagnosis used).
    base : Parameters, optional
        The setup the record was diagnosed with (default: Table 1); the
        diagnosis' calibrated values replace its entries.

    Returns
    -------
    structure : Structure
        The diagnosis' model with its selected effects.
    params : Parameters
        ``base`` with the diagnosis' final calibrated values and the selected effects' options.
    selected : list of str
        The selected effects.

    Raises
    ------
    ConfigFileError
        The file is missing, not JSON, or not a diagnosis.
    """
    d = diagnosis_dict(path)
    structure = Structure.from_diagnosis(d, model)
    values = {k: v["value"] for k, v in d["final_parameters"].items() if isinstance(v, dict) and "value" in v}
    base = Parameters() if base is None else base
    params = base.replace(**values) if values else base
    return structure, structure.apply(params), list(structure.effects)


def diagnosis_cautions(path) -> list[str]:
    """What the diagnosis behind a learned structure said to read before acting on it.

    A model learned from a record is only as good as the diagnosis says: its cautions (an effect's value far
    outside its usual range, a rival that fits as well, weak evidence under coloured noise) and what it left
    unexplained go with the model to every command that uses it (``design``, ``verify``, ``optimize-ramp``
    ``--model-from``).

    Parameters
    ----------
    path : path-like, dict or Diagnosis
        As for :func:`learned_structure`.

    Returns
    -------
    list of str
        The diagnosis' cautions, then ``"unexplained: ..."`` when it left structure unexplained; empty when it
        said nothing of the kind.

    Raises
    ------
    ConfigFileError
        The file is missing, not JSON, or not a diagnosis.
    """
    d = diagnosis_dict(path)
    out = [str(c) for c in d.get("caveats") or []]
    unexplained = d.get("unexplained")
    if isinstance(unexplained, dict) and unexplained.get("hint"):
        out.append(f"unexplained: {unexplained['hint']}")
    return out
