"""Compare a model with a measured record: fit %, residual tests, and where it fails.

>>> from kilnctl.measure import compare, read_csv            # doctest: +SKIP
>>> c = compare(read_csv("rec.csv"), params)                  # doctest: +SKIP
>>> c.fit                                                     # doctest: +SKIP
{'current_A': 62.1, 'speed_rpm': 99.2}
>>> c.failing[0]["text"]                                      # doctest: +SKIP
'0.0-6.8 s (ramp): model low by 36 A on average, by 61 A at 1.52 s (measured 316 A, model 255 A)'
"""

from __future__ import annotations

import math
import textwrap
from dataclasses import dataclass, field

import numpy as np

from ..params import Parameters
from ..simulate import resolve_gains
from .io import Experiment, Measurement
from .clipping import residual as clipped_residual
from .runner import CHANNELS, ModelRun, kiln_angle, run_model
from .stats import autocorr, crosscorr, failing_intervals, fit_percent, residual_spectrum, robust_sigma

__all__ = ["Comparison", "ChannelComparison", "compare", "compare_run", "level_caution"]

#: default largest correlation lag [s]
MAX_LAG_S = 5.0

#: longest line of a model's name in the legends of :meth:`Comparison.plot` [characters]
LEGEND_CHARS = 34


#: ratios of the model's to the record's signal spread that, with a fit below 0 %, are read as a unit or setup
#: mismatch (:func:`level_caution`): the model spanning more than 4 times the record (a
#: current in per cent of a rating above 400 A, a speed in rad/s read as rpm: 9.5, at the kiln shell: the gear
#: ratio) or less than a tenth of it.  Effects add variation to a record far more easily than they take it
#: away: the hard set's hunting records span 3.7 times the setup's model (fit 5 %)
SPREAD_RATIO = (0.1, 4.0)


def level_caution(name: str, unit: str, measured, model) -> str | None:
    """A caution when a model explains less of a channel than the record's own mean (fit below 0 %) and the
    ratio of the two signals' spreads lies outside :data:`SPREAD_RATIO`; None otherwise.

    That is a column in other units (a current in per cent of its rating, a speed at the kiln shell or in
    rad/s read as rpm: factors of 10 to 100) or a setup for another drive, which no effect of the catalogue
    explains.  The spread is the range of the middle 98 % of the samples: a few impacts' spikes do not set it.

    Parameters
    ----------
    name, unit : str
        Column name and unit.
    measured, model : array_like
        The record's and the model's signal at the compared samples [unit].

    Returns
    -------
    str or None
    """
    measured, model = np.asarray(measured, float), np.asarray(model, float)
    fit = fit_percent(measured, model)
    if not fit < 0.0:
        return None

    def spread(x):
        x = x[np.isfinite(x)]
        return float(np.percentile(x, 99) - np.percentile(x, 1)) if x.size else math.nan

    rec, mod = spread(measured), spread(model)
    ratio = mod / rec if rec > 0 else math.inf
    if SPREAD_RATIO[0] <= ratio <= SPREAD_RATIO[1]:
        return None
    size = (f"the model's signal spans {ratio:.3g} times the record's (1 % to 99 % of the samples)"
            if math.isfinite(ratio) else "the record's signal does not vary")
    return (f"{name}: fit {fit:.0f} %, less than the record's own mean explains (record "
            f"{np.nanmean(measured):.4g} {unit} on average, model {np.nanmean(model):.4g} {unit}), and {size}. "
            f"Check the column's unit (A and rpm at the motor; a current in per cent of the rating, a speed at "
            f"the kiln shell or in rad/s read as rpm) and that the setup is this drive's (ratings, gear ratio, "
            f"reference): no effect explains a difference of this size.")


