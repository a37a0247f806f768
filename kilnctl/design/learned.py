"""Gains checked and retuned on a learned plant structure (a compliant drive train, a lagging sensor ...).

The root-locus design of :mod:`kilnctl.design.pid` works on the paper's rigid
two-inertia model.  A measurement may teach a structure with more dynamics
(``kilnctl diagnose``).  :func:`check_gains` linearizes that structure exactly
(:func:`kilnctl.linearize.linearize`, both load conditions) with the given
gains and lists every closed-loop mode the controller acts on, with its
damping against the requirement.  :func:`retune` then scales the gains (the
PID zeros stay where the rigid design put them: the root-locus gain of the
learned loop) to the value that maximises the least damping, and reports
what changed and why.

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

__all__ = ["LoopCheck", "check_gains", "retune", "Retuned", "learned_structure"]

#: a damping this close below the requirement still meets it (the root-locus design places poles on the limit)
ZETA_TOL = 5e-4
#: sensitivity (relative pole shift per relative gain change) below which the gains barely act on a mode: it
#: is not counted against the gains (no gain can damp it) but named when lightly damped
WEAK = 0.01


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
    """

    gains: PIDGains
    components: tuple
    modes: dict
    zeta_min: float
    requirements: Requirements

    @property
    def stable(self) -> bool:
        """True when no mode has a positive real part."""
        return all(r["pole"].real <= 1e-9 for rows in self.modes.values() for r in rows)

    @property
    def ok(self) -> bool:
        """True when stable and every moved mode is damped at least ``requirements.zeta_min``."""
        return self.stable and self.zeta_min >= self.requirements.zeta_min - ZETA_TOL

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
            elif not self.ok:
                text = (f"UNSAFE: {what} (burden {cond}) is damped only zeta = {r['zeta']:.3f}, below the required "
                        f"{self.requirements.zeta_min:.2f}: these gains will excite it")
            else:
                text = (f"safe: every mode the gains act on is damped at least zeta = {self.zeta_min:.3f} ({what}, "
                        f"burden {cond})")
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
        lines.append("  " + self.verdict())
        return "\n".join(lines)

    def to_dict(self) -> dict:
        """JSON-ready form (a damping that is not defined, at a pole at zero, is null)."""
        def num(v):
            return float(v) if isinstance(v, (float, np.floating)) and np.isfinite(v) else (
                v if not isinstance(v, (float, np.floating)) else None)

        return {"gains": self.gains.as_dict(), "components": list(self.components), "stable": self.stable,
                "ok": self.ok, "zeta_min": num(self.zeta_min), "verdict": self.verdict(),
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
    """Closed-loop modes of a structure with the given gains, both load conditions.

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
        Requirements (default: :class:`Requirements` defaults).
    conditions : sequence of {'stick', 'slip'}
        Burden conditions to linearize in.

    Returns
    -------
    LoopCheck
    """
    params = resolve_gains(params)
    bases = _linearized(params, components, conditions)
    return _check(bases, PIDGains(params.k_p, params.k_I, params.k_D) if gains is None else gains, requirements)


def _linearized(params, components, conditions=("stick", "slip")):
    """The structure linearized in each burden condition (the gains are swapped in later, exactly)."""
    from ..linearize import linearize

    return {c: linearize(params, components=components, burden=c) for c in conditions}


def _check(bases, gains, requirements=None, exclude=None) -> LoopCheck:
    """check_gains on structures already linearized (``bases``: condition -> LinearizedPlant); with
    ``exclude`` (condition -> natural frequencies [rad/s]) only modes near those may count as not moved."""
    req = Requirements() if requirements is None else requirements
    bumped = gains.scaled(1.01)
    modes = {}
    zmin = np.inf
    for cond, base in bases.items():
        la = base.with_gains(gains.k_p, gains.k_I, gains.k_D)
        lb = base.with_gains(bumped.k_p, bumped.k_I, bumped.k_D)
        rows = _rows(la, lb, None if exclude is None else exclude.get(cond, []))
        modes[cond] = rows
        for r in rows:
            if r["moved"] and r["omega_n_rad_s"] > 0:
                zmin = min(zmin, r["zeta"] if r["pole"].real <= 1e-9 else -np.inf)
    return LoopCheck(gains, tuple(next(iter(bases.values())).components), modes, float(zmin), req)


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
        (kappa, kd_factor, least damping) of every pair tried.
    best_found : tuple or None
        When no setting meets the requirement: the best damped (kappa, kd_factor, zeta); the gains are
        then not changed (``after is before``).
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
            why = (f" The limiting mode is {'the %.2f Hz pair' % r['f_hz'] if r['f_hz'] > 0 else 'a real pole'} "
                   f"with the burden {cond}.")
        if a is b and self.best_found is None:
            return ("On the learned structure the rigid design's gains meet the requirements: kept. "
                    + b.verdict() + "\n\n" + b.summary())
        if a is b:
            k, d, z = self.best_found
            return (f"On the learned structure the rigid design's gains give least damping zeta = {b.zeta_min:.3f}, "
                    f"below the required {b.requirements.zeta_min:.2f}, and no slower setting with k_D from 0.1 to 5 "
                    f"times meets it (the best, gains x {k:.3g} and k_D x {d:.3g}, gives zeta = {z:.3f}): gains NOT "
                    "changed. Loosen the requirement, remove the effect at its source (a faster speed sensor, a "
                    "stiffer coupling), or add a filter to the loop.\n\n" + b.summary())
        head = (f"On the learned structure the rigid design's gains give least damping zeta = {b.zeta_min:.3f} "
                f"({'meets' if b.ok else 'MISSES'} the required {b.requirements.zeta_min:.2f}).{why} "
                f"Gains x {self.kappa:.3g}" + (f" and k_D x {self.kd_factor:.3g}" if self.kd_factor != 1 else
                                               " (zeros kept)")
                + f": {a.gains}, least damping zeta = {a.zeta_min:.3f}"
                + ("" if a.ok else f", still below {a.requirements.zeta_min:.2f}: no slower setting with k_D from "
                   "0.1 to 5 times meets the requirement on this structure; loosen it, or remove the effect at its "
                   "source (a faster sensor, a stiffer coupling) or add a filter") + ".")
        return head + "\n\nbefore:\n" + b.summary() + "\n\nafter:\n" + a.summary()

    def to_dict(self) -> dict:
        """JSON-ready form."""
        return {"kappa": self.kappa, "kd_factor": self.kd_factor, "before": self.before.to_dict(),
                "after": self.after.to_dict(), "scan": [list(x) for x in self.scan]}


def retune(params: Parameters, components, gains: PIDGains | None = None,
           requirements: Requirements | None = None, kappas=None) -> Retuned:
    """Slow the gains down (and move k_D) until the learned structure meets the damping requirement.

    Parameters
    ----------
    params : Parameters
        Parameters of the structure.
    components : Structure or sequence of str
        The learned plant structure.
    gains : PIDGains, optional
        Starting gains (default: the rigid root-locus design for ``params``).
    requirements : Requirements, optional
    kappas : sequence of float, optional
        Scales of all three gains to try (default: 31 values from 0.05 to 1,
        log spaced), each with k_D scaled further by 15 factors from 0.1 to
        5.  The rigid design is the fastest the requirements allow
        (natural-frequency cap, settling time), so the gains are only slowed
        down: the largest scale (then the k_D factor closest to 1) that meets
        ``zeta_min``, else the best damped.

    Returns
    -------
    Retuned

    Raises
    ------
    DesignError
        When no scale gives a stable loop.

    Notes
    -----
    When no setting meets the requirement the gains are kept (``after is
    before``) and ``best_found`` says what the best setting would give.
    """
    params = resolve_gains(params)
    gains = PIDGains(params.k_p, params.k_I, params.k_D) if gains is None else gains
    req = Requirements() if requirements is None else requirements
    bases = _linearized(params, components)
    before = _check(bases, gains, req)
    # modes the reference gains barely act on (a drive-train resonance, the burden's pendulum) stay out of the
    # objective for every candidate: no gain damps them, and a loop mode must not drop out because slower
    # gains act on it less
    exclude = {c: [r["omega_n_rad_s"] for r in rows if not r["moved"]] for c, rows in before.modes.items()}
    if before.ok:
        return Retuned(before, before, 1.0, 1.0, [])
    ks = np.geomspace(0.05, 1.0, 31) if kappas is None else np.asarray(kappas, float)
    ds = np.unique(np.concatenate([np.geomspace(0.1, 5.0, 15), [1.0]]))
    scan = []
    for k in ks:
        for d in ds:
            g = PIDGains(k * gains.k_p, k * gains.k_I, k * d * gains.k_D)
            scan.append((float(k), float(d), _check(bases, g, req, exclude).zeta_min))
    # the rigid design is the fastest the requirements allow (omega_n cap, settling): on the learned structure
    # the gains are only ever slowed down; k_D may go either way. Among the settings that meet zeta_min: the
    # largest scale, then the k_D factor closest to 1; else the best damped
    meeting = [x for x in scan if x[2] >= req.zeta_min - ZETA_TOL]
    best = (max(meeting, key=lambda x: (round(x[0], 9), -abs(np.log(x[1])))) if meeting
            else max(scan, key=lambda x: x[2]))
    if not np.isfinite(best[2]) or best[2] < 0:
        raise DesignError("no scale of the gains gives a stable loop on this structure "
                          f"({'+'.join(before.components)}); the PID structure itself has to change")
    if not meeting:  # nothing meets the requirement: keep the rigid design, and say what the best would give
        return Retuned(before, before, 1.0, 1.0, scan, best_found=best)
    new = PIDGains(best[0] * gains.k_p, best[0] * gains.k_I, best[0] * best[1] * gains.k_D)
    after = _check(bases, new, req, exclude)
    return Retuned(before, after, best[0], best[1], scan)


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
