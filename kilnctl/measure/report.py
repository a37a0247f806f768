"""Presentation of measurement analyses: summaries, JSON, figures and self-contained HTML reports.

The analyses (:class:`~kilnctl.measure.diagnose.Diagnosis`,
:class:`~kilnctl.measure.compare.Comparison`) compute; this module turns their
results into text, JSON, figures and HTML pages (figures embedded as base64
PNG), each file written whole or not at all.
"""

from __future__ import annotations

import base64
import html
import io
import json
import math
from pathlib import Path

import numpy as np

from ..errors import ConfigFileError
from ..params import SPECS
from ..response import write_atomic
from .effects import CATALOGUE

__all__ = ["figure_tag", "table", "page", "write_report_files", "esc", "json_number", "unit_of", "format_fit",
           "diagnosis_dict", "diagnosis_headline", "diagnosis_summary", "plot_diagnosis", "plot_ranking",
           "diagnosis_html", "write_diagnosis_report", "write_comparison_report"]

_CSS = """
body{font-family:system-ui,-apple-system,Segoe UI,sans-serif;max-width:1200px;margin:2em auto;padding:0 1em;
color:#222;line-height:1.45}
h1{font-size:1.5em}h2{font-size:1.2em;border-bottom:1px solid #ccc;padding-bottom:.2em;margin-top:1.8em}
table{border-collapse:collapse;font-size:.9em;margin:.6em 0}td,th{border:1px solid #ccc;padding:.25em .6em;
text-align:right}th{background:#f3f3f3}td.l,th.l{text-align:left}tr.sel td{background:#e9f6e9}
img{max-width:100%;border:1px solid #eee}.big{font-size:1.15em;background:#f6f8fa;padding:.6em 1em;
border-left:4px solid #2a7;margin:1em 0}.warn{border-left-color:#d80}code{background:#f3f3f3;padding:0 .2em}
"""


def esc(text) -> str:
    """HTML-escape any value's text."""
    return html.escape(str(text))


def figure_tag(fig, alt: str = "figure") -> str:
    """Return an ``<img>`` tag holding the figure as a base64 PNG.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure.
    alt : str
        Alternative text.

    Returns
    -------
    str
    """
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=90)
    data = base64.b64encode(buf.getvalue()).decode("ascii")
    return f'<img alt="{esc(alt)}" src="data:image/png;base64,{data}">'


def table(header, rows, left=1, selected=()) -> str:
    """Return an HTML table.

    Parameters
    ----------
    header : sequence of str
        Column titles.
    rows : sequence of sequence
        Cell values (escaped here).
    left : int, default 1
        Number of leading columns aligned left.
    selected : collection of int
        Row indices to highlight.

    Returns
    -------
    str
    """
    cls = lambda j: ' class="l"' if j < left else ""  # noqa: E731
    out = ["<table><tr>" + "".join(f"<th{cls(j)}>{esc(h)}</th>" for j, h in enumerate(header)) + "</tr>"]
    for i, r in enumerate(rows):
        tr = '<tr class="sel">' if i in selected else "<tr>"
        out.append(tr + "".join(f"<td{cls(j)}>{esc(c)}</td>" for j, c in enumerate(r)) + "</tr>")
    return "\n".join(out) + "</table>"


def page(title: str, body: str) -> str:
    """Return a complete HTML document.

    Parameters
    ----------
    title : str
        Page title.
    body : str
        HTML of the body (already escaped where needed).

    Returns
    -------
    str
    """
    return (f"<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>{esc(title)}</title>"
            f"<style>{_CSS}</style></head><body>\n<h1>{esc(title)}</h1>\n{body}\n</body></html>\n")


def write_report_files(folder, files: dict, protect=()) -> list[Path]:
    """Write report files into a folder, each whole or not at all.

    Parameters
    ----------
    folder : path-like
        Destination folder (created).
    files : dict of str to str or bytes or dict
        File name -> content (a dict is written as indented JSON).
    protect : sequence of path-like
        Input files that must never be overwritten (the record, the setup).

    Returns
    -------
    list of Path
        The paths written.

    Raises
    ------
    ConfigFileError
        When ``folder`` is a file, or a report file would replace an input.
    """
    folder = Path(folder)
    if folder.exists() and not folder.is_dir():
        raise ConfigFileError(f"--report {folder} is a file, not a folder")
    guarded = {Path(p).resolve() for p in protect if p}
    targets = {folder / name: content for name, content in files.items()}
    for path in targets:
        if path.resolve() in guarded:
            raise ConfigFileError(f"report file {path} would overwrite an input file: choose another --report folder")
    written = []
    for path, content in targets.items():
        if isinstance(content, dict):
            content = json.dumps(content, indent=2, allow_nan=False)
        written.append(write_atomic(path, content))
    return written