@dataclass
class ChannelComparison:
    """Measured and model signal of one channel and the tests of their residual.

    Attributes
    ----------
    name, unit : str
        Column name and unit.
    measured, model, residual : ndarray
        Signals at the compared times; residual = measured - model, 0 on
        samples the logger clipped or in a spike (:attr:`Measurement.kept
        <kilnctl.measure.io.Measurement.kept>`: no measurement there).
    fit : float
        Fit % (MATLAB ``compare``), over the samples kept, as are
        ``bias``, ``rms`` and ``sigma``.
    bias : float
        Mean residual [unit] (positive: model low).
    rms : float
        Root-mean-square residual [unit].
    sigma : float
        Robust residual scale 1.4826 median|e| [unit].
    whiteness : dict
        :func:`~kilnctl.measure.stats.autocorr` result (lags in steps of ``dt``).
    xcorr : dict of str to dict
        Cross-correlation with the input (``speed_ref_rpm``) and the other
        measured channel, :func:`~kilnctl.measure.stats.crosscorr` results.
    spectrum : dict
        :func:`~kilnctl.measure.stats.residual_spectrum` result.
    failing : list of dict
        Intervals with |residual| > 3 sigma: ``t_start``, ``t_end`` [s],
        ``phase``, ``measured_peak`` and ``model_peak`` (the measured
        signal's extreme in the interval and the model's of the same sign),
        ``mean_residual``, the largest miss (``t_worst`` [s],
        ``measured_worst``, ``model_worst``), and ``text``, which gives the
        mean and the largest miss.
    """

    name: str
    unit: str
    measured: np.ndarray
    model: np.ndarray
    residual: np.ndarray
    fit: float
    bias: float
    rms: float
    sigma: float
    whiteness: dict
    xcorr: dict
    spectrum: dict
    failing: list

    @property
    def level_caution(self) -> str | None:
        """:func:`level_caution` of this channel."""
        return level_caution(self.name, self.unit, self.measured, self.model)

    def to_dict(self) -> dict:
        """Return the statistics (not the signals) as a JSON-ready dictionary."""
        return {
            "fit_percent": _num(self.fit), "bias": self.bias, "rms": self.rms, "sigma_robust": self.sigma,
            "level_caution": self.level_caution,
            "unit": self.unit,
            "whiteness": {"n_lags": int(self.whiteness["lags"][-1]), "band": self.whiteness["band"],
                          "n_outside": self.whiteness["n_outside"],
                          "fraction_outside": self.whiteness["fraction_outside"]},
            "xcorr": {k: {"band": v["band"], "n_outside": v["n_outside"], "fraction_outside": v["fraction_outside"],
                          "max_abs": float(np.max(np.abs(v["r"])))} for k, v in self.xcorr.items()},
            "spectrum": {"dominant_hz": self.spectrum["dominant_hz"], "peak_ratio": _num(self.spectrum["peak_ratio"]),
                         "narrowband_hz": self.spectrum["narrowband_hz"],
                         "narrowband_ratio": _num(self.spectrum["narrowband_ratio"])},
            "failing": [{k: v for k, v in f.items()} for f in self.failing],
        }


def _num(v):
    return None if v is None or not math.isfinite(v) else float(v)


