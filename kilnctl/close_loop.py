"""Close the loop: redesign, verify and optimize on the structure a measurement taught.

``kilnctl diagnose`` learns a plant structure from a start-up record (the
paper's model plus the effects the data support, with calibrated values).
:func:`close_the_loop` takes that structure through the rest of the
toolkit in one call:

1. the rigid root-locus design (the paper's model, the calibrated values) --
   the gains one would use without the diagnosis;
2. both sets of gains checked on the exact linearization of the learned
   structure (:func:`kilnctl.linearize.linearize`, burden stuck and sliding)
   and the gains redesigned there (:func:`kilnctl.design.learned.retune`),
   with the root locus of the learned model over the gain scale;
3. both designs verified on the learned hybrid plant (the micro model,
   with backlash and coupling, plus the learned effects) with the paper's
   74 rpm/s ramp;
4. the start-up ramp optimized on the learned structure with the
   redesigned gains (:func:`kilnctl.optimize.optimize_ramp`) and its
   optimum verified on the same hybrid plant.

The result, :class:`LoopStudy`, gives the side-by-side table (``table``,
``to_markdown``, ``to_csv``), a plain summary and ``plot()``.
"""

from __future__ import annotations

import csv
import io
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .errors import ParameterError
from .gains import PIDGains
from .params import Parameters

__all__ = ["close_the_loop", "LoopStudy", "COLUMNS"]

#: the three cases of the table: (key, heading)
COLUMNS = (("rigid", "rigid design, paper ramp"),
           ("redesigned", "redesigned, paper ramp"),
           ("optimized", "redesigned, optimized ramp"))
#: gain scales of the root locus of the learned model [-]
LOCUS_KAPPAS = np.geomspace(0.05, 4.0, 161)


