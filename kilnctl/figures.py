"""The figure style shared by every kilnctl figure, and writing figures whole.

One place for what a reader should find the same in every figure: the
colour of a measured trace, of a model, of a limit or a requirement; font
sizes; how a record is named in a title (its file name, not its path); a
caption under the axes that explains lines and shading a legend cannot.

>>> record_name("/data/plant/2024-05-01 startup.csv")
'2024-05-01 startup.csv'
"""

from __future__ import annotations

import textwrap
from abc import ABC, abstractmethod
from pathlib import Path

from .errors import KilnctlError
from .files import atomic_path

__all__ = ["COLORS", "FONT", "save_figure", "record_name", "finish", "limit_line", "note_box", "Plotted"]

#: colours by role, the same in every figure
COLORS = {
    "measured": "k",          # a measured trace
    "model": "C0",            # the model as given / calibrated base / linear prediction (stick)
    "model2": "C1",           # a second model condition (slip)
    "final": "C3",            # the model after diagnosis / the nonlinear run / the optimized ramp
    "baseline": "0.55",       # the reference case something is compared against
    "reference": "k",         # a speed reference
    "limit": "#d62728",       # a hard limit or requirement bound (current limit, zeta_min, wn_max)
    "region": "#2ca02c",      # where a requirement is met
    "violation": "#d62728",   # where a requirement is not met (shaded)
    "threshold": "k",         # a decision threshold (dBIC, held-out gain)
    "supported": "C2",        # a supported candidate
    "rejected": "C7",         # a rejected candidate
    "event": "0.5",           # an event marker (breakaway, limit reached)
}

#: font sizes [pt] by role
FONT = {"suptitle": 11, "title": 9.5, "label": 9.5, "legend": 8, "note": 8.5, "caption": 8.5}


class Plotted(ABC):
    """Base of the result objects that draw one standard figure.

    :meth:`plot` makes the figure, or takes the caller's, and a subclass's
    ``_draw(fig)`` draws its panels into it and returns it; a subclass sets
    ``figsize`` for a new figure.
    """

    #: size of a new figure [inch]
    figsize = (10.0, 8.0)

    def plot(self, fig=None):
        """Draw the object's standard figure (its panels: the class description) and return it.

        Parameters
        ----------
        fig : matplotlib.figure.Figure, optional
            Figure to draw into; by default a new one of size ``figsize``.

        Returns
        -------
        matplotlib.figure.Figure
        """
        if fig is None:
            import matplotlib.pyplot as plt

            fig = plt.figure(figsize=self.figsize)
        return self._draw(fig)

    @abstractmethod
    def _draw(self, fig):
        """Draw the panels into ``fig`` and return it (each subclass defines its figure)."""


def record_name(source) -> str:
    """The name a figure or report gives a record: its file name, never its absolute path.

    Parameters
    ----------
    source : str or path-like
        The record's source (a path, or a name such as ``'synthetic'``).

    Returns
    -------
    str
    """
    text = str(source)
    path = Path(text.replace("\\", "/"))
    # a path (absolute, or a file name with its folder) gives its file name; a label with a slash in it ("drift
    # 0.25 A/s", "kiln 2 / line B") is kept whole
    return path.name if (path.is_absolute() or ("/" in text or "\\" in text) and path.suffix) else text


def limit_line(ax, value: float, label: str, *, axis: str = "h", color=None, ls="--", lw=1.0):
    """Draw a labelled horizontal (or vertical) line of a limit or requirement.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        Axes to draw on.
    value : float
        Where the line lies, in data units of the axis.
    label : str
        Legend text (say what it is and its value with unit).
    axis : {'h', 'v'}, default 'h'
        Horizontal (a y value) or vertical (an x value).
    color : color, optional
        Default: ``COLORS['limit']``.
    ls : str, default '--'
        Line style.
    lw : float, default 1.0
        Line width [pt].

    Returns
    -------
    matplotlib.lines.Line2D
    """
    draw = ax.axhline if axis == "h" else ax.axvline
    return draw(value, color=color or COLORS["limit"], ls=ls, lw=lw, label=label)


def note_box(ax, text: str, *, loc: str = "upper left", fontsize: float | None = None):
    """Put a short note in a white box inside the axes.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        Axes to annotate.
    text : str
        The note (may hold line breaks).
    loc : {'upper left', 'upper right', 'lower left', 'lower right'}, default 'upper left'
        Corner of the axes.
    fontsize : float, optional
        Font size [pt] (default ``FONT['note']``).

    Returns
    -------
    matplotlib.text.Text
    """
    v, h = loc.split()
    x = 0.02 if h == "left" else 0.98
    y = 0.97 if v == "upper" else 0.03
    return ax.text(x, y, text, transform=ax.transAxes, ha=h, va="top" if v == "upper" else "bottom",
                   fontsize=fontsize or FONT["note"], zorder=10,
                   bbox={"boxstyle": "round", "fc": "white", "ec": "0.6", "alpha": 0.92})


def finish(fig, title: str | None = None, caption: str | None = None, *, width: int = 170):
    """Give a figure its title and a caption below the axes, and lay it out.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure.
    title : str, optional
        Title above all axes (name the record by :func:`record_name`).
    caption : str, optional
        What the lines, shading and markers mean, where a legend cannot say
        it; wrapped to ``width`` characters.
    width : int, default 170
        Caption line length [characters].

    Returns
    -------
    matplotlib.figure.Figure
        The same figure.
    """
    bottom = 0.0
    if title:  # tight_layout leaves room for the suptitle itself
        # wrapped to the figure's width (a character is about 0.55 of the font size wide): a diagnosis' verdict
        # as a title ran off both edges of the ranking figure
        chars = max(40, int(fig.get_figwidth() * 72.0 / (0.55 * FONT["suptitle"])))
        fig.suptitle("\n".join(textwrap.wrap(title, chars)), fontsize=FONT["suptitle"])
    if caption:
        lines = textwrap.wrap(caption, width)
        fig.text(0.01, 0.005, "\n".join(lines), ha="left", va="bottom", fontsize=FONT["caption"], color="0.2")
        bottom = (0.18 * len(lines) + 0.08) / fig.get_figheight()
    fig.tight_layout(rect=(0, bottom, 1, 1))
    return fig


def save_figure(fig, path, **kwargs) -> Path:
    """Save a figure whole: to a temporary file beside ``path``, then renamed.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure.
    path : path-like
        Destination; its suffix (``.png``, ``.pdf``, ``.svg`` ...) sets the
        format.  An existing file is replaced (it is our own output).
    **kwargs
        Passed to ``Figure.savefig`` (``dpi`` defaults to 130).

    Returns
    -------
    Path
        The path written.
    """
    path = Path(path)
    fmt = path.suffix.lstrip(".").lower() or "png"
    if fmt not in fig.canvas.get_supported_filetypes():
        raise KilnctlError(f"{path}: unknown figure format {fmt!r}; use one of "
                           + ", ".join(sorted(fig.canvas.get_supported_filetypes())))
    kwargs.setdefault("dpi", 130)
    kwargs.setdefault("bbox_inches", "tight")
    with atomic_path(path, suffix=path.suffix or ".png") as tmp:
        fig.savefig(tmp, format=fmt, **kwargs)
    return path
