"""Writing figures: whole or not at all, in the format the file name asks for."""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

from .errors import KilnctlError

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
    path.parent.mkdir(parents=True, exist_ok=True)
    kwargs.setdefault("dpi", 130)
    kwargs.setdefault("bbox_inches", "tight")
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=".tmp-", suffix=path.suffix or ".png")
    os.close(fd)
    try:
        fig.savefig(tmp, format=fmt, **kwargs)
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise
    return path
