"""Writing figures: whole or not at all, in the format the file name asks for."""

from __future__ import annotations

from pathlib import Path

from .errors import KilnctlError
from .files import atomic_path

__all__ = ["save_figure"]


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
