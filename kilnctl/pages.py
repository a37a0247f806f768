"""One-page HTML reports of ``kilnctl verify`` and ``kilnctl optimize-ramp``.

The same layout as the measurement reports (:func:`kilnctl.measure.report.report_page`):
a plain-language headline, a "how to read this" box, the numbers as small
tables with units, the figure, the settings; self-contained (the figure is
embedded), written whole or not at all.
"""

from __future__ import annotations

import math

from .measure.report import esc, figure_block, png_bytes, report_page, table, write_page_files

__all__ = ["verify_html", "write_verify_report", "ramp_html", "write_ramp_report"]

#: the verification's quantities: label, unit, format
_VERIFY_ROWS = {
    "overshoot_pct": ("speed overshoot after the ramp", "%", "{:.2f}"),
    "settle_time_s": ("settled within 2 % of the set point at", "s", "{:.2f}"),
    "ramp_lag_rpm": ("lag behind the reference at the end of the ramp", "rpm", "{:.1f}"),
    "peak_current_A": ("peak armature current", "A", "{:.0f}"),
    "final_current_A": ("final armature current (mean of the last 5 s)", "A", "{:.0f}"),
}


def _fmt(v, f) -> str:
    return "not reached" if v is None else ("-" if not math.isfinite(v) else f.format(v))


def verify_headline(v) -> str:
    """The verification in one plain sentence.

    Parameters
    ----------
    v : Verification
        The verification (:func:`kilnctl.verify.verify`).

    Returns
    -------
    str
    """
    f, p = v.figures, v.params
    lin = v.linear["stick"]["figures"]["peak_current_A"]
    settle = "does not settle within 2 % in the simulated time" if f["settle_time_s"] is None else \
        f"settles within 2 % of {p.omega_ref:g} rpm at {f['settle_time_s']:.1f} s"
    return (f"On the nonlinear {v.nonlinear.model} model the designed gains follow the {p.ramp_rate:g} rpm/s ramp "
            f"{f['ramp_lag_rpm']:.0f} rpm behind, overshoot by {f['overshoot_pct']:.2f} % and {settle}; the current "
            f"peaks at {f['peak_current_A']:.0f} A (limit {p.I_max:g} A) against {lin:.0f} A predicted by the "
            "linear design, which carries no load torque.")


def verify_html(v, fig=None, cautions=()) -> str:
    """Return the verification as one self-contained HTML page.

    Parameters
    ----------
    v : Verification
        The verification.
    fig : matplotlib.figure.Figure or bytes, optional
        Its figure, already drawn (or its PNG content).
    cautions : sequence of str
        What the diagnosis behind a learned plant said to read before acting on it
        (:func:`kilnctl.design.learned.diagnosis_cautions`), shown at the top.

    Returns
    -------
    str
    """
    fig = fig or v.plot()
    g = v.params
    rows = []
    for r in v.table():
        label, unit, f = _VERIFY_ROWS.get(r["quantity"], (r["quantity"], "", "{:.3g}"))
        rows.append((label, unit, _fmt(r["linear_stick"], f), _fmt(r["linear_slip"], f), _fmt(r["nonlinear"], f)))
    parts = ["<h2>Linear design against the nonlinear plant</h2>"
             + table(["quantity", "unit", "linear, stick inertia", "linear, slip inertia",
                      f"nonlinear {v.nonlinear.model} model"], rows, left=2),
             "<h2>Where and why they part</h2><ul>" + "".join(f"<li>{esc(r)}</li>" for r in v.reasons) + "</ul>",
             "<h2>Speed and current</h2>" + figure_block(fig, "speed and current, linear and nonlinear")]
    return report_page(
        "Speed-loop design verified on the nonlinear plant", verify_headline(v), parts, terms=("linear",),
        warnings=[("Diagnosis caution", c) for c in cautions],
        settings={"k_p [V/rpm]": f"{g.k_p:.4g}", "k_I [V/(rpm·s)]": f"{g.k_I:.4g}", "k_D [V·s/rpm]": f"{g.k_D:.4g}",
                  "model": v.nonlinear.model, "ramp [rpm/s]": g.ramp_rate, "set point [rpm]": g.omega_ref,
                  "simulated [s]": float(v.nonlinear.t[-1])})