# --- shared formatting -----------------------------------------------------------------------------
def json_number(v):
    """A finite float, or None for JSON (no NaN or infinity).

    Parameters
    ----------
    v : float or None
        Any value.

    Returns
    -------
    float or None
    """
    return None if v is None or not math.isfinite(v) else float(v)


def unit_of(name: str) -> str:
    """Unit of a parameter of :data:`~kilnctl.params.SPECS`, '' when it has none.

    Parameters
    ----------
    name : str
        Parameter name.

    Returns
    -------
    str
    """
    return SPECS[name].unit if name in SPECS else ""


def format_fit(fit: dict) -> str:
    """``current_A 97.1 %, speed_rpm 99.9 %``: fit % per channel in one line.

    Parameters
    ----------
    fit : dict of str to float
        Fit [%] per channel.

    Returns
    -------
    str
    """
    return ", ".join(f"{k} {v:.1f} %" for k, v in fit.items())


def _fmt_val(v, se) -> str:
    if se is None or not math.isfinite(se):
        return f"{v:.4g} (se n/a)"
    if se == 0:
        return f"{v:.4g}"
    digits = max(0, 1 - int(math.floor(math.log10(abs(se))))) if se > 0 else 2
    if abs(v) >= 1e5 or (abs(v) < 1e-3 and v != 0):
        return f"{v:.3e} +- {se:.1e}"
    return f"{v:.{digits}f} +- {se:.{digits}f}"


def _jsonable(d):
    if d is None:
        return None
    out = {}
    for k, v in d.items():
        if isinstance(v, float):
            out[k] = json_number(v)
        elif isinstance(v, dict):
            out[k] = _jsonable(v)
        elif isinstance(v, (np.floating, np.integer)):
            out[k] = json_number(float(v))
        else:
            out[k] = v
    return out


def _effect_params(effect):
    out = set()
    for fp in CATALOGUE[effect].parameters:
        out.add(fp.name)
        if fp.partner:
            out.add(fp.partner)
    return out


def _params_dict(cal) -> dict:
    return {k: {"value": json_number(cal.values_[k]), "stderr": json_number(cal.stderr_[k]), "unit": unit_of(k),
                "on_bound": k in cal.on_bound_, "not_identifiable": k in cal.not_identifiable_} for k in cal.names_}


# --- diagnosis ----------------------------------------------------------------------------------------
def diagnosis_dict(d) -> dict:
    """Return a fitted diagnosis as a JSON-ready dictionary.

    Parameters
    ----------
    d : Diagnosis
        A fitted :class:`~kilnctl.measure.diagnose.Diagnosis`.

    Returns
    -------
    dict
        See :meth:`Diagnosis.to_dict <kilnctl.measure.diagnose.Diagnosis.to_dict>`.
    """
    fc = d.final_calibration_
    return {
        "source": d.measurement_.source,
        "baseline": {k: json_number(v) for k, v in d.baseline_.items()},
        "baseline_parameters": _params_dict(d.base_calibration_),
        "ranking": [r.to_dict() for r in d.ranking_],
        "rounds": [[r.to_dict() for r in rnd] for rnd in d.rounds_],
        "selected": list(d.selected_),
        "final": {k: json_number(v) for k, v in d.final_.items()},
        "final_parameters": _params_dict(fc),
        "unexplained": _jsonable(d.unexplained_),
        "caveats": list(d.caveats_),
        "residual_signature": _jsonable(d.signature_),
        "failing_before": d.comparison_base_.failing,
        "failing_after": d.comparison_final_.failing,
        "experiment": d.experiment_.to_dict(),
        "settings": {"calibrate": list(d.calibrate), "candidates": list(d.candidates), "model": d.model,
                     "holdout": d.holdout, "holdout_fraction": d.holdout_fraction,
                     "min_delta_bic": d.min_delta_bic, "min_holdout_gain_percent": d.min_holdout_gain},
        "wall_s": d.wall_s_,
    }