@dataclass
class LoopStudy:
    """The loop diagnose -> redesign -> verify -> optimize on one learned structure.

    Attributes
    ----------
    record : str
        Name of the record the structure was learned from ('' if not known).
    selected : list of str
        The effects the diagnosis selected.
    components : tuple of str
        The learned structure (as linearized and redesigned).
    hybrid_components : tuple of str
        The hybrid plant the designs and the ramp are verified on.
    params : Parameters
        Calibrated values of the learned structure (gains: the redesigned ones).
    requirements : Requirements
        The requirements, resolved (``wn_max`` a number) [rad/s].
    retuned : kilnctl.design.learned.Retuned
        ``before`` (the rigid design's gains) and ``after`` (the redesigned ones) checked on the learned structure.
    locus : dict
        ``{'rigid'|'redesigned': {'stick'|'slip': poles}}``, poles an array (len(kappas), n) [rad/s]: the closed
        loop with the gains scaled by each of ``kappas``.
    kappas : numpy.ndarray
        Gain scales of the locus [-].
    measures : dict
        ``{column: StartupMeasures}`` on the hybrid plant (see :data:`COLUMNS`).
    figures : dict
        ``{column: dict}`` of :func:`kilnctl.verify.ramp_figures` (settling, overshoot) of each hybrid run.
    responses : dict
        ``{column: Response}``, the hybrid runs.
    ramp : kilnctl.optimize.RampResult
        The ramp optimization on the learned structure.
    seconds : dict
        Wall time of each step [s].
    """

    record: str
    selected: list
    components: tuple
    hybrid_components: tuple
    params: Parameters
    requirements: object
    retuned: object
    locus: dict
    kappas: np.ndarray
    measures: dict
    figures: dict
    responses: dict = field(repr=False, default_factory=dict)
    ramp: object = field(repr=False, default=None)
    seconds: dict = field(default_factory=dict)

    # --- what the table is made of ------------------------------------------------------
    @property
    def gains(self) -> dict:
        """``{column: PIDGains}``: the rigid design, then the redesigned gains (twice)."""
        b, a = self.retuned.before.gains, self.retuned.after.gains
        return {"rigid": b, "redesigned": a, "optimized": a}

    def _check(self, column):
        return self.retuned.before if column == "rigid" else self.retuned.after

    def limiting_mode(self, column: str) -> dict:
        """The least damped closed-loop mode the gains act on, on the learned structure.

        Parameters
        ----------
        column : {'rigid', 'redesigned', 'optimized'}
            Which gains.

        Returns
        -------
        dict
            ``condition`` ('stick' or 'slip'), ``zeta`` [-], ``omega_n_rad_s`` [rad/s], ``f_hz`` [Hz],
            ``pole`` [rad/s].
        """
        cond, row = self._check(column).weakest()
        return {"condition": cond, **row}

    def dominant_mode(self, column: str, condition: str = "stick") -> dict:
        """The slowest closed-loop mode the gains act on (it sets the speed of the loop).

        Parameters
        ----------
        column : {'rigid', 'redesigned', 'optimized'}
            Which gains.
        condition : {'stick', 'slip'}, default 'stick'
            Burden condition.

        Returns
        -------
        dict
            A row of :meth:`kilnctl.design.learned.LoopCheck.modes` (``pole`` [rad/s], ``omega_n_rad_s``,
            ``zeta``, ``f_hz``).
        """
        rows = [r for r in self._check(column).modes[condition] if r["moved"] and r["omega_n_rad_s"] > 0]
        return min(rows, key=lambda r: r["omega_n_rad_s"])

    def table(self) -> list[dict]:
        """The side-by-side table: one row per quantity.

        Returns
        -------
        list of dict
            ``quantity``, ``unit``, one value per column key of :data:`COLUMNS` (a number, a string, or
            None for a time not reached) and ``format`` (how the text and Markdown tables print the numbers).
        """
        req = self.requirements
        rows = []

        def row(quantity, unit, fn, fmt=""):
            rows.append({"quantity": quantity, "unit": unit, **{k: fn(k) for k, _ in COLUMNS}, "format": fmt})

        row("k_p", "V/rpm", lambda k: self.gains[k].k_p, ".4g")
        row("k_I", "V/(rpm*s)", lambda k: self.gains[k].k_I, ".4g")
        row("k_D", "V*s/rpm", lambda k: self.gains[k].k_D, ".4g")
        row(f"least damping, learned linear model (>= {req.zeta_min:g})", "-",
            lambda k: self.limiting_mode(k)["zeta"], ".3f")
        row("  omega_n of that mode", "rad/s", lambda k: self.limiting_mode(k)["omega_n_rad_s"], ".2f")
        row("  burden condition of that mode", "", lambda k: self.limiting_mode(k)["condition"])
        row(f"dominant pole omega_n, burden stuck (<= {req.wn_max:.2f})", "rad/s",
            lambda k: self.dominant_mode(k)["omega_n_rad_s"], ".2f")
        row("verdict on the learned model", "", lambda k: self.verdict_word(k))
        row("start-up ramp", "", lambda k: self.ramp_text(k))
        row("peak current, hybrid plant", "A", lambda k: self.measures[k].peak_current_A, ".1f")
        row("peak bending stress, hybrid plant", "MPa", lambda k: self.measures[k].peak_stress_Pa / 1e6, ".1f")
        row("peak dynamic stress, hybrid plant", "MPa", lambda k: self.measures[k].peak_dynamic_stress_Pa / 1e6, ".1f")
        row("time to 95 % speed", "s", lambda k: self.measures[k].time_to_speed_s, ".2f")
        row("speed settled within 2 % from", "s", lambda k: self.figures[k]["settle_time_s"], ".2f")
        return rows

    def verdict_word(self, column: str) -> str:
        """'meets all' (every requirement, both burden conditions), 'UNSAFE' (damping or stability missed) or
        'misses ...' with the requirements missed, for a column's gains on the learned linear model.

        Parameters
        ----------
        column : {'rigid', 'redesigned', 'optimized'}

        Returns
        -------
        str
        """
        c = self._check(column)
        if not c.safe:
            return "UNSAFE"
        names = sorted({name for name, _, _ in c.unmet()})
        return "misses " + ", ".join(names) if names else "meets all"

    def ramp_text(self, column: str) -> str:
        """The start-up ramp of a column in words.

        Parameters
        ----------
        column : {'rigid', 'redesigned', 'optimized'}

        Returns
        -------
        str
        """
        if column != "optimized":
            return f"linear {self.params.ramp_rate:g} rpm/s"
        d = self.ramp.problem.profile.describe(self.ramp.values, self.params.omega_ref)
        if "jerk_rpm_s2" in d:
            return f"S-curve, {d['accel_rpm_s']:.1f} rpm/s"
        if "rate_rpm_s" in d:
            return f"linear {d['rate_rpm_s']:.1f} rpm/s"
        return f"{self.ramp.problem.profile.label}, at speed after {d['end_time_s']:.1f} s"

    # --- output -------------------------------------------------------------------------
    @staticmethod
    def _fmt(v, fmt: str = "") -> str:
        if v is None:
            return "not reached"
        if isinstance(v, str):
            return v
        return format(v, fmt or ".4g")

    def to_markdown(self) -> str:
        """The table as Markdown.

        Returns
        -------
        str
        """
        head = "| quantity | unit | " + " | ".join(h for _, h in COLUMNS) + " |"
        lines = [head, "|---|---|" + "---:|" * len(COLUMNS)]
        for r in self.table():
            lines.append(f"| {r['quantity'].strip()} | {r['unit']} | "
                         + " | ".join(self._fmt(r[k], r["format"]) for k, _ in COLUMNS) + " |")
        return "\n".join(lines) + "\n"

    def to_text(self) -> str:
        """The table as aligned plain text (what the demo prints).

        Returns
        -------
        str
        """
        heads = [h for _, h in COLUMNS]
        w = max(len(r["quantity"]) + len(r["unit"]) + 3 for r in self.table())
        cw = [max(len(h), 14) for h in heads]
        lines = [" " * w + "  ".join(f"{h:>{c}}" for h, c in zip(heads, cw))]
        for r in self.table():
            label = r["quantity"] + (f" [{r['unit']}]" if r["unit"] and r["unit"] != "-" else "")
            lines.append(f"{label:<{w}}" + "  ".join(f"{self._fmt(r[k], r['format']):>{c}}"
                                                    for (k, _), c in zip(COLUMNS, cw)))
        return "\n".join(lines)

    def to_csv(self, path=None) -> str:
        """The table as CSV (full precision); written whole to ``path`` when given.

        Parameters
        ----------
        path : path-like, optional
            File to write (replaced whole).

        Returns
        -------
        str
            The CSV text.
        """
        buf = io.StringIO()
        w = csv.writer(buf, lineterminator="\n")
        w.writerow(["quantity", "unit", *(k for k, _ in COLUMNS)])
        for r in self.table():
            w.writerow([r["quantity"].strip(), r["unit"], *("" if r[k] is None else r[k] for k, _ in COLUMNS)])
        text = buf.getvalue()
        if path is not None:
            from .files import write_atomic

            write_atomic(Path(path), text)
        return text

    def to_dict(self) -> dict:
        """JSON-ready form: the table, the redesign, the ramp summary and the timings."""
        return {"record": self.record, "selected": list(self.selected), "components": list(self.components),
                "hybrid_components": list(self.hybrid_components),
                "table": [{k: (float(v) if isinstance(v, (float, np.floating)) else v) for k, v in r.items()
                           if k != "format"} for r in self.table()],
                "retune": self.retuned.to_dict(), "ramp": self.ramp.summary(), "seconds": dict(self.seconds)}

    def summary(self) -> str:
        """What the loop found, in plain sentences with units.

        Returns
        -------
        str
        """
        b, a = self.retuned.before, self.retuned.after
        lb, la = self.limiting_mode("rigid"), self.limiting_mode("redesigned")
        m = self.measures
        src = f" from {self.record}" if self.record else ""
        lines = [f"Learned structure{src}: the paper's model with {', '.join(self.selected) or 'nothing added'}."]
        req = self.requirements
        missed = [t for name, t, _ in b.unmet() if name != "zeta_min"]
        lines.append(f"Rigid design {b.gains}: on the learned model the least damped mode is the "
                     f"{lb['f_hz']:.2f} Hz pair (burden {lb['condition']}), zeta = {lb['zeta']:.3f} "
                     f"({'meets' if b.safe else 'MISSES'} the required {req.zeta_min:g})"
                     + (f"; it also misses: {'; '.join(missed)}." if missed else "."))
        if a is b:
            lines.append("Redesign: the rigid gains are kept (" + ("they meet every requirement" if b.ok else
                         "no setting meets every requirement; see the retune summary") + ").")
        else:
            wn = " and ".join(f"{f['dominant_wn']:.2f} rad/s ({c})" for c, f in a.figures.items())
            lines.append(f"Redesigned {a.gains} (gains x {self.retuned.kappa:.3g}, k_D x "
                         f"{self.retuned.kd_factor:.3g}): zeta = {la['zeta']:.3f} at {la['f_hz']:.2f} Hz, dominant "
                         f"pole {wn} (wn_max = {req.wn_max:.2f} rad/s)"
                         + ("; it meets every requirement in both burden conditions." if a.ok else
                            "; it still misses: " + "; ".join(t for _, t, _ in a.unmet()) + "."))
        r, d = m["rigid"], m["redesigned"]

        def pct(x, y):
            return 100.0 * (y - x) / x

        lines.append(
            "On the hybrid plant (the micro model, with coupling and backlash"
            + (f", plus {', '.join(self.selected)}" if self.selected else "") + ") with the "
            f"{self.params.ramp_rate:g} rpm/s ramp: peak current {r.peak_current_A:.0f} A -> {d.peak_current_A:.0f} A "
            f"({pct(r.peak_current_A, d.peak_current_A):+.2f} %), peak dynamic stress "
            f"{r.peak_dynamic_stress_Pa / 1e6:.1f} -> {d.peak_dynamic_stress_Pa / 1e6:.1f} MPa "
            f"({pct(r.peak_dynamic_stress_Pa, d.peak_dynamic_stress_Pa):+.2f} %), peak stress "
            f"{r.peak_stress_Pa / 1e6:.1f} -> {d.peak_stress_Pa / 1e6:.1f} MPa.")
        if max(abs(pct(r.peak_current_A, d.peak_current_A)), abs(pct(r.peak_dynamic_stress_Pa,
                                                                       d.peak_dynamic_stress_Pa))) < 1.0:
            lines.append(f"The {self.params.ramp_rate:g} rpm/s ramp hardly excites the loop's modes: on the start-up "
                         "the redesign changes peak current and stress by under 1 %; it buys damping margin, and the "
                         "shape of the ramp (next line) is what lowers the start-up stress.")
        o = m["optimized"]
        lines.append(
            f"Optimized ramp ({self.ramp_text('optimized')}"
            + (f", jerk {self.ramp.values[1]:.1f} rpm/s^2" if self.ramp.problem.profile.kind == "scurve" else "")
            + ") with the redesigned gains: peak dynamic stress "
            f"{o.peak_dynamic_stress_Pa / 1e6:.1f} MPa against {d.peak_dynamic_stress_Pa / 1e6:.1f} MPa "
            f"({pct(d.peak_dynamic_stress_Pa, o.peak_dynamic_stress_Pa):+.1f} %); peak stress "
            f"{o.peak_stress_Pa / 1e6:.1f} MPa against {d.peak_stress_Pa / 1e6:.1f} MPa (the running load of the "
            "burden, which no ramp changes); 95 % speed at "
            + ("not reached" if o.time_to_speed_s is None else f"{o.time_to_speed_s:.2f} s") + ".")
        return "\n".join(lines)

    def plot(self, fig=None):
        """Root locus of the learned model, current at the ramp start, speed and dynamic stress.

        Parameters
        ----------
        fig : matplotlib.figure.Figure, optional
            Figure to draw into (a new one by default).

        Returns
        -------
        matplotlib.figure.Figure
        """
        return _plot(self, fig)