@dataclass
class Comparison:
    """A model compared with a measured record.

    Attributes
    ----------
    t : ndarray
        Compared times [s] (record time, from the start-up on).
    channels : dict of str to ChannelComparison
        ``current_A`` and ``speed_rpm``.
    experiment : Experiment
        Start time and ramp that were simulated.
    model : str
        ``macro`` or ``micro``.
    effects : tuple of str
        Effects added to the model.
    params : Parameters
        Parameters simulated.
    phases : list of dict
        Phases of the start-up in the model (``name``, ``t_start``, ``t_end``
        [s]): ramp, burden stuck, burden slipping.
    dt : float
        Median sample step [s].
    source : str
        The record's file.
    """

    t: np.ndarray
    channels: dict
    experiment: Experiment
    model: str
    effects: tuple
    params: Parameters
    phases: list
    dt: float
    source: str
    extra: dict = field(default_factory=dict)

    @property
    def fit(self) -> dict:
        """Fit % per channel (MATLAB ``compare``)."""
        return {k: c.fit for k, c in self.channels.items()}

    @property
    def cautions(self) -> list:
        """The channels' :attr:`ChannelComparison.level_caution` texts (a fit below 0 %: units or setup)."""
        return [t for t in (c.level_caution for c in self.channels.values()) if t is not None]

    @property
    def failing(self) -> list:
        """Failing intervals of every channel, in time order (dicts with ``channel``)."""
        out = [dict(f, channel=k) for k, c in self.channels.items() for f in c.failing]
        return sorted(out, key=lambda f: f["t_start"])

    def to_dict(self) -> dict:
        """Return the comparison as a JSON-ready dictionary.

        Returns
        -------
        dict
            ``source``, ``model``, ``effects``, ``experiment``, ``fit_percent``
            per channel, ``channels`` (statistics per channel), ``failing``
            (all intervals in time order, with their text), ``cautions``
            (:attr:`cautions`), ``phases``.
        """
        return {
            "source": self.source, "model": self.model, "effects": list(self.effects),
            "experiment": self.experiment.to_dict(),
            "fit_percent": {k: _num(v) for k, v in self.fit.items()},
            "channels": {k: c.to_dict() for k, c in self.channels.items()},
            "failing": self.failing,
            "cautions": self.cautions,
            "phases": self.phases,
        }

    def summary_lines(self) -> list[str]:
        """Return a short human-readable summary, one line per item."""
        lines = [f"{self.source}: {self.model} model" + (f" + {', '.join(self.effects)}" if self.effects else "")]
        for k, c in self.channels.items():
            w = c.whiteness
            lines.append(f"  {k:<10} fit {c.fit:6.1f} %   rms {c.rms:.4g} {c.unit}   bias {c.bias:+.3g} {c.unit}   "
                         f"residual autocorr outside 99 % band at {w['n_outside']}/{len(w['lags']) - 1} lags   "
                         f"dominant {c.spectrum['dominant_hz']:.2f} Hz")
        fails = self.failing
        if fails:
            lines.append("  where it fails (|residual| > 3 sigma):")
            lines += [f"    {f['channel']}: {f['text']}" for f in fails]
        else:
            lines.append("  no interval with |residual| > 3 sigma")
        lines += [f"  caution: {text}" for text in self.cautions]
        for note in self.experiment.notes:
            lines.append(f"  note: {note}")
        return lines

    def plot(self, fig=None, compare_with: "Comparison | None" = None, labels=("model", "extended model")):
        """Draw measured vs model, residuals, autocorrelation and spectrum per channel.

        Failing intervals are shaded.  With ``compare_with`` (e.g. the model
        after diagnosis) its signal and residual are drawn too.

        Parameters
        ----------
        fig : matplotlib.figure.Figure, optional
            Figure to draw into (a new one by default).
        compare_with : Comparison, optional
            A second comparison on the same record.
        labels : tuple of str
            Legend names of this model and of ``compare_with``.

        Returns
        -------
        matplotlib.figure.Figure
        """
        from matplotlib.figure import Figure

        from ..figures import COLORS, finish, record_name

        if fig is None:
            fig = Figure(figsize=(13, 3.3 * len(self.channels) + 0.9))
        axes = fig.subplots(len(self.channels), 4, squeeze=False,
                            gridspec_kw={"width_ratios": [3, 3, 2, 2]})
        c_mod, c_ext = COLORS["model"], COLORS["final"]
        names = {"current_A": "current", "speed_rpm": "speed"}
        # a model's name in the legends wrapped to the panels' width (a final structure of three effects in
        # one line ran over the neighbouring panels); the narrow correlation and spectrum panels name each model
        # by what comes before a colon ("final: base + ..." -> "final"), its colour tells the rest
        short = tuple(lab.split(":")[0] for lab in labels)
        labels = tuple("\n".join(textwrap.wrap(lab, LEGEND_CHARS)) for lab in labels)
        for row, (k, c) in enumerate(self.channels.items()):
            a0, a1, a2, a3 = axes[row]
            q = names.get(k, k)
            a0.plot(self.t, c.measured, color=COLORS["measured"], lw=0.8, label="measured")
            a0.plot(self.t, c.model, color=c_mod, lw=1.2, label=labels[0])
            a1.plot(self.t, c.residual, color=c_mod, lw=0.8, label=labels[0])
            if compare_with is not None:
                o = compare_with.channels[k]
                a0.plot(compare_with.t, o.model, color=c_ext, lw=1.2, ls="--", label=labels[1])
                a1.plot(compare_with.t, o.residual, color=c_ext, lw=0.8, alpha=0.8, label=labels[1])
            for n, f in enumerate(c.failing):
                for ax in (a0, a1):
                    ax.axvspan(f["t_start"], f["t_end"], color=COLORS["violation"], alpha=0.12, lw=0,
                               label=f"|residual| > 3$\\sigma$ ({labels[0]})" if n == 0 and ax is a1 else None)
            a1.axhline(3 * c.sigma, color="gray", ls=":", lw=0.9, label=f"$\\pm 3\\sigma$ = {3 * c.sigma:.3g} {c.unit}")
            a1.axhline(-3 * c.sigma, color="gray", ls=":", lw=0.9)
            a0.set_ylabel(f"{q} [{c.unit}]")
            a1.set_ylabel(f"residual [{c.unit}]")
            a0.set_title(f"{q}: fit {c.fit:.1f} %" + (f" -> {compare_with.channels[k].fit:.1f} %"
                                                        if compare_with is not None else ""), fontsize=9)
            a1.set_title(f"{q} residual (measured - model)", fontsize=9)
            w = c.whiteness
            lag_s = w["lags"] * self.dt
            a2.bar(lag_s[1:], w["r"][1:], width=self.dt, color=c_mod, label=short[0])
            if compare_with is not None:
                w2 = compare_with.channels[k].whiteness
                a2.plot(w2["lags"][1:] * compare_with.dt, w2["r"][1:], color=c_ext, lw=1.0, label=short[1])
            a2.axhspan(-w["band"], w["band"], color="gray", alpha=0.2, label="99 % band of white noise")
            a2.set_title(f"residual autocorrelation ({w['n_outside']} lags out)", fontsize=9)
            a2.set_ylabel("autocorrelation [-]")
            s = c.spectrum
            a3.semilogy(s["f"][1:], s["psd"][1:], color=c_mod, label=short[0])
            if compare_with is not None:
                s2 = compare_with.channels[k].spectrum
                a3.semilogy(s2["f"][1:], s2["psd"][1:], color=c_ext, ls="--", label=short[1])
            a3.axvline(s["dominant_hz"], color="gray", ls=":", label=f"peak {s['dominant_hz']:.2f} Hz")
            a3.set_title("residual spectrum", fontsize=9)
            a3.set_ylabel(f"PSD [{c.unit}$^2$/Hz]")
            for n, ax in enumerate((a0, a1)):
                for m, ph in enumerate(self.phases[1:]):
                    ax.axvline(ph["t_start"], color="gray", lw=0.6, ls="--",
                               label="phase boundary" if m == 0 and n == 0 and row == 0 else None)
                ax.grid(True, alpha=0.3)
            if row == 0:
                a0.legend(fontsize=7.5, loc="best")
                a1.legend(fontsize=7.5, loc="best")
                # head room above the data for the legends (they covered the autocorrelation's bars)
                lo, hi = a2.get_ylim()
                a2.set_ylim(lo, hi + 0.6 * (hi - lo))
                lo, hi = a3.get_ylim()
                a3.set_ylim(lo, hi * (hi / lo) ** 0.5 if lo > 0 else hi)
                a2.legend(fontsize=7.5, loc="upper right")
                a3.legend(fontsize=7.5, loc="upper right")
        for row in axes:
            for ax, lab in zip(row, ("time [s]", "time [s]", "lag [s]", "frequency [Hz]")):
                ax.set_xlabel(lab, fontsize=8.5)
        phases = ", ".join(f"{ph['name']} from {ph['t_start']:.1f} s" for ph in self.phases)
        caption = (f"Dashed vertical lines: start-up phases ({phases}). Red shading: intervals where the "
                   f"{labels[0]}'s |residual| exceeds 3 sigma (robust sigma of its residual). A white residual "
                   "(nothing left to explain) keeps its autocorrelation inside the grey band and has a flat "
                   "spectrum.")
        return finish(fig, f"{record_name(self.source)}: measured vs {self.model} model"
                      + (f" + {', '.join(self.effects)}" if self.effects else ""), caption)