def diagnosis_headline(d) -> str:
    """One sentence: how the error fell and what was added.

    Parameters
    ----------
    d : Diagnosis
        A fitted diagnosis.

    Returns
    -------
    str
    """
    c0, c1 = d.baseline_["current_A"], d.final_["current_A"]
    if not d.selected_:
        s = f"no catalogued effect is supported by the data; current fit {c0:.1f} % with the calibrated base model"
        if d.unexplained_:
            s += f"; the residual still has structure ({d.unexplained_['hint']})"
        return s
    fc = d.final_calibration_
    parts = []
    for e in d.selected_:
        for fp in CATALOGUE[e].parameters:
            for k in (fp.name, fp.partner):
                if k and k in fc.values_:
                    parts.append(f"{k} = {_fmt_val(fc.values_[k], fc.stderr_[k])} {unit_of(k)}".rstrip())
    return (f"current fit rose from {c0:.1f} % to {c1:.1f} % after adding {', '.join(d.selected_)}"
            + (f", {', '.join(parts)}" if parts else ""))


def diagnosis_summary(d) -> str:
    """Return a readable account of a fitted diagnosis.

    Parameters
    ----------
    d : Diagnosis
        A fitted diagnosis.

    Returns
    -------
    str
    """
    lines = [f"diagnosis of {d.measurement_.source} ({d.wall_s_:.0f} s)",
             f"  baseline (calibrated {', '.join(d.calibrate)}): {format_fit(d.baseline_)}"]
    for i, rnd in enumerate(d.rounds_):
        lines.append(f"  round {i + 1}: candidates against "
                     + ("the base" if i == 0 else "base + " + ", ".join(d.selected_[:i])))
        lines.append(f"    {'effect':<22} {'dBIC':>10} {'held-out':>9} {'fit I %':>8}  verdict")
        for r in rnd:
            fi = r.fit_percent.get("current_A", math.nan)
            lines.append(f"    {r.effect:<22} {r.delta_bic:>10.1f} {r.holdout_gain:>8.1f}% {fi:>8.1f}  "
                         f"{'SUPPORTED' if r.supported else r.reason}")
    lines.append(f"  selected: {', '.join(d.selected_) or 'nothing'}")
    lines.append(f"  final: {format_fit(d.final_)}")
    lines.append("  " + diagnosis_headline(d))
    if d.unexplained_:
        lines.append("  unexplained residual: " + d.unexplained_["text"])
    for c in d.caveats_:
        lines.append("  caution: " + c)
    return "\n".join(lines)


def plot_diagnosis(d, fig=None):
    """Measured vs base vs final model, residuals, correlation and spectrum (failing intervals shaded).

    Parameters
    ----------
    d : Diagnosis
        A fitted diagnosis.
    fig : matplotlib.figure.Figure, optional

    Returns
    -------
    matplotlib.figure.Figure
    """
    return d.comparison_base_.plot(fig=fig, compare_with=d.comparison_final_,
                                   labels=("calibrated base", "final: base + " + (", ".join(d.selected_) or
                                                                                  "nothing")))


