"""Presentation of measurement analyses: summaries, JSON, figures and self-contained HTML reports.

The analyses (:class:`~kilnctl.measure.diagnose.Diagnosis`,
:class:`~kilnctl.measure.compare.Comparison`) compute; this module turns their
results into text, JSON, figures and HTML pages (figures embedded as base64
PNG), each file written whole or not at all.
"""

from __future__ import annotations

import base64
import dataclasses
import html
import io
import json
import math
import re
import textwrap
from pathlib import Path

import numpy as np

from ..errors import ConfigFileError
from ..params import SPECS
from ..response import write_atomic
from .effects import CATALOGUE

__all__ = ["figure_tag", "table", "page", "write_report_files", "esc", "json_number", "unit_of", "format_fit",
           "diagnosis_dict", "diagnosis_headline", "diagnosis_summary", "plot_diagnosis", "plot_ranking",
           "diagnosis_html", "write_diagnosis_report", "write_comparison_report", "comparison_html",
           "diagnosis_plain_headline", "uncertainty_words", "how_to_read", "settings_table", "parameter_table",
           "figure_block", "record_name_of", "HOW_TO_READ", "pretty_unit", "value_pair", "png_bytes", "write_page_files",
           "render_pngs", "report_page", "candidate_dict", "candidate_verdict", "greedy_order", "round_model",
           "form_verdicts", "listed", "label", "SUMMARY_WIDTH"]

_CSS = """
*{box-sizing:border-box}
body{font-family:system-ui,-apple-system,Segoe UI,sans-serif;max-width:1180px;margin:1.2em auto;padding:0 1em;
color:#222;line-height:1.45;font-size:15px}
h1{font-size:1.45em;margin-bottom:.3em}h2{font-size:1.15em;border-bottom:1px solid #ccc;padding-bottom:.2em;
margin-top:1.6em}h3{font-size:1.02em;margin-bottom:.3em}
.scroll{overflow-x:auto;max-width:100%}
table{border-collapse:collapse;font-size:.88em;margin:.5em 0}td,th{border:1px solid #ccc;padding:.25em .55em;
text-align:right;vertical-align:top}th{background:#f3f3f3}td.l,th.l{text-align:left}td.w{max-width:30em;
text-align:left}tr.sel td{background:#e9f6e9}
img{max-width:100%;height:auto;border:1px solid #eee;display:block;margin:.4em 0}
.big{font-size:1.12em;background:#f6f8fa;padding:.6em 1em;border-left:4px solid #2a7;margin:1em 0}
.warn{border-left:4px solid #d80;background:#fff8ec;padding:.4em .8em;margin:.5em 0}
.howto{background:#f4f7fb;border:1px solid #cdd8e6;border-radius:4px;padding:.5em 1em;margin:1em 0;
font-size:.92em}.howto h2{border:0;margin:.2em 0;font-size:1.02em}.howto dl{margin:.2em 0}
.howto dt{font-weight:600;margin-top:.35em}.howto dd{margin-left:1.2em}
.cap{font-size:.9em;color:#444;margin:.2em 0 1em}
code{background:#f3f3f3;padding:0 .2em}pre{white-space:pre-wrap;font-size:.88em}
"""


def esc(text) -> str:
    """HTML-escape any value's text."""
    return html.escape(str(text))


def figure_tag(fig, alt: str = "figure") -> str:
    """Return an ``<img>`` tag holding the figure as a base64 PNG.

    Parameters
    ----------
    fig : matplotlib.figure.Figure or bytes
        The figure, or its PNG file content already rendered (a page that
        also writes the figure as a file renders it once, see
        :func:`write_page_files`).
    alt : str
        Alternative text.

    Returns
    -------
    str
    """
    data = base64.b64encode(fig if isinstance(fig, bytes) else png_bytes(fig, dpi=90)).decode("ascii")
    return f'<img alt="{esc(alt)}" src="data:image/png;base64,{data}">'


def png_bytes(fig, dpi: float = 110) -> bytes:
    """Return a figure as PNG file content.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure.
    dpi : float, default 110
        Resolution [dots per inch].

    Returns
    -------
    bytes
    """
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi)
    return buf.getvalue()