def _phases(run: ModelRun, t0: float, t_last: float) -> list:
    """Start-up phases from the model's events (record time)."""
    marks = [("ramp", t0)]
    ramp_end = next((e.t for e in run.events if e.kind == "ramp_end"), None)
    brk = next((e.t for e in run.events if e.kind == "breakaway"), None)
    if ramp_end is not None:
        marks.append(("hold, burden stuck" if brk is None or brk > ramp_end else "hold", t0 + float(ramp_end)))
    if brk is not None:
        marks.append(("burden slipping", t0 + float(brk)))
    marks.sort(key=lambda m: m[1])
    out = []
    for i, (name, ts) in enumerate(marks):
        te = marks[i + 1][1] if i + 1 < len(marks) else t_last
        if te > ts:
            out.append({"name": name, "t_start": float(ts), "t_end": float(te)})
    return out


def _phase_of(phases, ta, tb) -> str:
    names = [p["name"] for p in phases if p["t_end"] > ta and p["t_start"] < tb]
    return " / ".join(dict.fromkeys(names)) or "-"


def _describe(t, y, yhat, e, a, b, unit, phases) -> dict:
    sl = slice(a, b + 1)
    ym, yh = y[sl], yhat[sl]
    # the extreme of the measured signal in the interval, and the model's extreme of the same sign
    km = int(np.argmax(np.abs(ym)))
    mp = float(ym[km])
    hp = float(yh.max() if mp >= 0 else yh.min())
    # the largest miss, which the text gives: the measured peak of a dip is its edge, not its depth
    kw = a + int(np.argmax(np.abs(e[sl])))
    mean = float(np.mean(e[sl]))
    ta, tb = float(t[a]), float(t[b])
    phase = _phase_of(phases, ta, tb)
    fmt = ".0f" if unit == "A" else ".1f"
    side, worst = ("low" if mean > 0 else "high"), ("low" if e[kw] > 0 else "high")
    # the largest miss may lie on the other side of the mean (a dip within an interval the model overshoots):
    # then it is named with its own side ("high by 4 A on average, by 300 A at 2.32 s (measured 358 A, model
    # 58 A)" read as the model 300 A too high)
    def by(v):  # a miss: two significant digits where the value's format would round it to 0 ("by 0 A")
        v = abs(float(v))
        return f"{v:{fmt}}" if v >= (0.5 if unit == "A" else 0.05) else f"{v:.2g}"

    text = (f"{ta:.1f}-{tb:.1f} s ({phase}): model {side} by {by(mean)} {unit} on average, "
            + ("" if worst == side else f"but {worst} ")
            + f"by {by(e[kw])} {unit} at {float(t[kw]):.2f} s (measured {float(y[kw]):{fmt}} "
            f"{unit}, model {float(yhat[kw]):{fmt}} {unit})")
    return {"t_start": ta, "t_end": tb, "phase": phase, "measured_peak": mp, "model_peak": hp,
            "mean_residual": mean, "t_worst": float(t[kw]), "measured_worst": float(y[kw]),
            "model_worst": float(yhat[kw]), "text": text}