def plot_ranking(d, fig=None):
    """Bar charts: delta BIC and held-out gain of each first-round candidate, and fit before/after.

    Parameters
    ----------
    d : Diagnosis
        A fitted diagnosis.
    fig : matplotlib.figure.Figure, optional

    Returns
    -------
    matplotlib.figure.Figure
    """
    from matplotlib.figure import Figure
    from matplotlib.patches import Patch

    from ..figures import COLORS, finish, record_name

    rk = d.ranking_
    fig = fig or Figure(figsize=(13, 2.2 + 0.3 * max(len(rk), 4)))
    a0, a1, a2 = fig.subplots(1, 3, gridspec_kw={"width_ratios": [3, 3, 2]})
    names = [r.effect for r in rk]
    colors = [COLORS["supported"] if r.supported else COLORS["rejected"] for r in rk]
    y = np.arange(len(rk))
    dbic = [max(-1e6, r.delta_bic) if math.isfinite(r.delta_bic) else 0 for r in rk]
    a0.barh(y, [-v for v in dbic], color=colors)
    a0.set_xscale("symlog", linthresh=10)
    a0.axvline(d.min_delta_bic, color=COLORS["threshold"], ls=":", label=f"threshold {d.min_delta_bic:g}")
    a0.axvline(0, color="0.3", lw=0.6)
    a0.set_yticks(y, names, fontsize=8)
    a0.invert_yaxis()
    a0.set_xlabel("BIC improvement -dBIC on the fitting part [-] (log scale beyond 10)")
    a0.set_title("evidence in the fitted part (more is better)", fontsize=9)
    a0.legend(handles=[Patch(color=COLORS["supported"], label="supported (both tests)"),
                       Patch(color=COLORS["rejected"], label="not supported"),
                       *a0.get_legend_handles_labels()[0]], fontsize=7.5, loc="lower right")
    gains = [r.holdout_gain if math.isfinite(r.holdout_gain) else 0 for r in rk]
    a1.barh(y, [max(-100.0, g) for g in gains], color=colors)
    lim = min(105.0, max(10.0, 1.15 * max([abs(g) for g in gains] + [d.min_holdout_gain])))
    a1.set_xlim(-lim, lim)
    for yy, g in zip(y, gains):
        if g < -lim:
            a1.text(-lim, yy, f" {g:.0f} %", va="center", ha="left", fontsize=7)
    a1.axvline(d.min_holdout_gain, color=COLORS["threshold"], ls=":", label=f"threshold {d.min_holdout_gain:g} %")
    a1.axvline(0, color="0.3", lw=0.6)
    a1.set_yticks(y, [""] * len(y))
    a1.invert_yaxis()
    a1.set_xlabel("held-out gain [%]: error reduction on samples not fitted")
    a1.set_title("prediction of unseen samples (more is better)", fontsize=9)
    a1.legend(fontsize=7.5, loc="lower right")
    chans = list(d.baseline_)
    x = np.arange(len(chans))
    a2.bar(x - 0.2, [d.baseline_[c] for c in chans], 0.4, label="calibrated base", color=COLORS["model"])
    a2.bar(x + 0.2, [d.final_[c] for c in chans], 0.4, label="final", color=COLORS["final"])
    for i, c in enumerate(chans):
        a2.text(i - 0.2, d.baseline_[c], f"{d.baseline_[c]:.1f}", ha="center", va="bottom", fontsize=8)
        a2.text(i + 0.2, d.final_[c], f"{d.final_[c]:.1f}", ha="center", va="bottom", fontsize=8)
    a2.set_xticks(x, [{"current_A": "current", "speed_rpm": "speed"}.get(c, c) for c in chans])
    a2.set_ylim(0, 135)  # from zero: fit % bars are read by their length
    a2.set_yticks(range(0, 101, 20))
    a2.set_ylabel("fit [%] (100 = perfect)")
    a2.set_title("fit on the whole record", fontsize=9)
    a2.legend(fontsize=7.5, loc="upper center", ncol=2)
    return finish(fig, f"{record_name(d.measurement_.source)}: {diagnosis_headline(d)}")