def table(header, rows, left=1, selected=(), wrap=()) -> str:
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
    wrap : collection of int
        Columns of long text, left-aligned and wrapped.

    Returns
    -------
    str
    """
    def cls(j, head=False):
        if j in wrap and not head:
            return ' class="w"'
        return ' class="l"' if j < left or j in wrap else ""

    out = ['<div class="scroll"><table><tr>'
           + "".join(f"<th{cls(j, True)}>{esc(h)}</th>" for j, h in enumerate(header)) + "</tr>"]
    for i, r in enumerate(rows):
        tr = '<tr class="sel">' if i in selected else "<tr>"
        out.append(tr + "".join(f"<td{cls(j)}>{esc(c)}</td>" for j, c in enumerate(r)) + "</tr>")
    return "\n".join(out) + "</table></div>"


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
        try:
            written.append(write_atomic(path, content))
        except OSError as exc:  # a folder that cannot be made or written (read-only, full disk, a file in the way)
            raise ConfigFileError(f"--report {folder}: cannot write {path.name} ({exc.strerror or exc}); give a folder "
                                  "you may write into" + (f" ({len(written)} of the report's files were written)"
                                                          if written else "")) from None
    return written


def render_pngs(figures: dict, dpi: float = 110) -> dict:
    """Render figures to PNG content once, for a page's inline images and its PNG files alike.

    Drawing a figure (its tight layout, every text's extent) costs about as much as the rest of a report page:
    rendered once, the same bytes go into the page (:func:`figure_tag`) and into the file.

    Parameters
    ----------
    figures : dict of str to matplotlib.figure.Figure or bytes
        Name -> figure (content already rendered is kept as it is).
    dpi : float, default 110
        Resolution [dots per inch].

    Returns
    -------
    dict of str to bytes
    """
    return {name: fig if isinstance(fig, bytes) else png_bytes(fig, dpi) for name, fig in figures.items()}


def write_page_files(folder, stem: str, html_text: str, data: dict, figures: dict, protect=(), dpi: float = 110
                     ) -> list[Path]:
    """Write a report page ``STEM.html``, its numbers ``STEM.json`` and its figures as PNG, each whole or not at all.

    Parameters
    ----------
    folder : path-like
        Destination folder (created).
    stem : str
        Name of the page and of its JSON file, without the extension.
    html_text : str
        The page (:func:`report_page`).
    data : dict
        JSON-ready numbers of the page.
    figures : dict of str to matplotlib.figure.Figure or bytes
        PNG file name -> figure, or its PNG content already rendered (by
        :func:`render_pngs`, the same bytes the page holds inline).
    protect : sequence of path-like
        Input files never to overwrite.
    dpi : float, default 110
        Resolution of the PNG files [dots per inch].

    Returns
    -------
    list of Path
        The page, the JSON file, then the figures.
    """
    pngs = render_pngs(figures, dpi)
    return write_report_files(folder, {f"{stem}.html": html_text, f"{stem}.json": data, **pngs}, protect=protect)


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


def pretty_unit(unit: str) -> str:
    """``kg*m^2`` -> ``kg·m²``: a unit as a reader writes it.

    Parameters
    ----------
    unit : str
        Unit in kilnctl's ASCII form.

    Returns
    -------
    str
    """
    return unit.replace("*", "·").replace("^2", "²").replace("^3", "³").replace("^-1", "⁻¹")


def value_pair(v, se) -> tuple[str, str]:
    """A value and its standard error to the error's second significant digit: ``('579910', '180')``.

    Parameters
    ----------
    v : float
        Value.
    se : float or None
        Standard error (not finite or None: the value alone, 4 digits).

    Returns
    -------
    (str, str)
        The error string is '' when it is not a positive finite number.
    """
    if v is None or not math.isfinite(v):
        return "-", ""
    if se is None or not math.isfinite(se) or se <= 0:
        return f"{v:.4g}", ""
    exp = int(math.floor(math.log10(se)))
    if abs(v) >= 1e7 or (abs(v) < 1e-3 and v != 0) or exp < -6:
        # the mantissa to the error's second significant digit: 2.955e+09 ± 2.6e+07, not 2.9552e+09
        ev = int(math.floor(math.log10(abs(v)))) if v != 0 else exp
        return f"{v:.{min(6, max(0, ev - exp + 1))}e}", f"{se:.1e}"
    step = exp - 1  # the decade of the error's second significant digit
    if step < 0:
        return f"{v:.{-step}f}", f"{se:.{-step}f}"
    # whole numbers rounded there too: 5300000 ± 2100000, not 5309316 ± 2072959
    q = 10.0 ** step
    return f"{round(v / q) * q + 0.0:.0f}", f"{round(se / q) * q:.0f}"  # + 0.0: never "-0"


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


def _effect_params(effect) -> tuple[str, ...]:
    """The parameters an effect brings (each with its partner), in catalogue order; for two effects refitted as
    a pair in the round of pairs (``torque_friction_law+second_motor``), both effects' parameters."""
    return tuple(dict.fromkeys(k for part in effect.split("+") for fp in CATALOGUE[part].parameters
                               for k in (fp.name, fp.partner) if k))


def _form_params_of(effect, name) -> tuple[str, ...]:
    """The parameters the form ``name`` of an effect adds to the effect's own, each with its partner (none for
    another name)."""
    form = CATALOGUE[effect].form(name) if effect in CATALOGUE else None
    return tuple(k for fp in form.parameters for k in (fp.name, fp.partner) if k) if form is not None else ()


def _form_params(d, effect) -> tuple[str, ...]:
    """The parameters the form a selected effect is fitted in adds to the effect's own (none in its own form)."""
    return _form_params_of(effect, (getattr(d, "forms_", None) or {}).get(effect))


def listed(items) -> str:
    """Words joined as a user reads a list: ``a``, ``a and b``, ``a, b and c``."""
    items = list(items)
    return items[0] if len(items) == 1 else f"{', '.join(items[:-1])} and {items[-1]}"


def _named(effect: str, form: str | None) -> str:
    """An effect's name with the other form it is in (``speed_sensor_lag (delay form)``), or alone."""
    return f"{effect} ({form} form)" if form else effect


def label(r) -> str:
    """A candidate's name, with the other form its result is in.

    Parameters
    ----------
    r : CandidateResult
        A candidate's result (its ``form`` None for the effect's own form).

    Returns
    -------
    str
        ``speed_sensor_lag (delay form)``, or the effect's name alone.
    """
    return _named(r.effect, getattr(r, "form", None))


def _fitted_effect_params(d):
    """``(effect, parameter)`` of every selected effect's parameter the final calibration fitted (its form's
    too)."""
    fitted = d.final_calibration_.values_
    return [(e, k) for e in d.selected_ for k in _effect_params(e) + _form_params(d, e) if k in fitted]


def form_verdicts(d) -> list[tuple]:
    """Every other form of a supported candidate the diagnosis tried, with its verdict.

    Parameters
    ----------
    d : Diagnosis
        A fitted diagnosis.

    Returns
    -------
    list of (str, str, CandidateResult, str, str, str)
        The effect, the form's name, its evidence against the candidate in its own form, ``judged in it``
        (the supported form of lowest BIC, in which the round then judged the candidate) or ``not used``,
        why (the evidence's own reason), and the model it was a candidate for (``base + ...``).  A form refitted
        more than once against the same model (a round refitted from a re-anchored model) is listed once, with
        its last refit, the one the round used.
    """
    entries = list(getattr(d, "form_results_", None) or [])
    key = [(e[0], e[1], tuple(e[4])) for e in entries]
    out = []
    for i, (e, f, r, chosen, against) in enumerate(x[:5] for x in entries):
        n = key.count(key[i])
        if key[i] in key[i + 1:]:
            continue  # refitted again later against the same model: that refit is the one the round used
        why = r.reason if chosen or not r.supported else f"{r.reason}; another form has the lower BIC"
        if n > 1:
            why += (f" (the last of {n} refits of this form against this model: the round was refitted from a "
                    "re-anchored model)")
        out.append((e, f, r, "judged in it" if chosen else "not used", why,
                    "base + " + ", ".join(against) if against else "the base"))
    return out


def _selected_names(d) -> list[str]:
    """The selected effects, each fitted in another form named with it (``speed_sensor_lag (second_order
    form)``)."""
    forms = getattr(d, "forms_", None) or {}
    return [_named(e, forms.get(e)) for e in d.selected_]


def _params_dict(cal) -> dict:
    return {k: {"value": json_number(cal.values_[k]), "stderr": json_number(cal.stderr_[k]), "unit": unit_of(k),
                "on_bound": k in cal.on_bound_, "not_identifiable": k in cal.not_identifiable_} for k in cal.names_}


# --- diagnosis ----------------------------------------------------------------------------------------
#: width [characters] the text summary of a diagnosis is wrapped to
SUMMARY_WIDTH = 100


def greedy_order(d) -> list[str]:
    """The effects the greedy search added, round by round (before the backward check removed any).

    Parameters
    ----------
    d : Diagnosis
        A fitted diagnosis.

    Returns
    -------
    list of str
        The first candidate of each round that added one (a round adds its first-ranked candidate when
        it is supported).
    """
    return _added_in(d.rounds_)


def _added_in(rounds) -> list[str]:
    """The first candidate of each of ``rounds`` that added one (it is supported)."""
    return [label(rnd[0]) for rnd in rounds if rnd and rnd[0].supported]


def round_model(d, i: int, base: str = "the base") -> str:
    """What the candidates of round ``i`` were judged against: ``base``, or "base + " the effects the earlier
    rounds added (a round that added nothing adds nothing to the list: a round of pairs can follow it).

    Parameters
    ----------
    d : Diagnosis
        A fitted diagnosis.
    i : int
        Index of the round in ``d.rounds_``.
    base : str
        Words for the base model.

    Returns
    -------
    str
    """
    before = _added_in(d.rounds_[:i])
    return base if not before else "base + " + ", ".join(before)


def candidate_verdict(d, i: int, r) -> tuple[str, str]:
    """What became of a candidate of a diagnosis round, and why.

    Parameters
    ----------
    d : Diagnosis
        A fitted diagnosis.
    i : int
        Index of the round in ``d.rounds_``.
    r : CandidateResult
        A candidate of that round.

    Returns
    -------
    (str, str)
        ``added``, ``added, then removed`` (by the backward or the swap check), ``added by the swap
        check``, ``supported, not added`` or ``rejected``; and the reason: the candidate's own
        (:attr:`CandidateResult.reason`), with the backward or swap check's for a removed one, or, for a
        supported candidate the round did not add, which one it added in its place.
    """
    rnd = d.rounds_[i]
    added = rnd[0].effect if rnd and rnd[0].supported else None
    if r.supported and r.effect == added:
        removed = {x.effect: x for x in getattr(d, "removed_", None) or []}
        if r.effect in removed:
            return "added, then removed", f"{r.reason}; then {removed[r.effect].reason}"
        return "added", r.reason
    swaps = getattr(d, "swaps_", None) or {}
    if r.supported and r.effect in swaps and r.effect in d.selected_ and swaps[r.effect] == added:
        partners = [k for k, v in swaps.items() if v == added and k != r.effect]
        return "added by the swap check", (f"{r.reason}; {added} had the lower dBIC and was added first, then "
                                           f"replaced by {r.effect}"
                                           + (f" together with {listed(partners)}" if partners else "")
                                           + " in the swap check")
    if r.supported and added is not None:
        then = (f"tried again against it in round {i + 2}" if i + 1 < len(d.rounds_) else
                f"at most {d.max_effects} effects are added")
        return "supported, not added", f"{r.reason}; but {added} has the lower dBIC and was added instead; {then}"
    return ("supported, not added" if r.supported else "rejected"), r.reason


def _result_dict(r, verdict: str, why: str) -> dict:
    """:meth:`CandidateResult.to_dict` led by the effect, both dBICs, the verdict and why."""
    out = r.to_dict()
    first = {"effect": out.pop("effect"), "delta_bic": out.pop("delta_bic"),
             "delta_bic_whitened": json_number(r.delta_bic_corrected), "verdict": verdict, "reason": why}
    out.pop("reason", None)
    return {**first, **out}


def candidate_dict(d, i: int, r) -> dict:
    """A candidate of a diagnosis round as a JSON-ready dictionary, with both dBICs and its verdict.

    Parameters
    ----------
    d : Diagnosis
        A fitted diagnosis.
    i : int
        Index of the round in ``d.rounds_``.
    r : CandidateResult
        A candidate of that round.

    Returns
    -------
    dict
        :meth:`CandidateResult.to_dict` with ``delta_bic`` (plain, as before)
        followed by ``delta_bic_whitened`` (the residual's coloured noise
        modelled; the same number as ``delta_bic_corrected``), ``verdict``
        (see :func:`candidate_verdict`) and ``reason`` (why, for every
        candidate).
    """
    return _result_dict(r, *candidate_verdict(d, i, r))


#: the space between a number and its unit (kept by :func:`_wrap`)
_NUMBER_UNIT = re.compile(r"(?<=\d) (?=%|(?:A|Hz|s|ms|rpm|kg|m|N|rad|kg\*m\^2|N\*m)(?![\w*]))")


def _wrap(text: str, indent: str, hang: int = 2) -> list[str]:
    """``text`` wrapped to :data:`SUMMARY_WIDTH` columns, ``indent`` before it and ``hang`` more before its
    continuation lines; a number stays with its unit and its ``+-`` error."""
    glued = _NUMBER_UNIT.sub("\xa0", text).replace(" +- ", "\xa0+-\xa0")
    lines = textwrap.wrap(glued, SUMMARY_WIDTH, initial_indent=indent, subsequent_indent=indent + " " * hang,
                          break_long_words=False, break_on_hyphens=False) or [indent.rstrip()]
    return [line.replace("\xa0", " ") for line in lines]


def _bic_text(v) -> str:
    """``-25.5``, ``+57.3``; ``-`` for no number (a refit that failed)."""
    return f"{v:+.1f}" if v is not None and math.isfinite(v) else "-"


def _fit_text(v) -> str:
    """``95.1``; ``-`` for no number."""
    return f"{v:.1f}" if v is not None and math.isfinite(v) else "-"


def oscillation_dict(osc) -> dict | None:
    """A sustained oscillation of the record's current (:class:`~kilnctl.measure.oscillation.Oscillation`) as
    ``f_hz`` [Hz], ``rms_A`` [A] and ``share`` [-], or None."""
    if osc is None:
        return None
    return {"f_hz": json_number(osc.f_hz), "rms_A": json_number(osc.rms), "share": json_number(osc.share)}


def oscillation_text(osc) -> str:
    """What a user reads about a sustained oscillation of the record's current after the ramp."""
    return (f"The record's current oscillates at {osc.f_hz:.2f} Hz after the ramp ({osc.rms:.0f} A RMS, "
            f"{100 * osc.share:.0f} % of its variance): a loop hunting. Each candidate with one parameter was "
            "also started where the model oscillates at that frequency.")


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
        # how the file was read (units converted, columns ignored, samples missing, spikes): with the report files,
        # not only on the terminal
        "record_notes": list(getattr(d.measurement_, "notes", ())),
        "baseline": {k: json_number(v) for k, v in d.baseline_.items()},
        "baseline_parameters": _params_dict(d.base_calibration_),
        "base_refit": {k: json_number(v) for k, v in getattr(d, "base_refit_", {}).items()},
        "oscillation": oscillation_dict(getattr(d, "oscillation_", None)),
        "ranking": [candidate_dict(d, 0, r) for r in d.ranking_],
        "rounds": [[candidate_dict(d, i, r) for r in rnd] for i, rnd in enumerate(d.rounds_)],
        "selected": list(d.selected_),
        "removed": [_result_dict(r, "removed", r.reason) for r in getattr(d, "removed_", None) or []],
        "swaps": dict(getattr(d, "swaps_", None) or {}),
        "forms": dict(getattr(d, "forms_", None) or {}),
        "forms_tried": [dict(_result_dict(r, verdict, why), form=f, candidate_for=against)
                        for _, f, r, verdict, why, against in form_verdicts(d)],
        "final": {k: json_number(v) for k, v in d.final_.items()},
        "final_parameters": _params_dict(fc),
        "final_search": dict(getattr(d, "final_search_", {})),
        "unexplained": _jsonable(d.unexplained_),
        "caveats": list(d.caveats_),
        "residual_signature": _jsonable(d.signature_),
        "failing_before": d.comparison_base_.failing,
        "failing_after": d.comparison_final_.failing,
        "experiment": d.experiment_.to_dict(),
        "settings": {"calibrate": list(d.calibrate), "candidates": list(d.candidates), "model": d.model,
                     "holdout": d.holdout, "holdout_fraction": d.holdout_fraction,
                     "min_delta_bic": d.min_delta_bic, "min_holdout_gain_percent": d.min_holdout_gain,
                     "holdout_z": d.holdout_z},
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
        removed = [r.effect for r in getattr(d, "removed_", None) or []]
        s = ("no catalogued effect is supported by the data" if not removed else
             f"no catalogued effect kept ({', '.join(removed)} selected, then removed)")
        s += f"; current fit {c1:.1f} % with the calibrated base model"
        case = _final_against_first(d)
        if case == "better":
            s += f" (its first calibration stopped at {c0:.1f} %)"
        elif case == "beside_change":
            s += f" at the values fitted beside the change outside the catalogue ({c0:.1f} % calibrated through it)"
        elif case == "lower":
            s += f" (the base as first calibrated: {c0:.1f} %)"
        if d.unexplained_:
            s += f"; the residual still has structure ({d.unexplained_['hint']})"
        return s
    fc = d.final_calibration_
    parts = [f"{k} = {_fmt_val(fc.values_[k], fc.stderr_[k])} {unit_of(k).strip('-')}".rstrip()
             for _, k in _fitted_effect_params(d)]
    s = (f"current fit rose from {c0:.1f} % to {c1:.1f} % after adding {', '.join(_selected_names(d))}"
         + (f", {', '.join(parts)}" if parts else ""))
    cb = _base_refit_fit(d)
    if cb is not None:
        s += f" (the base model alone, calibrated again from a better start, reaches {cb:.1f} %)"
    return s


def _base_refit_fit(d) -> float | None:
    """The base model's current fit [%] where a round re-anchored it at least a point above the baseline, else
    None: that part of the rise is the base's, not an effect's (red team 12's R16 on slow noise: 84.7 % to
    92.0 % by the base alone, 92.5 % with an unbalance, and the headline gave the unbalance all of it)."""
    cb = (getattr(d, "base_refit_", None) or {}).get("current_A", math.nan)
    return cb if math.isfinite(cb) and cb - d.baseline_["current_A"] >= 1.0 else None


#: width of the effect column of the summary's tables [characters]; a longer name (a pair, an effect in another
#: form) stands on a line of its own above its numbers
EFFECT_WIDTH = 22


def _summary_rows(r, verdict: str, why: str) -> list[str]:
    """A candidate's row of the summary's table, then why, wrapped."""
    gain = f"{_signed(r.holdout_gain)} %" if math.isfinite(r.holdout_gain) else "-"
    fi = _fit_text(r.fit_percent.get("current_A", math.nan))
    name = label(r)
    first = [f"    {name}"] if len(name) > EFFECT_WIDTH else []
    return (first + [f"    {'' if first else name:<{EFFECT_WIDTH}} {_bic_text(r.delta_bic):>9} "
                     f"{_bic_text(r.delta_bic_corrected):>14} {gain:>9} {fi:>6}  {verdict}"]
            + _wrap(f"why: {why}", " " * 8, 5))


def diagnosis_summary(d) -> str:
    """Return a readable account of a fitted diagnosis, wrapped to :data:`SUMMARY_WIDTH` columns.

    Each round is a table of its candidates (plain and whitened dBIC, held-out gain, current fit,
    verdict), each followed by why (:func:`candidate_verdict`); long lines continue indented.

    Parameters
    ----------
    d : Diagnosis
        A fitted diagnosis.

    Returns
    -------
    str
    """
    lines = _wrap(f"diagnosis of {d.measurement_.source} ({d.wall_s_:.0f} s)", "")
    for note in getattr(getattr(d, "experiment_", None), "notes", ()):
        lines += _wrap(f"experiment: {note}", "  ")  # the reference the model follows, and where it starts
    lines += _wrap(f"baseline (calibrated {', '.join(d.calibrate)}): {format_fit(d.baseline_)}", "  ")
    if getattr(d, "oscillation_", None) is not None:
        lines += _wrap(oscillation_text(d.oscillation_), "  ")
    lines += _wrap("dBIC: BIC change on the fitted part (negative favours the effect; plain and with the "
                   "residual's coloured noise modelled, 'whitened'); held-out: error reduction on the part not "
                   "fitted [%]; fit\u00a0I: current fit on the fitted part [%]", "  ")
    head = f"    {'effect':<{EFFECT_WIDTH}} {'dBIC':>9} {'whitened dBIC':>14} {'held-out':>9} {'fit I':>6}  verdict"
    for i, rnd in enumerate(d.rounds_):
        lines.append(f"  round {i + 1}: candidates against "
                     + round_model(d, i))
        lines.append(head)
        lines += [x for r in rnd for x in _summary_rows(r, *candidate_verdict(d, i, r))]
    forms = form_verdicts(d)
    if forms:
        lines += _wrap("other forms of a candidate, each against the candidate in its own form", "  ")
        lines.append(head)
        lines += [x for e, f, r, verdict, why, against in forms
                  for x in _summary_rows(dataclasses.replace(r, form=f), verdict,
                                         f"as a candidate for {against}: {why}")]
    removed = getattr(d, "removed_", None) or []
    if removed:
        lines += _wrap("effects added, then removed (by the backward or the swap check on the fitting part, or "
                       "the final check on the whole record), each judged as if added to the model without it, or "
                       "with its replacement in its place (the dBICs of keeping it)", "  ")
        lines.append(head)
        lines += [x for r in removed for x in _summary_rows(r, "removed", r.reason)]
    lines += _wrap(f"selected: {', '.join(_selected_names(d)) or 'nothing'}", "  ")
    lines += _wrap(f"final: {format_fit(d.final_)}", "  ")
    fs = getattr(d, "final_search_", None)
    if fs and fs["n_local_fits"]:
        lines += _wrap(f"final refit: the best of {fs['n_local_fits']} local fits from {fs['n_starts']} starting "
                       "points; their current fits " + ", ".join(f"{v:.1f}" for v in fs["fit_current_percent"])
                       + " %" + ("; then without " + ", ".join(fs["then_removed"]) + " (final check), refitted from "
                                 "there" if fs.get("then_removed") else ""), "  ")
    lines += _wrap(diagnosis_headline(d), "  ")
    if d.unexplained_:
        lines += _wrap("unexplained residual: " + d.unexplained_["text"], "  ", 4)
    for c in d.caveats_:
        lines += _wrap("caution: " + c, "  ", 4)
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
    final = "final: base + " + ", ".join(d.selected_) if d.selected_ else "final: base, no effect added"
    return d.comparison_base_.plot(fig=fig, compare_with=d.comparison_final_, labels=("calibrated base", final))


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
    from matplotlib.transforms import ScaledTranslation

    from ..figures import COLORS, finish, record_name

    rk = d.ranking_
    fig = fig or Figure(figsize=(13, 2.8 + 0.3 * max(len(rk), 4)))  # the first panel's legend below it
    a0, a1, a2 = fig.subplots(1, 3, gridspec_kw={"width_ratios": [3, 3, 2]})
    names = [r.effect + (f" ({r.form})" if r.form else "") for r in rk]
    colors = [COLORS["supported"] if r.supported else COLORS["rejected"] for r in rk]
    y = np.arange(len(rk))
    def clipped(v):
        return max(-1e6, v) if math.isfinite(v) else 0.0

    a0.barh(y - 0.2, [-clipped(r.delta_bic) for r in rk], 0.4, color=colors)
    a0.barh(y + 0.2, [-clipped(r.delta_bic_corrected) for r in rk], 0.4, color=colors, alpha=0.55, hatch="///",
            edgecolor="0.25", lw=0)
    a0.set_xscale("symlog", linthresh=10)
    a0.axvline(d.min_delta_bic, color=COLORS["threshold"], ls=":", label=f"threshold {d.min_delta_bic:g}")
    a0.axvline(0, color="0.3", lw=0.6)
    a0.set_yticks(y, names, fontsize=8)
    a0.invert_yaxis()
    a0.set_xlabel("BIC improvement -dBIC on the fitted part [-]\n(log scale beyond 10)")
    a0.set_title("evidence in the fitted part (more is better)", fontsize=9)
    a0.legend(handles=[Patch(color=COLORS["supported"], label="supported (both tests)"),
                       Patch(color=COLORS["rejected"], label="not supported"),
                       Patch(facecolor="white", edgecolor="0.25", label="solid: -dBIC (plain)"),
                       Patch(facecolor="white", hatch="///", edgecolor="0.25",
                             label="hatched: -whitened dBIC (coloured noise modelled)"),
                       *a0.get_legend_handles_labels()[0]], fontsize=7.5, loc="upper center", ncol=2,
              # below the tick labels and the two-line axis label, whatever the panel's height
              bbox_to_anchor=(0.5, 0.0), bbox_transform=a0.transAxes + ScaledTranslation(0, -0.62,
                                                                                           fig.dpi_scale_trans))
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
    a1.set_xlabel("held-out gain [%]:\nerror reduction on samples not fitted")
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


def _effect_words(name: str) -> str:
    return name.replace("_", " ")


def _final_against_first(d) -> str | None:
    """How a diagnosis' final current fit stands against the base's first calibration, for the headlines:
    "better" (0.05 point or more above it: the search found the base a better optimum), "beside_change" (as
    much below, the base evaluated at the values fitted beside a change that comes and goes or a periodic one,
    see :meth:`~kilnctl.measure.checks.SelectionChecks._final_pulse`), "lower" (below for another reason), or None."""
    c0, c1 = d.baseline_["current_A"], d.final_["current_A"]
    if c1 >= c0 + 0.05:
        return "better"
    if c1 <= c0 - 0.05:
        beside = (getattr(d, "outside_change_", None) or {}).get("kind") in ("pulse", "line")
        return "beside_change" if beside else "lower"
    return None


def diagnosis_plain_headline(d) -> str:
    """The diagnosis in one plain sentence, for the top of the report.

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
        # the final model is the base structure, refitted where the search found it a better optimum, or at the
        # values fitted beside a change outside the catalogue (then it fits less than the base calibrated
        # through the change: red team 18's X1, 87.4 % against 89.2 %)
        again = {"better": f" (its first calibration stopped at {c0:.1f} %; the search found the same model a "
                           "better optimum)",
                 "beside_change": f" at the values fitted beside the change named next ({c0:.1f} % calibrated "
                                 "through it, which the change pulls off the plant's values)",
                 "lower": f" (the base as first calibrated: {c0:.1f} %)"}.get(_final_against_first(d), "")
        removed = [_effect_words(r.effect) for r in getattr(d, "removed_", None) or []]
        if removed:
            first = (f"{listed(removed)} {'was' if len(removed) == 1 else 'were'} selected and then removed (the "
                     "reasons below)")
        else:
            first = f"none of the {len(d.ranking_)} candidates passed both tests"
        tried = f"{first}; the calibrated model fits the current to {c1:.1f} %{again}"
        if d.unexplained_:
            # not "needs no catalogued effect to explain this record": the record is not explained (red team 6's
            # soft backlash at 90.9 % read as all well)
            return (f"No catalogued effect explains what the model misses: {tried}, and the residual has structure "
                    f"the catalogue does not explain: {d.unexplained_['hint']}.")
        return f"The model needs no catalogued effect to explain this record: {tried}."
    fc = d.final_calibration_
    vals: dict = {e: [] for e in d.selected_}
    for e, k in _fitted_effect_params(d):
        vals[e].append(f"{k} = {_value_words(fc.values_[k], fc.stderr_[k], k in fc.not_identifiable_, unit_of(k))}")
    forms = getattr(d, "forms_", None) or {}
    found = [_effect_words(e) + (f" in its {_effect_words(forms[e])} form" if e in forms else "")
             + (f" ({', '.join(v)})" if v else "") for e, v in vals.items()]
    effects = listed(found)
    s = (f"Missing from the model: {effects}. With {'it' if len(found) == 1 else 'them'} the current fit rose "
         f"from {c0:.1f} % to {c1:.1f} %.")
    cb = _base_refit_fit(d)
    if cb is not None:
        s += f" Of that rise, {cb - c0:.1f} points are the base model's own, calibrated again from a better start."
    if d.caveats_:
        s += f" Read the caution{'s' if len(d.caveats_) > 1 else ''} below before acting on it."
    return s


def _value_words(v, se, not_identifiable=False, unit="") -> str:
    """``20.7 ± 0.1 kg·m²``; words where the uncertainty is not a number."""
    unit = f" {pretty_unit(unit)}" if unit and unit != "-" else ""
    if v is None or not math.isfinite(v):
        return "not determined"
    if not_identifiable or se is None or not math.isfinite(se):
        return f"{v:.4g}{unit} (not identifiable from this record)"
    a, b = value_pair(v, se)
    return (f"{a} ± {b}" if b else a) + unit


def _signed(x: float) -> str:
    """``+44.8``; ``+0.0`` rather than ``-0.0``."""
    return f"{round(x, 1) + 0.0:+.1f}" if math.isfinite(x) else "-"


def uncertainty_words(se, not_identifiable: bool = False, on_bound: bool = False) -> str:
    """The uncertainty of a fitted value in a report cell: ``± 0.13`` or words, never ``± inf``.

    Parameters
    ----------
    se : float or None
        Standard error [unit of the value].
    not_identifiable : bool
        The record does not pin the value down.
    on_bound : bool
        The fit stopped on the parameter's bound.

    Returns
    -------
    str
    """
    words = []
    if not_identifiable or se is None or not math.isfinite(se):
        words.append("not identifiable from this record: other values fit as well")
    elif se == 0:
        words.append("exact (held by the fit)")
    else:
        words.append(f"± {value_pair(1.0, se)[1]}")
    if on_bound:
        words.append("on its bound: the fit wanted to go further")
    return "; ".join(words)


#: what the numbers in the reports mean, for a reader who is not a statistician
HOW_TO_READ = {
    "fit": ("fit %", "How much of the measured signal the model reproduces: 100 % is a perfect match, 0 % is no "
                     "better than a flat line at the mean (the normalised error of MATLAB's <code>compare</code>). "
                     "On a start-up record 95 % is good; the last few per cent often hold the effect you look for."),
    "sigma": ("3 σ intervals", "Where the residual (measured minus model) stays beyond three times its robust "
                              "standard deviation: there the model fails, not the noise."),
    "whiteness": ("residual autocorrelation", "A residual that is only noise has its autocorrelation inside the "
                                              "grey 99 % band; many lags outside mean the model misses something "
                                              "with a time structure."),
    "dbic": ("dBIC and whitened dBIC", "How much the Bayesian information criterion falls when an effect is "
                                        "added, on the fitting part of the record. It charges for every extra "
                                        "parameter; below −{min_delta_bic:g} counts as very strong evidence. It "
                                        "alone is fooled by coloured noise, hence the second test. The whitened "
                                        "dBIC is the same with the residual's "
                                        "coloured noise modelled (an autoregressive model of it): the evidence "
                                        "that is left once slow noise is allowed for."),
    "heldout": ("held-out gain", "How much better (in %) the model with the effect predicts the part of the "
                                 "record it was not fitted on. An effect that only fits noise gains nothing "
                                 "there; it must gain more than {min_holdout_gain:g} %. An effect whose trace lies "
                                 "mostly in the fitted part may instead pass with a BIC that also falls by more "
                                 "than {min_delta_bic:g} with the coloured noise modelled, and a held-out loss of "
                                 "less than {holdout_z:g} standard errors. Where the model already fits closely, "
                                 "a small gain must also be borne out: by the whitened dBIC, or by more than "
                                 "{holdout_z:g} standard errors; and no gain counts when the whitened dBIC rises "
                                 "(slow noise links the held-out blocks to their neighbours). Where the model has "
                                 "stick-slip cycles, any added parameter can shift them: a candidate that predicts "
                                 "the held-out part worse then needs the whitened dBIC to fall by "
                                 "more than {stick_slip_dbic:g}, and with that fall it passes however much worse "
                                 "(the cycles of the held-out blocks a sample off). An effect is "
                                 "<b>supported</b> only when it "
                                 "passes both tests."),
    "cautions": ("cautions", "Where the evidence is weaker than the numbers suggest (a record shorter than the "
                             "effect's period, a strongly autocorrelated residual, evidence just past the "
                             "threshold, another effect or another form of it that explains the record about as "
                             "well). Read them before acting."),
    "uncertainty": ("± values", "One standard error of a fitted value, from the fit's curvature and the "
                                "residual's correlation in time (slow noise pins a value down less than white "
                                "noise of the same size). It covers the noise, not a bias: an effect in another "
                                "form than the model's can leave a value several standard errors off. \"not "
                                "identifiable\" means the record does not pin the value down: other values fit "
                                "as well."),
    "linear": ("linear vs nonlinear", "The design is linear (eq. 21, no load torque, stick or slip inertia); the "
                                      "nonlinear plant adds the burden's friction and load, its breakaway and "
                                      "the drive's limits. Where they part, the reasons list says why."),
    "ramp": ("predicted / verified / baseline", "Predicted: the smooth model the optimizer works on. Verified: "
                                                "the exact hybrid plant with the same ramp. Baseline: the hybrid "
                                                "plant with the configured constant ramp. Prediction and "
                                                "verification must agree within the tolerance, or the result is "
                                                "flagged."),
    "objective": ("peak and dynamic stress", "Peak: the highest tooth bending stress of the start-up, running "
                                             "load included. Dynamic: the stress above the burden's running load "
                                             "(impacts, acceleration): what a ramp can change."),
}


def how_to_read(keys, **values) -> str:
    """Return the "how to read this" box for the given terms.

    Parameters
    ----------
    keys : sequence of str
        Terms of :data:`HOW_TO_READ`, in order.
    **values
        Numbers the texts name (``min_delta_bic``, ``min_holdout_gain``, ``holdout_z``, ``stick_slip_dbic``).

    Returns
    -------
    str
        HTML.
    """
    items = "".join(f"<dt>{esc(HOW_TO_READ[k][0])}</dt><dd>{HOW_TO_READ[k][1].format(**values)}</dd>" for k in keys)
    return f'<div class="howto"><h2>How to read this</h2><dl>{items}</dl></div>'


def settings_table(settings: dict, meanings: dict | None = None) -> str:
    """Return a small two- or three-column table of settings.

    Parameters
    ----------
    settings : dict
        Setting name -> value (lists are joined with commas).
    meanings : dict, optional
        Setting name -> what it means.

    Returns
    -------
    str
        HTML.
    """
    meanings = meanings or {}
    rows = []
    for k, v in settings.items():
        if isinstance(v, (list, tuple)):
            v = ", ".join(str(x) for x in v) or "-"
        elif isinstance(v, float):
            v = f"{v:g}"
        rows.append((k, v, meanings.get(k, "")) if meanings else (k, v))
    header = ["setting", "value", "meaning"] if meanings else ["setting", "value"]
    return table(header, rows, left=2, wrap=(2,) if meanings else ())


def parameter_table(names, values, stderr, *, not_identifiable=(), on_bound=(), description=True) -> str:
    """Return a table of fitted parameters: value, uncertainty in words where needed, unit, meaning.

    Parameters
    ----------
    names : sequence of str
        Parameter names.
    values, stderr : dict
        Value and standard error [unit of the parameter] by name.
    not_identifiable, on_bound : collection of str
        Names so flagged by the fit.
    description : bool, default True
        Add the parameter's description from :data:`~kilnctl.params.SPECS`.

    Returns
    -------
    str
        HTML.
    """
    rows = []
    for k in names:
        v, se = values[k], stderr.get(k)
        val, err = value_pair(v, se)
        unc = uncertainty_words(se, k in not_identifiable, k in on_bound)
        if err and k not in not_identifiable:
            unc = unc.replace(f"± {value_pair(1.0, se)[1]}", f"± {err}")
        row = [k, val, unc, pretty_unit(unit_of(k))]
        if description:
            row.append(SPECS[k].description if k in SPECS else "")
        rows.append(row)
    header = ["parameter", "value", "uncertainty", "unit"] + (["meaning"] if description else [])
    return table(header, rows, left=1, wrap=(2, 4) if description else (2,))


def figure_block(fig, alt: str, caption: str = "") -> str:
    """A figure with its caption.

    Parameters
    ----------
    fig : matplotlib.figure.Figure or bytes
        The figure, or its PNG content.
    alt : str
        Alternative text.
    caption : str
        What it shows (plain text).

    Returns
    -------
    str
        HTML.
    """
    return figure_tag(fig, alt) + (f'<p class="cap">{esc(caption)}</p>' if caption else "")


def report_page(title: str, headline: str, body, *, warnings=(), terms=(), values=None, notes=(), settings=None,
                meanings=None) -> str:
    """Return a report in the layout every kilnctl report page shares, as one self-contained HTML page.

    The layout: the headline in plain words, warnings, the "how to read this" box, the body
    (numbers as small tables with units, figures), notes, and the settings as a table.

    Parameters
    ----------
    title : str
        Page title.
    headline : str
        The result in one or two plain sentences.
    body : sequence of str
        HTML sections, in order.
    warnings : sequence of (str, str)
        ``(label, text)`` of each warning (``("Caution", "...")``).
    terms : sequence of str
        Terms of :data:`HOW_TO_READ` to explain.
    values : dict, optional
        Numbers the explanations name (see :func:`how_to_read`).
    notes : sequence of str
        Notes after the body.
    settings : dict, optional
        Setting name -> value (:func:`settings_table`).
    meanings : dict, optional
        Setting name -> what it means.

    Returns
    -------
    str
    """
    parts = [f'<p class="big">{esc(headline)}</p>']
    parts += [f'<p class="warn"><b>{esc(label)}:</b> {esc(text)}</p>' for label, text in warnings]
    parts.append(how_to_read(terms, **(values or {})))
    parts += list(body)
    parts += [f"<p>Note: {esc(n)}</p>" for n in notes]
    parts.append("<h2>Settings</h2>" + settings_table(settings or {}, meanings))
    return page(title, "\n".join(parts))


def _failing_table(failing) -> str:
    """The intervals where a model fails beyond 3 sigma, as a table (or a sentence when there are none)."""
    rows = [(f["channel"], f["text"]) for f in failing]
    return table(["channel", "interval"], rows, left=2, wrap=(1,)) if rows else "<p>nowhere beyond 3 sigma</p>"


_DIAGNOSIS_SETTINGS = {
    "calibrate": "base parameters refitted with every structure",
    "candidates": "catalogue effects tried",
    "model": "base model",
    "holdout": "how the held-out part is chosen",
    "holdout_fraction": "share of the record held out [-]",
    "min_delta_bic": "a candidate must lower BIC by more than this [-]",
    "min_holdout_gain_percent": "... and improve the held-out fit by more than this [%]",
    "holdout_z": "... or else not predict it worse by more than this many standard errors [-]",
}


def _candidate_row(r, verdict: str, why: str) -> tuple:
    """A candidate's row of the report's tables (header: see :func:`diagnosis_html`): the effect's parameters,
    and those of the other form its result is in."""
    names = _effect_params(r.effect) + _form_params_of(r.effect, getattr(r, "form", None))
    pars = "; ".join(f"{k} = {_value_words(v['value'], v['stderr'], k in r.not_identifiable, v['unit'])}"
                     for k, v in r.parameters.items() if k in names)
    return (label(r), _bic_text(r.delta_bic), _bic_text(r.delta_bic_corrected), _signed(r.holdout_gain),
            _fit_text(r.fit_percent.get("current_A", math.nan)), pars or "-",
            f"{verdict}: {why}" + (". On bound: " + ", ".join(r.on_bound)) * bool(r.on_bound))


def diagnosis_html(d, figs=None) -> str:
    """Return the report of a fitted diagnosis as one self-contained HTML page.

    Parameters
    ----------
    d : Diagnosis
        A fitted diagnosis.
    figs : dict, optional
        Figures already drawn (name -> Figure or its PNG content): the
        signals, then the ranking.

    Returns
    -------
    str
    """
    figs = figs or {"s": plot_diagnosis(d), "r": plot_ranking(d)}
    f_sig, f_rank = list(figs.values())
    parts = ["<h2>Measured, calibrated base and final model</h2>"]
    parts.append(figure_block(f_sig, "signals and residuals",
                              "Per channel: the signals, the residual, its autocorrelation and its spectrum, for "
                              "the calibrated base model (blue) and the final model (red). Red shading: where the "
                              "base model fails beyond 3 sigma. Dashed lines: phases of the start-up."))
    parts.append("<h3>Where the base model fails</h3>" + _failing_table(d.comparison_base_.failing))
    parts.append("<h3>Where the final model fails</h3>" + _failing_table(d.comparison_final_.failing))
    fc = d.final_calibration_
    parts.append("<h2>Final model: fitted parameters</h2>")
    parts.append(f"<p>{esc(', '.join(d.calibrate))} refitted with "
                 f"{esc(', '.join(d.selected_) or 'no effect added')} on the whole record "
                 f"(current fit {d.final_['current_A']:.1f} %, speed fit {d.final_['speed_rpm']:.1f} %).</p>")
    parts.append(parameter_table(fc.names_, fc.values_, fc.stderr_, not_identifiable=fc.not_identifiable_,
                                 on_bound=fc.on_bound_))
    if getattr(d, "oscillation_", None) is not None:
        parts.append(f"<p>{esc(oscillation_text(d.oscillation_))}</p>")
    parts.append("<h2>Candidates</h2>")
    parts.append(figure_block(f_rank, "ranking", "Green: supported (both tests passed); grey: not supported. "
                              "Left: dBIC, plain (solid) and whitened (hatched), the round-1 table's two dBIC "
                              "columns. Dotted lines: the thresholds."))
    header = ["effect", "dBIC", "whitened dBIC", "held-out gain [%]", "current fit [%]", "effect parameters",
              "verdict and why"]
    for i, rnd in enumerate(d.rounds_):
        parts.append(f"<h3>Round {i + 1}: against " + esc(round_model(d, i, "the calibrated base")) + "</h3>")
        verdicts = [candidate_verdict(d, i, r) for r in rnd]
        rows = [_candidate_row(r, *v) for r, v in zip(rnd, verdicts)]
        sel = {j for j, (v, _) in enumerate(verdicts) if v in ("added", "added by the swap check")}
        parts.append(table(header, rows, left=1, selected=sel, wrap=(5, 6)))
    forms = form_verdicts(d)
    if forms:
        parts.append("<h3>Other forms of a candidate</h3><p>A supported candidate with other forms is refitted "
                     "in each (a current limit also when the clamp lowered the BIC without being supported: a "
                     "limiter of finite bandwidth misses the clamp by hundreds of amperes); a form counts on the "
                     "same evidence as a candidate, judged against the candidate in its own form, and the round "
                     "judges the candidate in its best form.</p>")
        parts.append(table(header, [_candidate_row(dataclasses.replace(r, form=f), verdict,
                                                   f"as a candidate for {against}: {why}")
                                    for e, f, r, verdict, why, against in forms], left=1,
                           selected={j for j, x in enumerate(forms) if x[3] == "judged in it"}, wrap=(5, 6)))
    removed = getattr(d, "removed_", None) or []
    if removed:
        parts.append("<h3>Effects added, then removed</h3><p>By the backward or the swap check on the fitting "
                     "part, or the final check on the whole record; each judged as if added to the model without "
                     "it, or with its replacement in its place (the dBICs of keeping it).</p>")
        parts.append(table(header, [_candidate_row(r, "removed", r.reason) for r in removed], left=1,
                           wrap=(5, 6)))
    # the whole account once, a sentence a paragraph; the warning at the top names what it suggests
    misses = (d.unexplained_ or d.signature_)["text"]
    parts.append("<h2>What the final model still misses</h2>"
                 + "".join(f"<p>{esc(x)}</p>" for x in re.split(r"(?<=\.) (?=[A-Za-z])", misses)))
    headline = diagnosis_plain_headline(d)
    # the hint once on the page: when the headline already says it, the warning points to it (red team 9)
    hint = d.unexplained_["hint"] if d.unexplained_ else ""
    said = hint and hint in headline
    warnings = ([("Unexplained", ("the structure the headline names" if said else hint)
                  + " (the whole account: \"What the final model still misses\" below)")] if d.unexplained_ else []) \
        + [("Caution", c) for c in d.caveats_]
    return report_page(f"Diagnosis of {record_name_of(d.measurement_.source)}", headline, parts,
                       warnings=warnings, terms=("fit", "dbic", "heldout", "cautions", "uncertainty", "sigma"),
                       values={"min_delta_bic": d.min_delta_bic, "min_holdout_gain": d.min_holdout_gain,
                               "holdout_z": d.holdout_z, "stick_slip_dbic": d.stick_slip_fall * d.min_delta_bic},
                       notes=[f"record: {n}" for n in getattr(d.measurement_, "notes", ())]
                       + list(d.experiment_.notes), settings=diagnosis_dict(d)["settings"],
                       meanings=_DIAGNOSIS_SETTINGS)


def record_name_of(source) -> str:
    """The record's file name (see :func:`kilnctl.figures.record_name`).

    Parameters
    ----------
    source : str or path-like
        Source of the record.

    Returns
    -------
    str
    """
    from ..figures import record_name

    return record_name(source)


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
    figs = render_pngs({"diagnose_signals.png": plot_diagnosis(d), "diagnose_ranking.png": plot_ranking(d)}, dpi=100)
    return write_page_files(folder, "diagnose", diagnosis_html(d, figs), diagnosis_dict(d), figs, protect)


# --- comparison ------------------------------------------------------------------------------------
def comparison_html(c, fig=None, record_notes=()) -> str:
    """Return the report of a comparison as one self-contained HTML page.

    Parameters
    ----------
    c : Comparison
        A comparison of a model with a record.
    fig : matplotlib.figure.Figure or bytes, optional
        Its figure, already drawn (or its PNG content).
    record_notes : sequence of str
        How the record was read (:attr:`Measurement.notes <kilnctl.measure.io.Measurement.notes>`: units
        converted, samples missing ...), shown as notes.

    Returns
    -------
    str
    """
    fig = fig or c.plot()
    names = {"current_A": "current", "speed_rpm": "speed"}
    model = f"{c.model} model" + (f" with {', '.join(c.effects)}" if c.effects else "")
    fits = " and ".join(f"the {names.get(k, k)} to {ch.fit:.1f} %" for k, ch in c.channels.items())
    fails = c.failing
    if not fails:
        where = "Nowhere does its residual stay beyond 3 sigma."
    elif len(fails) == 1:
        f0 = fails[0]
        where = f"It fails beyond 3 sigma in one interval: {names.get(f0['channel'], f0['channel'])} {f0['text']}."
    else:
        where = (f"It fails beyond 3 sigma in {len(fails)} intervals, the first: "
                 f"{names.get(fails[0]['channel'], fails[0]['channel'])} {fails[0]['text']}.")
    # bias = mean(measured - model): positive is a model too low
    offsets = [f"the {names.get(k, k)} by {abs(ch.bias):.3g} {ch.unit} on average (model too "
               f"{'low' if ch.bias > 0 else 'high'})" for k, ch in c.channels.items() if abs(ch.bias) > 0.5 * ch.rms]
    head = f"The {model} reproduces {fits}. " + (f"It misses {' and '.join(offsets)}. " if offsets else "") + where
    rows = []
    for k, ch in c.channels.items():
        w = ch.whiteness
        bias = ch.bias if abs(ch.bias) >= 1e-3 * ch.rms else 0.0
        rows.append((names.get(k, k), f"{ch.fit:.1f}", f"{ch.rms:.3g}", f"{bias:+.3g}", ch.unit,
                     f"{w['n_outside']} of {len(w['lags']) - 1}", f"{ch.spectrum['dominant_hz']:.2f}"))
    parts = ["<h2>Per channel</h2>" + table(["channel", "fit [%]", "residual rms", "bias", "unit",
                                                 "autocorrelation lags outside 99 % band",
                                                 "dominant residual frequency [Hz]"], rows),
             "<h2>Measured and model</h2>" + figure_block(fig, "measured vs model"),
             "<h2>Where it fails</h2>" + _failing_table(fails)]
    return report_page(f"{record_name_of(c.source)} against the {model}", head, parts,
                       warnings=[("Caution", text) for text in c.cautions],
                       terms=("fit", "sigma", "whiteness"),
                       notes=[f"record: {n}" for n in record_notes] + list(c.experiment.notes),
                       settings={"model": c.model, "effects": list(c.effects), "record": record_name_of(c.source)})


def write_comparison_report(c, folder, protect=(), record_notes=()) -> list:
    """Write ``compare.html`` (self-contained), ``compare.json`` and ``compare.png`` into a folder.

    Parameters
    ----------
    c : Comparison
        A :class:`~kilnctl.measure.compare.Comparison` of a model with a record.
    folder : path-like
        Destination folder (created).
    protect : sequence of path-like
        Input files never to overwrite.
    record_notes : sequence of str
        How the record was read; in the page and in ``compare.json`` (``record_notes``).

    Returns
    -------
    list of Path
        Files written (each whole or not at all).
    """
    png = png_bytes(c.plot())
    return write_page_files(folder, "compare", comparison_html(c, png, record_notes),
                            dict(c.to_dict(), record_notes=list(record_notes)), {"compare.png": png}, protect)
