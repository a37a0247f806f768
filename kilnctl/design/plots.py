"""Figures of the speed-loop design: root loci, step responses, parameter loci.

The data objects of :mod:`kilnctl.design.locus` and
:class:`kilnctl.design.DesignResult` call these from their ``.plot()``; each
function draws on given axes or on a new figure and returns the figure.
"""

from __future__ import annotations

import math

import numpy as np

from ..figures import COLORS, note_box, save_figure

__all__ = ["plot_root_locus", "plot_step_responses", "plot_parameter_locus", "plot_design", "save_figure"]

#: line style and colour of each load condition
STYLE = {"stick": {"color": "C0", "ls": "-"}, "slip": {"color": "C1", "ls": "--"}}
_REGION = COLORS["region"]
_LIMIT = COLORS["limit"]


def _plt():
    import matplotlib.pyplot as plt
    return plt


# --- design region -------------------------------------------------------------------
def _draw_region(ax, req, extent: float, *, legend: bool = True) -> None:
    """Shade the damping sector and the dominant-pole region; draw rays, line and arc."""
    theta = math.acos(req.zeta_min)
    far = 10 * extent
    # zeta >= zeta_min: the sector about the negative real axis
    ax.fill([0, -far, -far], [0, far * math.tan(theta), -far * math.tan(theta)] if theta < math.pi / 2 - 1e-9
            else [0, far, -far], color=_REGION, alpha=0.07, lw=0,
            label=f"$\\zeta \\geq {req.zeta_min:g}$ (all poles)" if legend else None)
    for sign in (1, -1):
        ax.plot([0, -far * math.cos(theta)], [0, sign * far * math.sin(theta)], color=_REGION, lw=0.9, ls="--",
                label=f"$\\zeta = {req.zeta_min:g}$" if legend and sign == 1 else None)
    # dominant-pole region: sector, sigma >= 4/Ts, |s| <= wn_max
    sig = req.sigma_min
    wn = req.wn_max
    th = np.linspace(-theta, theta, 200)
    inner = sig / np.cos(th)
    ok = inner <= wn
    if np.any(ok):
        th = th[ok]
        outer_pts = -wn * np.exp(1j * th)
        inner_pts = -(sig / np.cos(th[::-1])) * np.exp(1j * th[::-1])
        pts = np.concatenate([outer_pts, inner_pts])
        ax.fill(pts.real, pts.imag, color=_REGION, alpha=0.35, lw=0,
                label="dominant-pole region" if legend else None)
    ax.axvline(-sig, color=_LIMIT, lw=0.9, ls="-.",
               label=f"$\\sigma = -4/T_s = {-sig:.2f}$" if legend else None)
    arc = np.linspace(math.pi / 2, 3 * math.pi / 2, 200)
    ax.plot(wn * np.cos(arc), wn * np.sin(arc), color=_LIMIT, lw=0.9, ls=":",
            label=f"$\\omega_n = {wn:.2f}$ rad/s" if legend else None)


def _fmt_s(s: complex) -> str:
    if abs(s.imag) < 1e-6 * max(1.0, abs(s)):
        return f"{s.real:.3g}"
    return f"{s.real:.3g} {'+' if s.imag >= 0 else '-'} {abs(s.imag):.3g}j"