def write_verify_report(v, folder, protect=(), cautions=()) -> list:
    """Write ``verify.html``, ``verify.json`` and ``verify.png`` into a folder.

    Parameters
    ----------
    v : Verification
        The verification.
    folder : path-like
        Destination folder (created).
    protect : sequence of path-like
        Input files never to overwrite.
    cautions : sequence of str
        What the diagnosis behind a learned plant said (see :func:`verify_html`).

    Returns
    -------
    list of Path
    """
    png = png_bytes(v.plot())  # rendered once: the page's image and the file are the same bytes
    return write_page_files(folder, "verify", verify_html(v, png, cautions), v.to_dict(), {"verify.png": png},
                            protect)


def ramp_html(result, fig=None, cautions=()) -> str:
    """Return a ramp optimization as one self-contained HTML page.

    Parameters
    ----------
    result : RampResult
        The optimization (:func:`kilnctl.optimize.optimize_ramp`).
    fig : matplotlib.figure.Figure or bytes, optional
        Its figure, already drawn (or its PNG content).
    cautions : sequence of str
        What the diagnosis behind a learned plant said to read before acting on it
        (:func:`kilnctl.design.learned.diagnosis_cautions`), shown at the top.

    Returns
    -------
    str
    """
    from .optimize.result import OBJECTIVE_WORDS, _ramp_text

    if fig is None:
        from matplotlib.figure import Figure

        fig = result.plot(fig=Figure(figsize=(10, 8.5)))
    s = result.summary()
    prob = result.problem
    head = result.headline()
    head = head[0].upper() + head[1:] + "."
    mpa = lambda v: "-" if v is None else f"{v / 1e6:.1f}"  # noqa: E731
    rows = [("dynamic stress (above the running load)", "MPa", mpa(s["dynamic_stress_predicted_Pa"]),
             mpa(s["dynamic_stress_verified_Pa"]), mpa(s["baseline_dynamic_stress_Pa"])),
            ("peak stress (running load included)", "MPa", mpa(s["peak_stress_predicted_Pa"]),
             mpa(s["peak_stress_verified_Pa"]), mpa(s["baseline_peak_stress_Pa"]))]
    if s["objective"] == "peak":
        rows.reverse()
    tts = s["time_to_speed_s"]
    rows.append((f"time to {100 * prob.speed_fraction:g} % speed", "s", "-",
                 "not reached" if tts is None else f"{tts:.2f}", "-"))
    parts = [f"<h2>The ramp found: {esc(_ramp_text(s['ramp']))}</h2>"
             + table(["quantity", "unit", "predicted (smooth model)", "verified (hybrid plant)",
                      f"baseline ({s['baseline_ramp']:g} rpm/s)"], rows, left=2, selected={0})]
    if s["running_stress_Pa"] is not None:
        parts.append(f"<p>Running load of the burden at its angle: {s['running_stress_Pa'] / 1e6:.1f} MPa. "
                     f"Prediction and verification agree to {abs(s['agreement_pct']):.2f} % "
                     f"(tolerance {s['tolerance_pct']:g} %).</p>")
    parts.append("<h2>Reference, stress and current</h2>"
                 + figure_block(fig, "ramp, stress and current against the baseline"))
    return report_page(
        "Start-up ramp optimization", head, parts,
        warnings=[("Flag", f) for f in result.flags] + [("Diagnosis caution", c) for c in cautions],
        terms=("objective", "ramp"), notes=result.notes,
        settings={"profile": s["profile"], "objective": s["objective"], "t_max [s]": prob.t_max,
                  "horizon [s]": prob.horizon, "robust": "yes" if prob.robust else "no (nominal parameters)",
                  "transcription": s["transcription"],
                  "solver": f"IPOPT {s['solver_status']}, {s['iterations']} iterations"},
        meanings={"objective": OBJECTIVE_WORDS[s["objective"]],
                  "t_max [s]": f"the motor must reach {100 * prob.speed_fraction:g} % of its set point by then",
                  "horizon [s]": "simulated start-up"})


def write_ramp_report(result, folder, protect=(), cautions=()) -> list:
    """Write ``optimize_ramp.html``, ``optimize_ramp.json`` and ``optimize_ramp.png`` into a folder.

    Parameters
    ----------
    result : RampResult
        The optimization.
    folder : path-like
        Destination folder (created).
    protect : sequence of path-like
        Input files never to overwrite.
    cautions : sequence of str
        What the diagnosis behind a learned plant said (see :func:`ramp_html`).

    Returns
    -------
    list of Path
    """
    from matplotlib.figure import Figure

    png = png_bytes(result.plot(fig=Figure(figsize=(10, 8.5))))
    return write_page_files(folder, "optimize_ramp", ramp_html(result, png, cautions), result.summary(),
                            {"optimize_ramp.png": png}, protect)