def diagnosis_html(d, figs=None) -> str:
    """Return the report of a fitted diagnosis as one self-contained HTML page.

    Parameters
    ----------
    d : Diagnosis
        A fitted diagnosis.
    figs : dict, optional
        Figures already drawn (name -> Figure): the signals, then the ranking.

    Returns
    -------
    str
    """
    figs = figs or {"s": plot_diagnosis(d), "r": plot_ranking(d)}
    f_sig, f_rank = list(figs.values())
    parts = [f'<p class="big">{esc(diagnosis_headline(d))}</p>']
    if d.unexplained_:
        parts.append(f'<p class="big warn">Unexplained: {esc(d.unexplained_["text"])}</p>')
    for c in d.caveats_:
        parts.append(f'<p class="warn">Caution: {esc(c)}</p>')
    parts.append("<h2>Measured, calibrated base and final model</h2>")
    parts.append("<p>Shaded: intervals where the base model's |residual| exceeds 3 sigma. "
                 "Dashed lines: phases of the start-up.</p>")
    parts.append(figure_tag(f_sig, "signals and residuals"))
    rows = [(f["channel"], f["text"]) for f in d.comparison_base_.failing]
    parts.append("<h3>Where the base model fails</h3>" + (table(["channel", "interval"], rows, left=2)
                                                            if rows else "<p>nowhere beyond 3 sigma</p>"))
    rows = [(f["channel"], f["text"]) for f in d.comparison_final_.failing]
    parts.append("<h3>Where the final model fails</h3>" + (table(["channel", "interval"], rows, left=2)
                                                             if rows else "<p>nowhere beyond 3 sigma</p>"))
    parts.append("<h2>Candidates</h2>")
    parts.append(figure_tag(f_rank, "ranking"))
    for i, rnd in enumerate(d.rounds_):
        parts.append(f"<h3>Round {i + 1}: against " + esc("the calibrated base" if i == 0 else
                                                          "base + " + ", ".join(d.selected_[:i])) + "</h3>")
        rows, sel = [], set()
        for j, r in enumerate(rnd):
            if r.supported and j == 0:
                sel.add(j)
            pars = "; ".join(f"{k} = {_fmt_val(v['value'], v['stderr'])} {v['unit']}".rstrip()
                             for k, v in r.parameters.items() if k in _effect_params(r.effect))
            rows.append((r.effect, f"{r.delta_bic:.1f}", f"{r.holdout_gain:+.1f}",
                         f"{r.fit_percent.get('current_A', math.nan):.1f}",
                         f"{r.fit_percent.get('speed_rpm', math.nan):.2f}", pars or "-",
                         ", ".join(r.on_bound) or "-", "supported" if r.supported else r.reason))
        parts.append(table(["effect", "dBIC", "held-out gain %", "fit I %", "fit n %", "effect parameters",
                            "on bound", "verdict"], rows, left=1, selected=sel))
    parts.append("<h2>Final model</h2><pre>" + esc(d.final_calibration_.summary()) + "</pre>")
    parts.append("<h2>Residual signature of the final model</h2><pre>"
                 + esc(d.signature_["text"]) + "</pre>")
    for note in d.experiment_.notes:
        parts.append(f"<p>Note: {esc(note)}</p>")
    parts.append("<h2>Settings</h2><pre>" + esc(str(diagnosis_dict(d)["settings"])) + "</pre>")
    return page(f"kilnctl diagnose: {d.measurement_.source}", "\n".join(parts))


def write_diagnosis_report(d, folder, protect=()) -> list:
    """Write ``diagnose.html`` (self-contained), ``diagnose.json`` and the figures into a folder.

    Parameters
    ----------
    d : Diagnosis
        A fitted diagnosis.
    folder : path-like
        Destination folder (created).
    protect : sequence of path-like
        Input files never to overwrite.

    Returns
    -------
    list of Path
        Files written (each whole or not at all).
    """
    figs = {"diagnose_signals.png": plot_diagnosis(d), "diagnose_ranking.png": plot_ranking(d)}
    pngs = {}
    for name, fig in figs.items():
        buf = io.BytesIO()
        fig.savefig(buf, format="png", dpi=100)
        pngs[name] = buf.getvalue()
    return write_report_files(folder, {"diagnose.html": diagnosis_html(d, figs), "diagnose.json": diagnosis_dict(d),
                                       **pngs}, protect=protect)


# --- comparison ------------------------------------------------------------------------------------
def write_comparison_report(c, folder, protect=()) -> list:
    """Write ``compare.html`` (self-contained), ``compare.json`` and ``compare.png`` into a folder.

    Parameters
    ----------
    c : Comparison
        A :class:`~kilnctl.measure.compare.Comparison` of a model with a record.
    folder : path-like
        Destination folder (created).
    protect : sequence of path-like
        Input files never to overwrite.

    Returns
    -------
    list of Path
        Files written (each whole or not at all).
    """
    fig = c.plot()
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110)
    body = ("<pre>" + esc("\n".join(c.summary_lines())) + "</pre>\n" + figure_tag(fig, "measured vs model"))
    return write_report_files(folder, {"compare.html": page(f"kilnctl compare: {c.source}", body),
                                       "compare.json": c.to_dict(), "compare.png": buf.getvalue()}, protect=protect)
