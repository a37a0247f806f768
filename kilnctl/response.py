"""Simulation results: a data object with a summary, CSV export and plots."""

from __future__ import annotations

import csv
import io
from dataclasses import dataclass, field

import numpy as np

from .figures import Plotted
from .files import write_atomic
from .params import Parameters

__all__ = ["Event", "Response", "write_atomic"]


@dataclass(frozen=True)
class Event:
    """One mode switch.

    Attributes
    ----------
    t : float
        Time [s].
    kind : str
        Physical name (``breakaway``, ``restick``, ``contact`` ...).
    component : str
        Component whose mode changed.
    from_mode, to_mode : str
        Modes before and after.
    rate : float
        Time derivative of the guard that fired, at the switch [1/s, guards
        scaled to order one]; NaN for a switch within a cascade that no
        guard crossing started.  A small rate is a slow (grazing) crossing,
        whose time is resolved only to (guard tolerance)/rate.
    """

    t: float
    kind: str
    component: str
    from_mode: str
    to_mode: str
    rate: float = float("nan")


@dataclass
class Response(Plotted):
    """Result of a hybrid simulation.

    Its figure (:meth:`plot`): motor current; motor speed with its reference;
    burden angle with the burden mode shaded; gear bending stress (or mesh
    force) with the mesh mode.  Event times are marked.

    Attributes
    ----------
    t : ndarray
        Time [s]; an event time appears twice (before and after the switch).
    outputs : dict of str to ndarray
        ``i_a`` [A], ``speed_rpm``, ``speed_ref_rpm`` [rpm], ``e_a`` [V],
        ``kiln_rpm`` [rpm], ``psi`` [rad], ``v_rel`` [rad/s], ``T_f`` [N*m],
        ``W_t`` [N], ``sigma`` [Pa], and in the micro model ``T_c`` [N*m]
        and ``ds`` [m].
    states : dict of str to ndarray
        States in physical units.
    modes : dict of str to ndarray of str
        Mode of each moded component at each sample.
    events : list of Event
        Mode switches in time order.
    params : Parameters
        Parameters used (gains resolved).
    model : str
        ``macro``, ``micro`` or ``custom``.
    components : tuple of str
        Components of the plant.
    info : dict
        ``wall_s`` (run time without building), ``build_s``, ``n_events``,
        ``dt``, tolerances.
    """

    t: np.ndarray
    outputs: dict
    states: dict
    modes: dict
    events: list
    params: Parameters
    model: str
    components: tuple
    info: dict = field(default_factory=dict)

    def __getitem__(self, name: str) -> np.ndarray:
        if name in self.outputs:
            return self.outputs[name]
        if name in self.states:
            return self.states[name]
        raise KeyError(f"no signal {name!r}; have {sorted(self.outputs) + sorted(self.states)}")

    @property
    def burden_mode(self) -> np.ndarray:
        """Burden mode at each sample (``stick``, ``slip_pos``, ``slip_neg``, ``held``)."""
        return self.modes.get("burden", np.array(["none"] * len(self.t)))

    def settle_time(self, band: float = 0.02) -> float | None:
        """Time after which the motor speed stays within ``band`` of the set point [s].

        Parameters
        ----------
        band : float, default 0.02
            Relative band around ``omega_ref``.

        Returns
        -------
        float or None
            None if the speed is outside the band at the end.
        """
        ref = self.params.omega_ref
        out = np.abs(self.outputs["speed_rpm"] - ref) > band * ref
        if out[-1]:
            return None
        idx = np.nonzero(out)[0]
        return float(self.t[idx[-1] + 1]) if len(idx) else float(self.t[0])

    def window_mean(self, name: str, seconds: float = 5.0) -> float:
        """Time-weighted mean of a signal over the last ``seconds`` of the run."""
        t, y = self.t, self.outputs[name]
        m = t >= t[-1] - seconds
        if m.sum() < 2:
            return float(y[-1])
        return float(np.trapezoid(y[m], t[m]) / (t[m][-1] - t[m][0]))

    def summary(self) -> dict:
        """Key figures of the run (JSON-ready).

        Returns
        -------
        dict
            ``peak_current_A``, ``final_current_A`` (mean of the last 5 s),
            ``settle_time_s`` (speed within 2 % of the set point for good, or
            None), ``burden_mode_final``, ``n_events``, and where the plant
            has a stress output ``peak_stress_Pa`` and ``final_stress_Pa``.
        """
        s = {"model": self.model, "t_end_s": float(self.t[-1])}
        if "i_a" in self.outputs:
            s["peak_current_A"] = float(np.max(np.abs(self.outputs["i_a"])))
            s["final_current_A"] = self.window_mean("i_a")
        if "speed_rpm" in self.outputs:
            s["settle_time_s"] = self.settle_time()
        s.update({
            "burden_mode_final": str(self.burden_mode[-1]),
            "n_events": len(self.events),
            "events_by_kind": {k: sum(e.kind == k for e in self.events) for k in sorted({e.kind for e in self.events})},
            "wall_time_s": self.info.get("wall_s"),
        })
        if "sigma" in self.outputs:
            s["peak_stress_Pa"] = float(np.max(np.abs(self.outputs["sigma"])))
            s["final_stress_Pa"] = self.window_mean("sigma")
        return s

    def to_csv(self, path=None) -> str:
        """Write the time series as CSV (whole or not at all) and return the text.

        Columns: ``time_s``, every output, and the mode of each moded
        component.

        Parameters
        ----------
        path : path-like, optional
            Destination file; not written if None.

        Returns
        -------
        str
            The CSV text.
        """
        buf = io.StringIO()
        w = csv.writer(buf, lineterminator="\n")
        names = list(self.outputs)
        w.writerow(["time_s"] + names + [f"mode_{c}" for c in self.modes])
        cols = [self.outputs[n] for n in names]
        mcols = list(self.modes.values())
        for k in range(len(self.t)):
            w.writerow([repr(float(self.t[k]))] + [repr(float(c[k])) for c in cols] + [m[k] for m in mcols])
        text = buf.getvalue()
        if path is not None:
            write_atomic(path, text)
        return text

    figsize = (10, 9)

    def _draw(self, fig):
        axes = fig.subplots(4, 1, sharex=True)
        t, y = self.t, self.outputs
        axes[0].plot(t, y["i_a"], color="C0")
        axes[0].set_ylabel("armature current [A]")
        axes[1].plot(t, y["speed_rpm"], color="C1", label="motor speed")
        axes[1].plot(t, y["speed_ref_rpm"], color="k", ls="--", lw=0.8, label="reference")
        axes[1].set_ylabel("speed [rpm]")
        axes[1].legend(loc="lower right")
        axes[2].plot(t, np.degrees(y["psi"]), color="C2")
        axes[2].set_ylabel("burden angle [deg]")
        bm = self.burden_mode
        slipping = np.isin(bm, ("slip_pos", "slip_neg"))
        if slipping.any():
            axes[2].fill_between(t, 0, 1, where=slipping, transform=axes[2].get_xaxis_transform(),
                                 color="C2", alpha=0.15, label="burden slipping")
            axes[2].legend(loc="lower right")
        if "sigma" in y:
            axes[3].plot(t, y["sigma"] / 1e6, color="C3")
            axes[3].set_ylabel("tooth bending\nstress [MPa]")
        if "mesh" in self.modes:
            gap = self.modes["mesh"] != "contact"
            if gap.any():
                axes[3].fill_between(t, 0, 1, where=gap, transform=axes[3].get_xaxis_transform(),
                                     color="C3", alpha=0.15, label="teeth not in driving contact")
                axes[3].legend(loc="lower right")
        axes[3].set_xlabel("time [s]")
        for ax in axes:
            ax.grid(True, alpha=0.3)
        s = self.summary()
        burden = {"stick": "stuck", "slip_pos": "sliding", "slip_neg": "sliding back", "held": "held by friction"}
        fig.suptitle(f"kilnctl {self.model} model: peak current {s['peak_current_A']:.0f} A, final "
                     f"{s['final_current_A']:.0f} A, {s['n_events']} mode switches; burden at the end: "
                     f"{burden.get(s['burden_mode_final'], s['burden_mode_final'])}")
        fig.tight_layout()
        return fig