# --- root locus over the gain ---------------------------------------------------------
def plot_root_locus(data, axes=None):
    """Draw a :class:`RootLocusData`: full view and a zoom on the dominant region.

    Parameters
    ----------
    data : RootLocusData
        The loci.
    axes : pair of matplotlib Axes, optional
        ``(full, zoom)``; a new 1 x 2 figure when omitted.

    Returns
    -------
    matplotlib.figure.Figure
        In an interactive backend, clicking near a locus marks the nearest
        locus point and shows its gain scaling and gains.
    """
    plt = _plt()
    own = axes is None
    if own:
        fig, axes = plt.subplots(1, 2, figsize=(14, 7.5), gridspec_kw={"width_ratios": [1.1, 1]})
    ax_full, ax_zoom = axes
    fig = ax_full.figure
    req = data.requirements
    g = data.gains

    pts = np.concatenate([np.concatenate([b.open_loop_poles, b.open_loop_zeros, b.chosen])
                          for b in data.branches.values()])
    radius = max(float(np.abs(pts).max()), 1.0)
    full_x = (-1.6 * radius, 0.3 * radius)
    full_y = (-1.05 * radius, 1.05 * radius)
    dom = max(abs(b.chosen[np.argmax(b.chosen.real)]) for b in data.branches.values())
    zoom_r = 1.7 * max(dom, req.wn_max if req else 0.0, 1e-3)
    zoom_x = (-1.45 * zoom_r, 0.35 * zoom_r)
    zoom_y = (-0.9 * zoom_r, 0.9 * zoom_r)

    for ax, (xl, yl), legend in ((ax_full, (full_x, full_y), True), (ax_zoom, (zoom_x, zoom_y), False)):
        extent = max(abs(xl[0]), abs(yl[1]))
        if req is not None:
            _draw_region(ax, req, extent, legend=legend)
        ax.axhline(0, color="0.4", lw=0.6)
        ax.axvline(0, color="0.4", lw=0.6)
        for cond, br in data.branches.items():
            st = STYLE.get(cond, {})
            for j in range(br.loci.shape[1]):
                ax.plot(br.loci[:, j].real, br.loci[:, j].imag, color=st.get("color"), ls=st.get("ls"), lw=1.6,
                        label=f"locus, {cond} (J = {br.J:.2f} kg·m²)" if legend and j == 0 else None)
            ax.plot(br.open_loop_poles.real, br.open_loop_poles.imag, "x", color=st.get("color"), ms=10, mew=2,
                    label=f"open-loop poles, {cond}" if legend else None)
            ax.plot(br.chosen.real, br.chosen.imag, "s", color=st.get("color"), ms=8, mec="k",
                    label=f"closed-loop poles, {cond} ($\\kappa$ = 1)" if legend else None)
        zeros = next(iter(data.branches.values())).open_loop_zeros
        ax.plot(zeros.real, zeros.imag, "o", mfc="none", mec="k", ms=10, mew=1.8,
                label="PID zeros" if legend else None)
        ax.set_xlim(*xl)
        ax.set_ylim(*yl)
        ax.set_aspect("equal", adjustable="box")
        ax.grid(True, alpha=0.3)
        ax.set_xlabel("Re s [1/s]")
        ax.set_ylabel("Im s [rad/s]")

    # label the chosen poles with the gain (stick, or the first condition)
    br = data.branches.get("stick", next(iter(data.branches.values())))
    for p in br.chosen:
        if p.imag < -1e-9:
            continue
        for ax, (xl, yl) in ((ax_full, (full_x, full_y)), (ax_zoom, (zoom_x, zoom_y))):
            if xl[0] < p.real < xl[1] and yl[0] < p.imag < yl[1]:
                # complex poles: label up and to the left; real poles: below and to the left
                offset = (-95, 28) if p.imag > 1e-9 else (-85, -70)
                ax.annotate(f"s = {_fmt_s(p)}\n$\\kappa$ = 1: $k_D$ = {g.k_D:.4g} V·s/rpm",
                            xy=(p.real, p.imag), xytext=offset, textcoords="offset points", ha="center",
                            fontsize=8.5,
                            bbox={"boxstyle": "round", "fc": "white", "ec": "0.6", "alpha": 0.9},
                            arrowprops={"arrowstyle": "-", "color": "0.5"})
    ax_full.set_title(f"Root locus of $1 + \\kappa K C(s) G(s)$; $\\kappa$ = 1: $k_p$ = {g.k_p:.4g} V/rpm, "
                      f"$k_I$ = {g.k_I:.4g} V/(rpm·s), $k_D$ = {g.k_D:.4g} V·s/rpm", fontsize=10)
    ax_zoom.set_title("zoom: dominant pole and design region", fontsize=10)
    if req is not None:
        note_box(ax_zoom, _margin_text(data), loc="lower left")
    handles, labels = ax_full.get_legend_handles_labels()
    ax_zoom.legend(handles, labels, loc="upper left", bbox_to_anchor=(1.02, 1.0), fontsize=8.5, framealpha=0.95,
                   borderaxespad=0.0)
    if own:
        fig.tight_layout()
    _connect_click(fig, data, (ax_full, ax_zoom))
    return fig


def _margin_text(data) -> str:
    """The design's margins to the damping and frequency limits, per condition."""
    req = data.requirements
    lines = ["margins to the requirements:"]
    for cond, br in data.branches.items():
        p = br.chosen
        zeta = float(np.min(-p.real / np.maximum(np.abs(p), 1e-300)))
        dom = p[np.argmax(p.real)]
        wn = float(abs(dom))
        dz = zeta - req.zeta_min
        dw = req.wn_max - wn
        dz = 0.0 if abs(dz) < 5e-4 else dz  # no "-0.000"
        dw = 0.0 if abs(dw) < 5e-3 else dw
        on = [n for n, d in (("$\\zeta$", dz), ("$\\omega_n$", dw)) if d == 0.0]
        lines.append(f"{cond}: min $\\zeta$ {zeta:.3f} (limit {req.zeta_min:g}, margin {dz:.3f})\n"
                     f"   dominant $\\omega_n$ {wn:.2f} rad/s (limit {req.wn_max:.2f}, margin {dw:.2f})"
                     + (f"\n   on the {' and '.join(on)} limit{'s' if len(on) > 1 else ''}" if on else ""))
    return "\n".join(lines)


