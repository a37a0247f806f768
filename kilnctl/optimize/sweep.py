"""Sweep of the paper's constant ramp on the hybrid plant (Fig. 15), as a data object.

:func:`ramp_sweep` runs the exact hybrid micro model for a list of ramp
constants and measures every start-up the way the optimizer's verification
does; :class:`RampSweep` holds the numbers, prints a table and draws the
figure, with optimized ramps (:class:`~kilnctl.optimize.RampResult`) on the
same axes.

Examples
--------
>>> from kilnctl import Parameters
>>> from kilnctl.optimize.sweep import ramp_sweep
>>> sw = ramp_sweep(Parameters(gains="given", k_p=0.085, k_I=2.17, k_D=0.0142), [74.0, 148.0], settle=3.0)
>>> bool(sw.peak_stress_Pa[1] > sw.peak_stress_Pa[0])
True
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..params import Parameters
from ..simulate import resolve_gains
from .problem import Profile
from .verify import measure_hybrid

__all__ = ["RampSweep", "ramp_sweep"]


@dataclass
class RampSweep:
    """Start-up measures of the hybrid plant for a range of constant ramps.

    Attributes
    ----------
    rate : ndarray
        Ramp constants [rpm/s].
    peak_stress_Pa, dynamic_stress_Pa : ndarray
        Peak |sigma| and peak dynamic stress [Pa] (see
        :func:`kilnctl.optimize.model.load_stress`).
    time_peak_s : ndarray
        Time of the peak |sigma| [s].
    running_stress_Pa : ndarray
        Mean stress over the last 5 s [Pa].
    time_to_speed_s : ndarray
        Time to 95 % of omega_ref [s] (NaN if not reached).
    peak_current_A : ndarray
        Peak armature current [A].
    limit_events : ndarray
        Drive-limit switches per run.
    params : Parameters
        Parameter set (gains resolved).
    """

    rate: np.ndarray
    peak_stress_Pa: np.ndarray
    dynamic_stress_Pa: np.ndarray
    time_peak_s: np.ndarray
    running_stress_Pa: np.ndarray
    time_to_speed_s: np.ndarray
    peak_current_A: np.ndarray
    limit_events: np.ndarray
    params: Parameters

    def at(self, rate: float) -> dict:
        """Measures of one run of the sweep.

        Parameters
        ----------
        rate : float
            Ramp constant [rpm/s]; must be one of the sweep's.

        Returns
        -------
        dict
            ``rate``, ``peak_stress_Pa``, ``dynamic_stress_Pa``, ``time_to_speed_s``,
            ``peak_current_A``, ``running_stress_Pa``, ``limit_events``.

        Raises
        ------
        KeyError
            ``rate`` is not in the sweep.
        """
        k = int(np.argmin(np.abs(self.rate - rate)))
        if not np.isclose(self.rate[k], rate):
            raise KeyError(f"ramp constant {rate} rpm/s is not in the sweep")
        return {f: getattr(self, f)[k] for f in ("rate", "peak_stress_Pa", "dynamic_stress_Pa", "time_to_speed_s",
                                                  "peak_current_A", "running_stress_Pa", "limit_events")}

    def best_at(self, t_max: float, kind: str = "peak") -> dict | None:
        """The grid point of least stress among those at speed by ``t_max`` [s], or None.

        Parameters
        ----------
        t_max : float
            Start-up time allowed [s].
        kind : {'peak', 'dynamic'}
            Which stress.

        Returns
        -------
        dict or None
            As :meth:`at`.
        """
        y = self.peak_stress_Pa if kind == "peak" else self.dynamic_stress_Pa
        ok = np.nan_to_num(self.time_to_speed_s, nan=np.inf) <= t_max
        if not ok.any():
            return None
        return self.at(float(self.rate[ok][np.argmin(y[ok])]))

    def table(self) -> str:
        """Plain-text table, one line per ramp constant."""
        rows = [f"{'ramp [rpm/s]':>12s} {'to speed [s]':>12s} {'peak [MPa]':>11s} {'at [s]':>7s} "
                f"{'dynamic [MPa]':>14s} {'running [MPa]':>14s} {'I peak [A]':>11s} {'limits':>6s}"]
        for k in range(len(self.rate)):
            tts = self.time_to_speed_s[k]
            rows.append(f"{self.rate[k]:12.1f} {('-' if np.isnan(tts) else f'{tts:.2f}'):>12s} "
                        f"{self.peak_stress_Pa[k] / 1e6:11.2f} {self.time_peak_s[k]:7.2f} "
                        f"{self.dynamic_stress_Pa[k] / 1e6:14.2f} {self.running_stress_Pa[k] / 1e6:14.2f} "
                        f"{self.peak_current_A[k]:11.0f} {int(self.limit_events[k]):6d}")
        return "\n".join(rows)

    def plot(self, optima=(), fig=None, paper_rate: float = 74.0, paper_factor: float = 4.0):
        """Draw the sweep against the ramp constant and against the start-up time, optima on the same axes.

        Parameters
        ----------
        optima : sequence of RampResult
            Verified optimization results (drawn at their time to speed and
            equivalent rate omega_ref/end time).
        fig : matplotlib.figure.Figure, optional
            Figure to draw into (a new one by default).
        paper_rate : float, default 74.0
            The paper's typical ramp constant [rpm/s] (marked).
        paper_factor : float, default 4.0
            The paper's Fig. 15 finding: x10 ramp gives x``paper_factor`` stress
            (drawn as a trend through the sweep's point at ``paper_rate``).

        Returns
        -------
        matplotlib.figure.Figure
        """
        if fig is None:
            from matplotlib.figure import Figure

            fig = Figure(figsize=(12, 5.5))
        ax, bx = fig.subplots(1, 2)
        r = self.rate
        for a, x in ((ax, r), (bx, self.time_to_speed_s)):
            a.plot(x, self.peak_stress_Pa / 1e6, "o-", color="k", ms=4, label="constant ramp: peak stress")
            a.plot(x, self.dynamic_stress_Pa / 1e6, "s--", color="0.45", ms=3.5,
                   label="constant ramp: dynamic stress")
            a.grid(True, alpha=0.3, which="both")
        k74 = int(np.argmin(np.abs(r - paper_rate)))
        slope = np.log(paper_factor) / np.log(10.0)
        rr = np.geomspace(r.min(), r.max(), 50)
        ax.plot(rr, self.dynamic_stress_Pa[k74] / 1e6 * (rr / r[k74]) ** slope, color="C3", ls=":", lw=1.2,
                label=f"paper, Fig. 15: x10 ramp -> x{paper_factor:g} stress (through the dynamic stress "
                      f"at {r[k74]:g} rpm/s)")
        ax.axvline(paper_rate, color="C3", lw=0.8, alpha=0.5)
        ax.set_xscale("log")
        ax.set_xlabel("ramp constant [rpm/s]")
        ax.set_ylabel("tooth bending stress [MPa]")
        ax.set_title("(a) Fig. 15: stress against the ramp constant", loc="left", fontsize=10)
        bx.set_xscale("log")
        ax.set_yscale("log")
        bx.set_xlabel("time to 95 % speed [s]")
        bx.set_title("(b) at equal start-up time: sweep and optimized ramps", loc="left", fontsize=10)
        markers = {"constant": "*", "scurve": "D", "pwl": "^"}
        for k, res in enumerate(optima):
            s = res.summary()
            prof = res.problem.profile
            t = s["time_to_speed_s"]
            lab = f"optimized {s['profile']} (t_max {res.problem.t_max:g} s)"
            rate_eq = prof.equivalent_rate(res.values, res.problem.params.omega_ref)
            for a, x in ((ax, rate_eq), (bx, t)):
                a.plot([x], [s["peak_stress_verified_Pa"] / 1e6], markers.get(prof.kind, "o"), color=f"C{k}", ms=11,
                       mec="k", label=lab + ": peak" if a is bx else None)
                a.plot([x], [s["dynamic_stress_verified_Pa"] / 1e6], markers.get(prof.kind, "o"), color=f"C{k}",
                       ms=8, mfc="none", mew=2, label=lab + ": dynamic" if a is bx else None)
        ax.legend(fontsize=7.5, loc="upper left")
        bx.legend(fontsize=7, loc="upper right")
        fig.tight_layout()
        return fig


def ramp_sweep(params: Parameters, rates, settle: float = 15.0, speed_fraction: float = 0.95,
               dt: float = 1e-3) -> RampSweep:
    """Run the hybrid micro model for each constant ramp and measure the start-up.

    Parameters
    ----------
    params : Parameters
        Parameter set (gains resolved if ``'design'``).
    rates : sequence of float
        Ramp constants [rpm/s], > 0.
    settle : float, default 15.0
        Simulated time after the reference reaches omega_ref [s] (the burden
        reaches its running angle): each run lasts omega_ref/rate + settle.
    speed_fraction : float, default 0.95
        Fraction of omega_ref for the time to speed [-].
    dt : float, default 1e-3
        Output step [s].

    Returns
    -------
    RampSweep
    """
    p = resolve_gains(params)
    prof = Profile("constant", 1)
    rows = []
    for r in rates:
        m, _ = measure_hybrid(p, prof, [float(r)], p.omega_ref / float(r) + settle, speed_fraction, dt)
        rows.append(m)
    arr = lambda f: np.array([np.nan if getattr(m, f) is None else getattr(m, f) for m in rows], dtype=float)  # noqa: E731
    return RampSweep(np.asarray(rates, dtype=float), arr("peak_stress_Pa"), arr("peak_dynamic_stress_Pa"),
                     arr("time_peak_s"), arr("running_stress_Pa"), arr("time_to_speed_s"), arr("peak_current_A"),
                     arr("limit_events"), p)
