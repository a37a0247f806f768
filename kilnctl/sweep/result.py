"""The result of a sweep: a labelled table (pandas), its summary, files and figures.

Why pandas and not xarray: a Latin hypercube or Monte Carlo sample is a set of
scattered points, not a grid, so the one shape that fits every method is a
table with one row per point (variables, outputs, status).  A grid is pivoted
from it when needed (:meth:`SweepResult.grid`), and
``result.table.set_index(list(result.variables)).to_xarray()`` gives an
xarray Dataset for those who want one.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from ..errors import KilnctlError, ParameterError, close_matches_hint
from ..params import SPECS
from ..files import write_atomic

__all__ = ["SweepResult", "wilson_interval"]

#: outputs a study may ask for: keys of :meth:`kilnctl.response.Response.summary`, with unit and meaning
OUTPUTS: dict[str, tuple[str, str]] = {
    "peak_current_A": ("A", "largest absolute armature current of the run"),
    "final_current_A": ("A", "time-weighted mean armature current over the last 5 s"),
    "settle_time_s": ("s", "time after which the motor speed stays within 2 % of the set point (NaN: never)"),
    "peak_stress_Pa": ("Pa", "largest absolute bending stress of a girth-gear tooth (Lewis)"),
    "final_stress_Pa": ("Pa", "time-weighted mean tooth bending stress over the last 5 s"),
    "n_events": ("-", "number of mode switches (breakaway, contact, limits ...)"),
    "burden_mode_final": ("-", "burden mode at the end: stick, slip_pos, slip_neg or held"),
    "wall_time_s": ("s", "simulation wall time of the point (not reproducible; for benchmarks)"),
}

#: file formats of :meth:`SweepResult.save`
TABLE_FORMATS = (".csv", ".json")


def wilson_interval(k: int, n: int, z: float = 1.96) -> tuple[float, float]:
    """Return the Wilson score interval of a probability estimated as k/n.

    Parameters
    ----------
    k : int
        Number of successes (e.g. points over the allowable stress).
    n : int
        Number of trials, >= 1.
    z : float, default 1.96
        Normal quantile of the confidence level (1.96: 95 %).

    Returns
    -------
    (float, float)
        Lower and upper bound of the probability.

    Examples
    --------
    >>> lo, hi = wilson_interval(0, 100)
    >>> lo, round(hi, 4)
    (0.0, 0.037)
    """
    if n < 1:
        raise ParameterError(f"n = {n!r}: a probability needs at least one trial")
    p = k / n
    den = 1 + z * z / n
    centre = (p + z * z / (2 * n)) / den
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / den
    return max(0.0, centre - half), min(1.0, centre + half)


#: display units for figures: SI unit -> (threshold of the largest value, scale, shown unit)
_DISPLAY = {"m": (0.1, 1e3, "mm"), "kg": (1e4, 1e-3, "t"), "Pa": (1e5, 1e-6, "MPa")}


def _axis(name: str, values, factors=None) -> tuple[float, str]:
    """Return (scale, unit) for plotting a variable or output: SI values times scale are in that unit."""
    if factors and name in factors:
        return 1.0, "x base " + ", ".join(factors[name])
    unit = SPECS[name].unit if name in SPECS else OUTPUTS[name][0] if name in OUTPUTS else ""
    if unit in _DISPLAY:
        big, scale, shown = _DISPLAY[unit]
        vals = np.abs(np.asarray(values, dtype=float))
        if vals.size and (np.nanmax(vals) < big if unit == "m" else np.nanmax(vals) >= big):
            return scale, shown
    return 1.0, unit


def _scaled(name: str, values, factors=None) -> tuple[float, str]:
    """Return (scale, axis label) of a variable or output."""
    scale, unit = _axis(name, values, factors)
    return scale, _label(name, unit)


def _label(name: str, unit: str) -> str:
    """Axis label ``name [unit]`` (no brackets for a dimensionless quantity)."""
    return f"{name} [{unit}]" if unit and unit != "-" else name


class SweepResult:
    """Outcome of :func:`kilnctl.sweep.run_sweep`.

    Attributes
    ----------
    table : pandas.DataFrame
        One row per point (index ``point``, in the space's order): the
        variables, the outputs (units in their names; NaN where a point
        failed), ``status`` (``ok`` or ``failed``), ``error`` (the message of a
        failed point) and ``cached`` (True if read from the cache).
    study : Study
        The study that was run.
    variables, outputs : tuple of str
        Column names of the swept variables and of the outputs.
    info : dict
        ``n_points``, ``n_computed``, ``n_cached``, ``n_failed``, ``wall_s``
        [s], ``executor``, ``cache``.
    worst_point : WorstPoint or None
        The point with the largest first output re-run on the CVODES engine
        at rtol 1e-10 (:mod:`kilnctl.sweep.confirm`), with a setup that
        reproduces it; None when not confirmed.
    """

    def __init__(self, study, table, info: dict):
        self.study = study
        self.table = table
        self.variables = tuple(study.variables)
        self.outputs = tuple(study.outputs)
        self.info = dict(info)
        self.worst_point = None

    @classmethod
    def from_records(cls, study, records, cached, info) -> "SweepResult":
        """Build the table from the worker records, in the space's order.

        Parameters
        ----------
        study : Study
        records : list of dict
            One record per point (see :func:`kilnctl.sweep.engine.run_point`).
        cached : list of bool
            Whether each point was read from the cache.
        info : dict
            Run information.

        Returns
        -------
        SweepResult
        """
        import pandas as pd

        cols = {nm: list(v) for nm, v in study.samples().items()}
        for k in study.outputs:
            vals = [r["custom"].get(k) if k in study.custom_outputs else r["summary"].get(k) for r in records]
            if k == "burden_mode_final":
                cols[k] = [v if v is not None else "" for v in vals]
            else:
                cols[k] = [math.nan if v is None else float(v) for v in vals]
        cols["status"] = [r["status"] for r in records]
        cols["error"] = [r["error"] for r in records]
        cols["cached"] = list(cached)
        table = pd.DataFrame(cols, index=pd.RangeIndex(len(records), name="point"))
        return cls(study, table, info)

    # --- access ----------------------------------------------------------------------------------
    def __len__(self) -> int:
        return len(self.table)

    def __repr__(self) -> str:
        i = self.info
        return (f"SweepResult({self.study.name!r}: {i['n_points']} points, {i['n_computed']} computed, "
                f"{i['n_cached']} cached, {i['n_failed']} failed, {i['wall_s']:.1f} s)")

    def to_pandas(self):
        """Return a copy of the result table (pandas.DataFrame)."""
        return self.table.copy()

    def _output(self, output: str | None) -> str:
        output = self.outputs[0] if output is None else output
        if output not in self.outputs:
            raise ParameterError(f"{output!r} is not an output of this sweep: {close_matches_hint(output, self.outputs)}")
        return output

    def worst(self, output: str | None = None, n: int = 5):
        """Return the ``n`` points with the largest value of an output.

        Parameters
        ----------
        output : str, optional
            Output column (default: the first output).
        n : int, default 5
            Number of rows.

        Returns
        -------
        pandas.DataFrame
            Variables and that output, largest first.
        """
        output = self._output(output)
        return self.table.nlargest(n, output)[list(self.variables) + [output]]

    def exceedance(self, output: str, threshold: float) -> dict:
        """Return the fraction of points whose output exceeds a threshold, with its 95 % interval.

        Failed points are left out (and counted).

        Parameters
        ----------
        output : str
            Output column.
        threshold : float
            Limit, in the output's unit (e.g. an allowable stress [Pa]).

        Returns
        -------
        dict
            ``probability``, ``ci_low``, ``ci_high`` (Wilson, 95 %),
            ``n_exceed``, ``n`` (points used), ``n_failed``.
        """
        output = self._output(output)
        vals = self.table.loc[self.table["status"] == "ok", output].to_numpy(float)
        n = len(vals)
        k = int(np.sum(vals > threshold))
        lo, hi = wilson_interval(k, n)
        return {"probability": k / n, "ci_low": lo, "ci_high": hi, "n_exceed": k, "n": n,
                "n_failed": int(len(self.table) - n)}

    def grid(self, output: str | None = None, rows: str | None = None, cols: str | None = None):
        """Return an output of a two-variable grid as a table (rows x columns).

        Parameters
        ----------
        output : str, optional
            Output column (default: the first output).
        rows, cols : str, optional
            Variables along the rows and columns (default: the first two).
            Any other variables must have been fixed by filtering the table.

        Returns
        -------
        pandas.DataFrame
        """
        output = self._output(output)
        rows = rows or self.variables[0]
        cols = cols or self.variables[1]
        return self.table.pivot(index=rows, columns=cols, values=output)

    def summary(self) -> dict:
        """Return min, mean, max and the point of the maximum of each numeric output.

        Returns
        -------
        dict
            ``{output: {"min", "mean", "max", "argmax": {variable: value}}}``,
            plus ``info``.
        """
        ok = self.table[self.table["status"] == "ok"]
        out = {}
        for k in self.outputs:
            if k == "burden_mode_final" or ok.empty:
                continue
            col = ok[k].astype(float)
            i = col.idxmax()
            out[k] = {"min": float(col.min()), "mean": float(col.mean()), "max": float(col.max()),
                      "argmax": {v: _plain(ok.at[i, v]) for v in self.variables}}
        out["info"] = self.info
        w = self.worst_point
        if w is not None:
            out["worst_point"] = {"output": w.output, "point": w.index, "variables": w.variables, "value": w.value,
                                  "cvodes_rtol_1e-10": w.reference, "confirmed": w.agree, "error": w.error,
                                  "setup_toml": w.setup_toml, "command": w.command}
        return out

    # --- files -----------------------------------------------------------------------------------
    def to_csv(self, path=None) -> str:
        """Return the table as CSV text and write it (whole or not at all) if a path is given.

        Parameters
        ----------
        path : path-like, optional
            Destination file.

        Returns
        -------
        str
        """
        text = self.table.to_csv()
        if path is not None:
            write_atomic(path, text)
        return text

    def to_json(self, path=None) -> str:
        """Return ``{"study", "info", "rows"}`` as JSON text; write it whole if a path is given.

        Parameters
        ----------
        path : path-like, optional
            Destination file.

        Returns
        -------
        str
        """
        rows = json.loads(self.table.reset_index().to_json(orient="records"))
        text = json.dumps({"study": self.study.describe(), "info": self.info, "rows": rows}, indent=1)
        if path is not None:
            write_atomic(path, text)
        return text

    def save(self, path) -> Path:
        """Write the table as ``.csv`` or ``.json`` (by the extension), whole or not at all.

        Parameters
        ----------
        path : path-like

        Returns
        -------
        Path
        """
        path = Path(path)
        suffix = path.suffix.lower()
        if suffix not in TABLE_FORMATS:
            raise KilnctlError(f"{path}: unknown table format {path.suffix!r}; use .csv or .json")
        (self.to_json if suffix == ".json" else self.to_csv)(path)
        return path

    # --- figures ---------------------------------------------------------------------------------
    def plot(self, output: str | None = None, *, threshold: float | None = None, fig=None):
        """Draw the sweep and return the figure.

        One variable: the output against it.  A grid of two or more variables:
        heat maps of the output over the first two, one panel per value of the
        third (further variables at their worst case), with the region above
        ``threshold`` outlined.  A sampled space: the histogram of the output
        with the fraction above ``threshold``, and the output against each
        variable.

        Parameters
        ----------
        output : str, optional
            Output to draw (default: the first output).
        threshold : float, optional
            A limit in the output's unit (e.g. the allowable stress [Pa]).
        fig : matplotlib.figure.Figure, optional
            Figure to draw into (a new one by default).

        Returns
        -------
        matplotlib.figure.Figure
        """
        from matplotlib.figure import Figure

        output = self._output(output)
        ok = self.table[self.table["status"] == "ok"]
        if ok.empty:
            raise KilnctlError("every point of the sweep failed: nothing to plot")
        fig = Figure(figsize=(10, 6.5)) if fig is None else fig
        fig.set_layout_engine("constrained")
        if len(self.variables) == 1:
            self._plot_line(fig, ok, output, threshold)
        elif self.study.space.method == "grid":
            self._plot_maps(fig, ok, output, threshold)
        else:
            self._plot_sample(fig, ok, output, threshold)
        n_fail = self.info.get("n_failed", 0)
        fig.suptitle(f"{self.study.name}: {len(self)} {self.study.model}-model start-ups of {self.study.t_end:g} s"
                     + (f" ({n_fail} failed, left out)" if n_fail else ""), fontsize=11)
        return fig

    def _plot_line(self, fig, ok, output, threshold):
        ax = fig.subplots()
        v = self.variables[0]
        d = ok.sort_values(v)
        sx, xlab = _scaled(v, d[v], self.study.factors)
        sy, ylab = _scaled(output, d[output])
        style = "o-" if self.study.space.method == "grid" else "o"
        ax.plot(d[v] * sx, d[output] * sy, style, color="C0")
        if threshold is not None:
            ax.axhline(threshold * sy, color="C3", ls="--", label=f"limit {threshold * sy:g}")
            ax.legend()
        ax.set_xlabel(xlab)
        ax.set_ylabel(ylab)
        ax.grid(True, alpha=0.3)

    def _plot_maps(self, fig, ok, output, threshold):
        yv, xv = self.variables[0], self.variables[1]
        rest = self.variables[2:]
        panel_var = rest[0] if rest else None
        d = ok
        if len(rest) > 1:  # further variables: worst case over them
            d = ok.groupby(list(self.variables[:3]), as_index=False)[output].max()
        panels = sorted(d[panel_var].unique())[:12] if panel_var else [None]
        sx, xlab = _scaled(xv, d[xv], self.study.factors)
        sy, ylab = _scaled(yv, d[yv], self.study.factors)
        sz, zlab = _scaled(output, d[output])
        vmin, vmax = d[output].min() * sz, d[output].max() * sz
        ncol = min(len(panels), 3)
        nrow = math.ceil(len(panels) / ncol)
        axes = fig.subplots(nrow, ncol, squeeze=False, sharex=True, sharey=True).ravel()
        mesh = None
        for ax, pv in zip(axes, panels):
            sub = d if pv is None else d[d[panel_var] == pv]
            g = sub.pivot(index=yv, columns=xv, values=output) * sz
            X, Y = np.meshgrid(np.asarray(g.columns, float) * sx, np.asarray(g.index, float) * sy)
            Z = g.to_numpy()
            mesh = ax.pcolormesh(X, Y, Z, shading="nearest", vmin=vmin, vmax=vmax, cmap="viridis")
            if threshold is not None and min(Z.shape) > 1 and np.nanmax(Z) > threshold * sz:
                ax.contourf(X, Y, Z, levels=[threshold * sz, np.inf], colors="none", hatches=["//"])
                if np.nanmin(Z) < threshold * sz:
                    ax.contour(X, Y, Z, levels=[threshold * sz], colors="C3", linewidths=2)
            worst = sub.loc[sub[output].idxmax()]
            ax.plot(worst[xv] * sx, worst[yv] * sy, marker="*", ms=14, color="C3", mec="w")
            if pv is not None:
                ps, punit = _axis(panel_var, [pv], self.study.factors)
                shown = "" if punit.startswith("x ") or punit == "-" else f" {punit}"
                ax.set_title(f"{panel_var} = {pv * ps:g}{shown}", fontsize=9)
        for ax in axes[len(panels):]:
            ax.set_visible(False)
        for ax in axes[(nrow - 1) * ncol:]:
            ax.set_xlabel(xlab)
        for ax in axes[::ncol]:
            ax.set_ylabel(ylab)
        cb = fig.colorbar(mesh, ax=list(axes[:len(panels)]), shrink=0.9)
        cb.set_label(zlab + ("" if threshold is None else f"; hatched: above {threshold * sz:.4g}") + "; star: worst")

    def _plot_sample(self, fig, ok, output, threshold):
        nv = len(self.variables)
        axes = fig.subplots(1, 1 + min(nv, 3), squeeze=False)[0]
        sz, zlab = _scaled(output, ok[output])
        vals = ok[output].to_numpy(float) * sz
        axes[0].hist(vals, bins=max(10, min(50, int(np.sqrt(len(vals))) * 2)), color="C0", alpha=0.8)
        axes[0].set_xlabel(zlab)
        axes[0].set_ylabel("points")
        # exceedance curve: fraction of points above each level (empirical survival function)
        levels = np.sort(vals)
        frac = 1.0 - np.arange(1, len(levels) + 1) / len(levels)
        twin = axes[0].twinx()
        twin.step(levels, frac, where="post", color="k", lw=1.0)
        twin.set_ylim(0, 1.02)
        twin.set_ylabel("fraction of points above (black)")
        if threshold is not None:
            ex = self.exceedance(output, threshold)
            axes[0].axvline(threshold * sz, color="C3", ls="--")
            axes[0].set_title(f"P(> {threshold * sz:.4g}) = {ex['probability']:.3f}, 95 % interval "
                              f"[{ex['ci_low']:.3f}, {ex['ci_high']:.3f}]", fontsize=9)
        for ax, v in zip(axes[1:], self.variables):
            sx, xlab = _scaled(v, ok[v], self.study.factors)
            ax.plot(ok[v] * sx, vals, ".", alpha=0.6)
            ax.set_xlabel(xlab)
            ax.set_ylabel(zlab)
            if threshold is not None:
                ax.axhline(threshold * sz, color="C3", ls="--")
        for ax in axes:
            ax.grid(True, alpha=0.3)


def _plain(v):
    """A numpy scalar as a plain Python value."""
    return v.item() if isinstance(v, np.generic) else v