def click_text(data, s0: complex) -> str:
    """Return the text shown when the locus plot is clicked at ``s0``.

    Parameters
    ----------
    data : RootLocusData
        The loci.
    s0 : complex
        Clicked point [rad/s].

    Returns
    -------
    str
        Condition, nearest locus point, gain scaling ``kappa`` and the gains there.
    """
    cond, s, kappa = data.nearest(s0)
    g = data.gains
    z = -s.real / abs(s) if abs(s) > 0 else 0.0
    return (f"{cond}: s = {_fmt_s(s)}, zeta = {z:.3f}\nkappa = {kappa:.4g}: k_p = {kappa * g.k_p:.4g}, "
            f"k_I = {kappa * g.k_I:.4g}, k_D = {kappa * g.k_D:.4g}")


def _connect_click(fig, data, axes) -> None:
    marks = {}

    def on_click(event):
        if event.inaxes not in axes or event.xdata is None:
            return
        text = click_text(data, complex(event.xdata, event.ydata))
        _, s, _ = data.nearest(complex(event.xdata, event.ydata))
        ax = event.inaxes
        for artist in marks.pop(ax, ()):
            artist.remove()
        dot, = ax.plot([s.real], [s.imag], "r*", ms=12)
        note = ax.text(0.02, 0.02, text, transform=ax.transAxes, fontsize=8, va="bottom",
                       bbox={"fc": "lightyellow", "ec": "0.5"})
        marks[ax] = (dot, note)
        fig.canvas.draw_idle()

    fig._kilnctl_click = on_click  # keep a strong reference for the callback registry
    fig.canvas.mpl_connect("button_press_event", on_click)
    manager = getattr(fig.canvas, "manager", None)
    if manager is not None:  # the hint shows in an interactive window's title, never in a saved file
        manager.set_window_title("kilnctl root locus: click a locus for its gain")


# --- step responses ------------------------------------------------------------------
def plot_step_responses(data, axes=None):
    """Draw a :class:`StepResponseData`: speed and current after a reference step.

    Parameters
    ----------
    data : StepResponseData
        The responses.
    axes : pair of matplotlib Axes, optional
        ``(speed, current)``; a new 1 x 2 figure when omitted.

    Returns
    -------
    matplotlib.figure.Figure
    """
    plt = _plt()
    if axes is None:
        fig, axes = plt.subplots(1, 2, figsize=(13, 4.8))
    ax_w, ax_i = axes
    fig = ax_w.figure
    t = data.time
    req = data.requirements
    ax_w.axhspan(0.98, 1.02, color=_REGION, alpha=0.15, lw=0, label="±2 % settling band")
    if req is not None:
        ax_w.axhline(1 + req.overshoot_max / 100, color=_LIMIT, lw=1, ls="--",
                     label=f"overshoot limit {req.overshoot_max:g} %")
        ax_w.axvline(req.settling_time_max, color=_LIMIT, lw=1, ls="-.",
                     label=f"settling-time limit {req.settling_time_max:g} s")
    for cond, y in data.speed.items():
        st = STYLE.get(cond, {})
        r = data.reports[cond]
        lab = cond
        if r.settling_time is not None:
            lab += (f": $T_s$ = {r.settling_time:.2f} s, OS = {r.overshoot:.2f} %, $T_r$ = {r.rise_time:.2f} s, "
                    f"dip {r.dip:.0f} %")
        ax_w.plot(t, y, color=st.get("color"), ls=st.get("ls"), lw=1.8, label=lab)
        if r.settling_time is not None:
            ax_w.plot([r.settling_time], [np.interp(r.settling_time, t, y)], "o", color=st.get("color"), mec="k")
        ax_i.plot(t, data.current[cond], color=st.get("color"), ls=st.get("ls"), lw=1.8,
                  label=f"{cond}: jump $k_D/L_a$ = {r.current_jump:.3g} A/rpm")
    ax_w.set_xlabel("time [s]")
    ax_w.set_ylabel("motor speed $K\\omega_m$ per rpm of reference step [-]")
    ax_w.set_title("Speed after a step of the speed reference $e_v$", fontsize=10)
    ymax = max(1.15, max(float(np.max(y)) for y in data.speed.values()) * 1.05)
    ax_w.set_ylim(0, ymax)
    ax_w.set_xlim(0, t[-1])
    ax_w.legend(loc="lower right", fontsize=8)
    ax_w.grid(True, alpha=0.3)
    ax_i.axhline(0, color="0.4", lw=0.6)
    ax_i.set_xlabel("time [s]")
    ax_i.set_ylabel("armature current $i_a$ per rpm of reference step [A/rpm]")
    ax_i.set_title("Current after the same step (derivative through $L_a$)", fontsize=10)
    ax_i.set_xlim(0, t[-1])
    ax_i.legend(loc="upper right", fontsize=8)
    ax_i.grid(True, alpha=0.3)
    return fig