def _base_model(components) -> str:
    return "micro" if "mesh" in components else "macro"


def close_the_loop(source, params: Parameters | None = None, *, selected=None, base: Parameters | None = None,
                   requirements=None, rigid_gains: PIDGains | None = None, profile: str = "scurve",
                   t_max: float = 10.0, objective: str = "dynamic", record: str = "") -> LoopStudy:
    """Redesign, verify and optimize the ramp on the structure a diagnosis learned.

    Parameters
    ----------
    source : path-like or sequence of str
        The JSON ``kilnctl diagnose --json`` wrote (or ``diagnose.json`` of its report folder), or the learned
        structure's component names (then ``params`` is required).
    params : Parameters, optional
        Calibrated values of the structure, when ``source`` is a component list.
    selected : sequence of str, optional
        Effect names, for the text (with a component list; default: the added components).
    base : Parameters, optional
        The setup the record was diagnosed with (``source`` a path; default Table 1): the diagnosis' calibrated
        values replace its entries.
    requirements : kilnctl.design.Requirements, optional
        Requirements of the design (default: the documented defaults).
    rigid_gains : PIDGains, optional
        The gains to start from (default: the root-locus design of the paper's rigid model with the calibrated
        values).
    profile : str, default 'scurve'
        Profile family of the ramp optimization.
    t_max : float, default 10.0
        Time by which the motor must reach 95 % speed [s].
    objective : {'dynamic', 'peak'}, default 'dynamic'
        What the ramp minimizes.
    record : str, default ''
        Name of the record, for the text and the figure.

    Returns
    -------
    LoopStudy

    Raises
    ------
    ConfigFileError
        ``source`` is not a readable diagnosis.
    ParameterError
        A component list without ``params``.
    ModelError
        A learned effect the ramp optimization cannot carry (one with modes or one that replaces a
        component); the message names it.
    """
    import time

    from .design import Requirements, design_pid
    from .design.learned import learned_structure, retune
    from .linearize import linearize
    from .model import component_names
    from .optimize import Profile, RampProblem, measure_hybrid, optimize_ramp
    from .optimize.model import hybrid_components
    from .verify import ramp_figures

    seconds = {}
    t0 = time.perf_counter()
    if isinstance(source, (str, Path)):
        structure, lp, sel = learned_structure(source, base=base)
        comps = structure.components()
    else:
        if params is None:
            raise ParameterError("close_the_loop: with a component list as source, give params (the calibrated "
                                 "values of the structure)")
        comps, lp = tuple(source), params
        sel = None
    model = _base_model(comps)
    added = tuple(c for c in comps if c not in component_names(model))
    sel = list(selected) if selected is not None else (sel if sel is not None else list(added))
    req = (Requirements() if requirements is None else requirements).resolve(lp)
    if rigid_gains is None:
        rigid_gains = design_pid(lp.replace(gains="design"), req).gains
    g = rigid_gains
    lp = lp.replace(gains="given", k_p=g.k_p, k_I=g.k_I, k_D=g.k_D)
    # the ramp problem first: it refuses, named, an effect it cannot carry before anything long runs
    RampProblem(lp, profile=profile, t_max=t_max, objective=objective, effects=added)
    seconds["design"] = time.perf_counter() - t0

    t0 = time.perf_counter()
    rt = retune(lp, comps, PIDGains(g.k_p, g.k_I, g.k_D), req)
    bases = {c: linearize(lp, components=comps, burden=c) for c in ("stick", "slip")}
    locus = {}
    for key, gg in (("rigid", rt.before.gains), ("redesigned", rt.after.gains)):
        locus[key] = {c: np.array([bases[c].with_gains(k * gg.k_p, k * gg.k_I, k * gg.k_D).poles()
                                   for k in LOCUS_KAPPAS]) for c in bases}
    seconds["redesign"] = time.perf_counter() - t0

    a = rt.after.gains
    pa = lp.replace(k_p=a.k_p, k_I=a.k_I, k_D=a.k_D)
    prob = RampProblem(pa, profile=profile, t_max=t_max, objective=objective, effects=added)
    t0 = time.perf_counter()
    measures, figs, resp = {}, {}, {}
    const = Profile.parse("constant")
    for key, gg in (("rigid", rt.before.gains), ("redesigned", a)):
        p = lp.replace(k_p=gg.k_p, k_I=gg.k_I, k_D=gg.k_D)
        measures[key], resp[key] = measure_hybrid(p, const, [p.ramp_rate], prob.horizon, effects=added)
    seconds["verify"] = time.perf_counter() - t0

    t0 = time.perf_counter()
    ramp = optimize_ramp(prob)
    measures["optimized"], resp["optimized"] = measure_hybrid(pa, prob.profile, ramp.values, prob.horizon,
                                                             effects=added)
    seconds["optimize"] = time.perf_counter() - t0
    for key, r in resp.items():
        tt, uniq = np.unique(r.t, return_index=True)
        figs[key] = ramp_figures(tt, np.asarray(r.outputs["speed_rpm"])[uniq], np.asarray(r.outputs["i_a"])[uniq],
                                 r.params)
    return LoopStudy(record=record, selected=sel, components=tuple(comps),
                     hybrid_components=hybrid_components(const, added), params=pa, requirements=req, retuned=rt,
                     locus=locus, kappas=LOCUS_KAPPAS, measures=measures, figures=figs, responses=resp, ramp=ramp,
                     seconds=seconds)