def compare_run(measurement: Measurement, run: ModelRun, experiment: Experiment, *, model="macro", effects=(),
                params: Parameters | None = None, max_lag_s: float = MAX_LAG_S) -> Comparison:
    """Build a :class:`Comparison` from a model run already sampled at the measured times.

    Parameters
    ----------
    measurement : Measurement
        The record.
    run : ModelRun
        Output of :func:`~kilnctl.measure.runner.run_model` on this record.
    experiment : Experiment
        The experiment simulated.
    model : str
        Model name, for the report.
    effects : sequence of str
        Effects added, for the report.
    params : Parameters, optional
        Parameters simulated, for the report.
    max_lag_s : float, default 5.0
        Largest correlation lag [s].

    Returns
    -------
    Comparison
    """
    active = measurement.t >= experiment.t0 - 1e-9
    t = measurement.t[active]
    dt = float(np.median(np.diff(t)))
    n = t.size
    max_lag = int(max(1, min(n // 4, round(max_lag_s / dt))))
    meas = {k: measurement.channels[k][active] for k in CHANNELS}
    u = measurement.speed_ref[active] if measurement.speed_ref is not None else run.outputs["speed_ref_rpm"]
    phases = _phases(run, experiment.t0, float(t[-1]))
    chans = {}
    ok = measurement.kept[active]  # fit %, bias and rms leave out samples the logger clipped and spikes
    for k, (_name, unit) in CHANNELS.items():
        y, yhat = meas[k], run.outputs[k]
        e = clipped_residual(measurement, k, yhat, active)
        others = {"speed_ref_rpm (input)": u}
        others.update({f"{o} (measured)": meas[o] for o in CHANNELS if o != k})
        xc = {label: crosscorr(e, sig, max_lag, t=t) for label, sig in others.items()}
        fails = [_describe(t, y, yhat, e, a, b, unit, phases) for a, b in failing_intervals(t, e)]
        chans[k] = ChannelComparison(
            name=k, unit=unit, measured=y, model=yhat, residual=e, fit=fit_percent(y[ok], yhat[ok]),
            bias=float(np.mean(e[ok])), rms=float(np.sqrt(np.mean(e[ok] ** 2))), sigma=robust_sigma(e[ok]),
            whiteness=autocorr(e, max_lag, t=t), xcorr=xc, spectrum=residual_spectrum(e, t=t), failing=fails)
    extra = {"kiln_angle": kiln_angle(t, meas["speed_rpm"], (params or Parameters()).n),
             "model_outputs": run.outputs}
    return Comparison(t=t, channels=chans, experiment=experiment, model=model, effects=tuple(effects),
                      params=params, phases=phases, dt=dt, source=measurement.source, extra=extra)


def compare(measurement: Measurement, params: Parameters | None = None, model: str = "macro", effects=(), *,
            t0: float | None = None, max_lag_s: float = MAX_LAG_S) -> Comparison:
    """Simulate the experiment of a record and compare the model with it.

    Parameters
    ----------
    measurement : Measurement
        The measured start-up.
    params : Parameters, optional
        Setup of the experiment (defaults: the paper's Table 1); the gains
        are fixed once (see :func:`~kilnctl.measure.runner.fixed_gains`).
    model : {'macro', 'micro'}, default 'macro'
        Base model.
    effects : sequence of str
        Components to add (names of :mod:`kilnctl.model`).
    t0 : float, optional
        Start of the start-up in record time [s] (default: from the recorded
        reference, else the first sample).
    max_lag_s : float, default 5.0
        Largest lag of the correlation tests [s].

    Returns
    -------
    Comparison
        Fit % per channel, residual whiteness, cross-correlations with the
        input and the other channel (99 % bands), residual spectrum, and the
        failing intervals described in words.
    """
    Measurement.require(measurement, "compare")
    params = resolve_gains(Parameters() if params is None else params)
    exp = measurement.experiment(params, t0=t0)
    run = run_model(params, measurement, exp, model=model, effects=effects)
    return compare_run(measurement, run, exp, model=model, effects=effects, params=params, max_lag_s=max_lag_s)