# --- parameter locus -----------------------------------------------------------------
def _value_scale(data):
    if data.parameter == "m_v":
        return 1e-3, "burden mass $m_v$ [t]"
    if data.parameter == "J_v":
        return 1e-6, "burden inertia $J_v$ [$10^6$ kg·m²]"
    return 1.0, f"{data.parameter} [{data.unit}]"


def plot_parameter_locus(data, axes=None):
    """Draw a :class:`ParameterLocusData`: the electromechanical pole, the dominant pole, the pair's damping.

    Parameters
    ----------
    data : ParameterLocusData
        Poles over the parameter.
    axes : sequence of three matplotlib Axes, optional
        ``(s-plane near the upper electromechanical pole, dominant pole vs
        parameter, pair damping vs parameter)``; a new figure when omitted.

    Returns
    -------
    matplotlib.figure.Figure
    """
    plt = _plt()
    if axes is None:
        fig, axes = plt.subplots(1, 3, figsize=(17, 5.2), gridspec_kw={"width_ratios": [1.1, 1, 1]})
    ax_s, ax_d, ax_p = axes
    fig = ax_s.figure
    scale, xlabel = _value_scale(data)
    name = xlabel.split(" [")[0]
    x = data.values * scale
    req = data.requirements
    cmap = plt.get_cmap("viridis")
    norm = plt.Normalize(x.min(), x.max())
    rows = np.arange(len(x))
    sc = None
    upper_all = []
    for cond, P in data.poles.items():
        st = STYLE.get(cond, {})
        upper = P[rows, np.argmax(P.imag, axis=1)]
        upper_all.append(upper)
        moving = np.ptp(np.abs(upper)) > 1e-9 * np.abs(upper).max()
        if moving:
            ax_s.plot(upper.real, upper.imag, color=st.get("color"), ls=st.get("ls"), lw=1, alpha=0.7)
            sc = ax_s.scatter(upper.real, upper.imag, c=x, cmap=cmap, norm=norm, s=22, zorder=3,
                              edgecolors=st.get("color"), linewidths=0.6, label=f"{cond}")
        else:
            ax_s.plot(upper[:1].real, upper[:1].imag, "D", color=st.get("color"), mec="k", ms=8, zorder=4,
                      label=f"{cond}: does not move (burden slides, eq. 15)")
        J = data.inertias[cond]
        jtext = (f"J = {J.min():.2f} to {J.max():.2f} kg·m²" if np.ptp(J) > 1e-9 * J.max()
                 else f"J = {J[0]:.2f} kg·m² (fixed)")
        ax_d.plot(x, data.dominant_wn(cond), color=st.get("color"), ls=st.get("ls"), lw=2, label=f"{cond}: {jtext}")
        ax_p.plot(x, data.pair_zeta(cond), color=st.get("color"), ls=st.get("ls"), lw=2, label=cond)
    if sc is not None:
        fig.colorbar(sc, ax=ax_s, label=xlabel, shrink=0.9)
    up = np.concatenate(upper_all)
    pad = max(0.15 * max(np.ptp(up.real), np.ptp(up.imag)), 0.02 * np.abs(up).max())
    ax_s.set_xlim(up.real.min() - pad, up.real.max() + pad)
    ax_s.set_ylim(up.imag.min() - pad, up.imag.max() + pad)
    if req is not None:
        theta = math.acos(req.zeta_min)
        r = np.linspace(0, 2 * np.abs(up).max(), 2)
        ax_s.plot(-r * math.cos(theta), r * math.sin(theta), color=_REGION, ls="--", lw=1.2,
                  label=f"$\\zeta = {req.zeta_min:g}$")
    ax_s.set_aspect("equal", adjustable="box")
    ax_s.set_xlabel("Re s [1/s]")
    ax_s.set_ylabel("Im s [rad/s]")
    ax_s.set_title(f"Electromechanical pole (upper) over {name}", fontsize=10)
    ax_s.grid(True, alpha=0.3)
    ax_s.legend(loc="best", fontsize=8)
    for ax in (ax_d, ax_p):
        ax.axvline(data.nominal * scale, color="0.3", lw=1, ls=":", label="nominal (Table 1)")
        ax.set_xlabel(xlabel)
        ax.grid(True, alpha=0.3)
    if req is not None:
        ax_d.axhline(req.wn_max, color=_LIMIT, lw=1, ls="--", label=f"$\\omega_{{n,max}}$ = {req.wn_max:.2f} rad/s")
        ax_p.axhline(req.zeta_min, color=_LIMIT, lw=1, ls="--", label=f"$\\zeta_{{min}}$ = {req.zeta_min:g}")
    ax_d.set_ylabel("dominant pole $\\omega_n$ [rad/s]")
    ax_d.set_title("Dominant (slowest) pole", fontsize=10)
    # from zero: the dominant pole hardly moves, and the axis must not make a 0.2 % change look large
    wn_all = np.concatenate([data.dominant_wn(c) for c in data.poles])
    ax_d.set_ylim(0, 1.3 * max(float(wn_all.max()), req.wn_max if req is not None else 0.0))
    spread = 100 * 0.5 * np.ptp(wn_all) / float(np.mean(wn_all))
    note_box(ax_d, f"$\\omega_n$ = {wn_all.min():.2f} to {wn_all.max():.2f} rad/s over this range "
                   f"($\\pm${spread:.1f} %)", loc="upper left")
    ax_d.legend(fontsize=8, loc="lower right")
    ax_p.set_ylabel("damping ratio of the electromechanical pair [-]")
    ax_p.set_title("Damping of the electromechanical pair", fontsize=10)
    # damping: zoomed (the question is where it crosses the limit), never closer than +-0.03 about the limit
    z_all = np.concatenate([data.pair_zeta(c) for c in data.poles])
    ref = req.zeta_min if req is not None else float(np.mean(z_all))
    half = max(0.03, 1.3 * float(np.max(np.abs(z_all - ref))))
    ax_p.set_ylim(ref - half, ref + half)
    if req is not None:
        ax_p.axhspan(ref - half, req.zeta_min, color=COLORS["violation"], alpha=0.08, lw=0,
                     label=f"$\\zeta < {req.zeta_min:g}$: requirement not met")
        for cond in data.poles:
            bad = data.pair_zeta(cond) < req.zeta_min
            if bad.any():
                lo_x, hi_x = x[bad].min(), x[bad].max()
                unit = xlabel.split("[")[-1].rstrip("]")
                ax_p.annotate(f"{cond}: below {req.zeta_min:g}\nfor {name} {lo_x:.0f} to {hi_x:.0f} {unit}",
                              xy=(x[bad][len(x[bad]) // 2], data.pair_zeta(cond)[bad][len(x[bad]) // 2]),
                              xytext=(0, -38), textcoords="offset points", ha="center", fontsize=8,
                              color=COLORS["violation"], arrowprops={"arrowstyle": "->", "color": COLORS["violation"]})
    ax_p.legend(fontsize=8, loc="upper right")
    fig.suptitle(f"Closed-loop poles over {name} at fixed gains ({data.gains})", fontsize=11)
    fig.tight_layout()
    return fig


# --- the design overview -----------------------------------------------------------------
def plot_design(result):
    """Draw a :class:`DesignResult`: root locus (full, zoom) above the step responses.

    Parameters
    ----------
    result : DesignResult
        The design.

    Returns
    -------
    matplotlib.figure.Figure
    """
    plt = _plt()
    fig = plt.figure(figsize=(14, 11))
    gs = fig.add_gridspec(2, 2, height_ratios=[1.25, 1], width_ratios=[1.25, 1])
    locus_axes = (fig.add_subplot(gs[0, 0]), fig.add_subplot(gs[0, 1]))
    step_axes = (fig.add_subplot(gs[1, 0]), fig.add_subplot(gs[1, 1]))
    result.locus().plot(locus_axes)
    result.step_responses().plot(step_axes)
    status = "meets all requirements" if result.meets_requirements else "DOES NOT MEET: " + "; ".join(result.unmet)
    fig.suptitle(f"Speed-loop PID by root locus: {result.gains}\n{status}", fontsize=11)
    fig.tight_layout()
    return fig