# --- figure ------------------------------------------------------------------------------
#: colour and style of each column in the figure
_STYLE = {"rigid": {"color": "0.45", "ls": "--"}, "redesigned": {"color": "C0", "ls": "-"},
          "optimized": {"color": "C3", "ls": "-"}}


def _plot(study: LoopStudy, fig=None):
    """Draw a :class:`LoopStudy` (see :meth:`LoopStudy.plot`)."""
    from matplotlib.figure import Figure

    from .design.plots import _draw_region
    from .figures import FONT, finish
    from .optimize.model import load_stress

    fig = Figure(figsize=(11, 8.2)) if fig is None else fig
    ax = fig.subplots(2, 2)
    names = dict(COLUMNS)
    # (a) root locus of the learned model, burden stuck, over the gain scale
    a = ax[0, 0]
    at1 = {k: study.locus[k]["stick"][int(np.argmin(np.abs(study.kappas - 1.0)))] for k in ("rigid", "redesigned")}
    extent = 1.6 * max(float(np.max(np.abs(p))) for p in at1.values())
    extent = min(extent, 80.0)
    _draw_region(a, study.requirements, extent, legend=True)
    for key, mark in (("rigid", "s"), ("redesigned", "D")):
        pts = study.locus[key]["stick"].ravel()
        st = _STYLE[key]
        a.plot(pts.real, pts.imag, ".", ms=1.6, color=st["color"],
               label=f"locus, {'rigid' if key == 'rigid' else 'redesigned'} zeros (gains x 0.05-4)")
        p1 = at1[key]
        a.plot(p1.real, p1.imag, mark, ms=7, mfc="none", mew=1.6, color=st["color"],
               label=f"poles, {'rigid design' if key == 'rigid' else 'redesigned'} gains")
    a.set_xlim(-extent, 0.1 * extent)
    a.set_ylim(-0.7 * extent, 1.15 * extent)
    a.axhline(0, color="0.8", lw=0.6)
    a.axvline(0, color="0.8", lw=0.6)
    a.set_xlabel("real part [rad/s]")
    a.set_ylabel("imaginary part [rad/s]")
    a.set_title("root locus of the learned model (burden stuck)", fontsize=FONT["title"])
    a.legend(fontsize=FONT["legend"] - 1.5, loc="upper left", ncol=2)
    # (b) armature current around the ramp start: where the loop modes show
    b = ax[0, 1]
    for key in ("rigid", "redesigned"):
        r = study.responses[key]
        t = np.asarray(r.t)
        keep = t <= 2.0
        b.plot(t[keep], np.asarray(r.outputs["i_a"])[keep], label=names[key], **_STYLE[key])
    b.set_xlabel("time [s]")
    b.set_ylabel("armature current [A]")
    b.set_title("hybrid plant: current in the first 2 s of the start-up", fontsize=FONT["title"])
    b.legend(fontsize=FONT["legend"], loc="lower right")
    # (c) speed
    c = ax[1, 0]
    for key, _ in COLUMNS:
        r = study.responses[key]
        c.plot(r.t, r.outputs["speed_rpm"], label=names[key], **_STYLE[key])
    c.set_xlabel("time [s]")
    c.set_ylabel("motor speed [rpm]")
    c.set_title("hybrid plant: motor speed", fontsize=FONT["title"])
    c.legend(fontsize=FONT["legend"], loc="lower right")
    # (d) dynamic stress
    d = ax[1, 1]
    for key, _ in COLUMNS:
        r = study.responses[key]
        dyn = np.asarray(r.outputs["sigma"]) - load_stress(np.asarray(r.outputs["T_f"]),
                                                           np.asarray(r.states["omega_kiln"]), r.params)
        d.plot(r.t, dyn / 1e6, label=f"{names[key]}: peak {study.measures[key].peak_dynamic_stress_Pa / 1e6:.1f} MPa",
               **_STYLE[key])
    d.set_xlim(0.0, min(float(study.responses["optimized"].t[-1]), study.ramp.problem.t_max + 5.0))
    d.set_xlabel("time [s]")
    d.set_ylabel("dynamic bending stress [MPa]")
    d.set_title("hybrid plant: gear stress above the running load", fontsize=FONT["title"])
    d.legend(fontsize=FONT["legend"], loc="upper right")
    lim = study.limiting_mode("rigid")
    src = f" ({study.record})" if study.record else ""
    return finish(
        fig, f"Close the loop on the learned structure{src}: {', '.join(study.selected) or 'no effect added'}",
        "Top left: closed-loop poles of the exact linearization of the learned structure with the gains scaled "
        "by 0.05 to 4 (grey: the rigid design's PID zeros, blue: the redesigned ones); markers at scale 1. Green: "
        f"damping >= {study.requirements.zeta_min:g} and the dominant-pole region. With the rigid gains the "
        f"{lim['f_hz']:.2f} Hz pair sits at zeta = {lim['zeta']:.3f}. Other panels: hybrid simulation of the "
        "micro model (coupling, backlash) with the learned effects and calibrated values; dynamic stress = "
        "bending stress minus that of the burden and bearing loads.")
