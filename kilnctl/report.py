"""Comparing kilnctl with the paper: a table object and the signal measures the studies use.

A study (``studies/fig*.py``) computes with :func:`kilnctl.simulate.simulate`,
measures the responses with the functions here, and fills a
:class:`PaperTable` with one row per quantity: what the paper reports, what
kilnctl gives, whether they agree, and why not when they do not.

>>> tab = PaperTable("demo", "Steady current")
>>> row = tab.add("final current", "620 A", "842 A", "differs", "Table 1 torque")
>>> print(tab.to_markdown().splitlines()[2])
| final current | 620 A | 842 A | differs | Table 1 torque |
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from .errors import KilnctlError
from .response import write_atomic

__all__ = ["Row", "PaperTable", "VERDICTS", "settle_time", "oscillation", "window_peak"]

#: allowed verdicts of a row
VERDICTS = ("agrees", "partly", "differs", "not in paper")


@dataclass(frozen=True)
class Row:
    """One compared quantity.

    Attributes
    ----------
    quantity : str
        What is compared, with its condition.
    paper : str
        What the paper reports (with the figure or equation).
    kilnctl : str
        What kilnctl gives.
    verdict : str
        One of :data:`VERDICTS`.
    note : str
        Reason for a difference, or the reading used.
    """

    quantity: str
    paper: str
    kilnctl: str
    verdict: str
    note: str = ""


class PaperTable:
    """Table "paper reports / kilnctl gives" of one study.

    Parameters
    ----------
    study : str
        Short name of the study (``fig04_friction``); the folder of its files.
    title : str
        One line saying what is reproduced.
    """

    def __init__(self, study: str, title: str):
        self.study = study
        self.title = title
        self.rows: list[Row] = []

    def add(self, quantity: str, paper: str, kilnctl: str, verdict: str, note: str = "") -> Row:
        """Append a row and return it.

        Parameters
        ----------
        quantity : str
            What is compared.
        paper : str
            The paper's value or statement.
        kilnctl : str
            kilnctl's value.
        verdict : str
            One of :data:`VERDICTS`.
        note : str, optional
            Reason for a difference, or the reading used.

        Returns
        -------
        Row

        Raises
        ------
        KilnctlError
            For a verdict not in :data:`VERDICTS`.
        """
        if verdict not in VERDICTS:
            raise KilnctlError(f"verdict {verdict!r} is not one of {VERDICTS}")
        row = Row(quantity, paper, kilnctl, verdict, note)
        self.rows.append(row)
        return row

    def to_markdown(self) -> str:
        """Return the table as GitHub markdown (no title line).

        Returns
        -------
        str
        """
        head = "| quantity | paper reports | kilnctl gives | verdict | note |\n|---|---|---|---|---|\n"

        def cell(s: str) -> str:
            return s.replace("|", "\\|").replace("\n", " ")

        body = "".join(f"| {cell(r.quantity)} | {cell(r.paper)} | {cell(r.kilnctl)} | {r.verdict} | "
                       f"{cell(r.note)} |\n" for r in self.rows)
        return head + body

    def to_text(self, width: int = 110) -> str:
        """Return the table as plain text for a terminal, notes on their own lines.

        Parameters
        ----------
        width : int, default 110
            Line width [characters] the notes are wrapped to.

        Returns
        -------
        str
        """
        import textwrap

        wq = max([len("quantity")] + [len(r.quantity) for r in self.rows])
        wp = max([len("paper reports")] + [len(r.paper) for r in self.rows])
        wk = max([len("kilnctl gives")] + [len(r.kilnctl) for r in self.rows])
        lines = [f"{self.study}: {self.title}",
                 f"{'quantity':<{wq}}  {'paper reports':<{wp}}  {'kilnctl gives':<{wk}}  verdict",
                 "-" * (wq + wp + wk + 15)]
        for r in self.rows:
            lines.append(f"{r.quantity:<{wq}}  {r.paper:<{wp}}  {r.kilnctl:<{wk}}  {r.verdict}")
            if r.note:
                lines += textwrap.wrap(r.note, width=width, initial_indent="    note: ",
                                       subsequent_indent="          ")
        return "\n".join(lines)

    def __str__(self) -> str:
        return self.to_text()

    def write(self, out_dir) -> Path:
        """Write ``table.md`` and ``table.json`` into ``out_dir`` (each whole or not at all).

        Parameters
        ----------
        out_dir : path-like
            Folder of the study's files (created).

        Returns
        -------
        Path
            The markdown file.
        """
        out = Path(out_dir)
        md = write_atomic(out / "table.md", f"**{self.study}**: {self.title}\n\n" + self.to_markdown())
        write_atomic(out / "table.json", json.dumps(
            {"study": self.study, "title": self.title, "rows": [asdict(r) for r in self.rows]}, indent=2))
        return md


def settle_time(t, y, tol: float, final: float | None = None) -> float | None:
    """Time after which a signal stays within ``tol`` of its final value.

    Parameters
    ----------
    t : array_like
        Time [s], non-decreasing.
    y : array_like
        Signal (any unit).
    tol : float
        Half-width of the band, in the unit of ``y``.
    final : float, optional
        Final value; the last sample of ``y`` if not given.

    Returns
    -------
    float or None
        The time [s] of the first sample after the last excursion; None if the
        last sample is outside the band.
    """
    t, y = np.asarray(t, float), np.asarray(y, float)
    final = float(y[-1]) if final is None else float(final)
    out = np.abs(y - final) > tol
    if out[-1]:
        return None
    idx = np.nonzero(out)[0]
    return float(t[idx[-1] + 1]) if len(idx) else float(t[0])


def oscillation(t, y, t_from: float) -> tuple[float, float | None]:
    """Peak-to-peak size and frequency of the oscillation of a signal after ``t_from``.

    The frequency is counted from the upward crossings of the signal's mean
    over the window (linear interpolation between samples).

    Parameters
    ----------
    t : array_like
        Time [s].
    y : array_like
        Signal (any unit).
    t_from : float
        Start of the window [s].

    Returns
    -------
    ptp : float
        Peak-to-peak value in the window, in the unit of ``y``.
    freq : float or None
        Frequency [Hz]; None with fewer than two upward crossings.
    """
    tw, yw = _window(t, y, t_from)
    if len(tw) < 3:
        return 0.0, None
    d = yw - np.mean(yw)
    up = np.nonzero((d[:-1] < 0) & (d[1:] >= 0))[0]
    if len(up) < 2:
        return float(np.ptp(yw)), None
    tc = tw[up] - d[up] * (tw[up + 1] - tw[up]) / (d[up + 1] - d[up])
    return float(np.ptp(yw)), float(1.0 / np.mean(np.diff(tc)))


def window_peak(t, y, t0: float, t1: float) -> tuple[float, float]:
    """Largest absolute value of a signal in the window [t0, t1] and its time.

    Parameters
    ----------
    t : array_like
        Time [s].
    y : array_like
        Signal (any unit).
    t0, t1 : float
        Window [s].

    Returns
    -------
    peak : float
        max |y| in the window, in the unit of ``y``.
    t_peak : float
        Time of the peak [s].

    Raises
    ------
    KilnctlError
        When no sample falls in the window.
    """
    tw, yw = _window(t, y, t0, t1)
    if len(tw) == 0:
        raise KilnctlError(f"no sample in the window [{t0}, {t1}] s")
    k = np.argmax(np.abs(yw))
    return float(abs(yw[k])), float(tw[k])


def _window(t, y, t0: float, t1: float = np.inf):
    """The samples of a signal with ``t0 <= t <= t1``, as float arrays ``(t, y)``."""
    t, y = np.asarray(t, float), np.asarray(y, float)
    m = (t >= t0) & (t <= t1)
    return t[m], y[m]
