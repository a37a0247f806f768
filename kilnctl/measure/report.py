"""Self-contained HTML reports: figures embedded as base64 PNG, written whole or not at all."""

from __future__ import annotations

import base64
import html
import io
import json
from pathlib import Path

from ..errors import ConfigFileError
from ..response import write_atomic

__all__ = ["figure_tag", "table", "page", "write_report_files", "esc"]

_CSS = """
body{font-family:system-ui,-apple-system,Segoe UI,sans-serif;max-width:1200px;margin:2em auto;padding:0 1em;
color:#222;line-height:1.45}
h1{font-size:1.5em}h2{font-size:1.2em;border-bottom:1px solid #ccc;padding-bottom:.2em;margin-top:1.8em}
table{border-collapse:collapse;font-size:.9em;margin:.6em 0}td,th{border:1px solid #ccc;padding:.25em .6em;
text-align:right}th{background:#f3f3f3}td.l,th.l{text-align:left}tr.sel td{background:#e9f6e9}
img{max-width:100%;border:1px solid #eee}.big{font-size:1.15em;background:#f6f8fa;padding:.6em 1em;
border-left:4px solid #2a7;margin:1em 0}.warn{border-left-color:#d80}code{background:#f3f3f3;padding:0 .2em}
"""


def esc(text) -> str:
    """HTML-escape any value's text."""
    return html.escape(str(text))


def figure_tag(fig, alt: str = "figure") -> str:
    """Return an ``<img>`` tag holding the figure as a base64 PNG.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure.
    alt : str
        Alternative text.

    Returns
    -------
    str
    """
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=90)
    data = base64.b64encode(buf.getvalue()).decode("ascii")
    return f'<img alt="{esc(alt)}" src="data:image/png;base64,{data}">'


def table(header, rows, left=1, selected=()) -> str:
    """Return an HTML table.

    Parameters
    ----------
    header : sequence of str
        Column titles.
    rows : sequence of sequence
        Cell values (escaped here).
    left : int, default 1
        Number of leading columns aligned left.
    selected : collection of int
        Row indices to highlight.

    Returns
    -------
    str
    """
    cls = lambda j: ' class="l"' if j < left else ""  # noqa: E731
    out = ["<table><tr>" + "".join(f"<th{cls(j)}>{esc(h)}</th>" for j, h in enumerate(header)) + "</tr>"]
    for i, r in enumerate(rows):
        tr = '<tr class="sel">' if i in selected else "<tr>"
        out.append(tr + "".join(f"<td{cls(j)}>{esc(c)}</td>" for j, c in enumerate(r)) + "</tr>")
    return "\n".join(out) + "</table>"


def page(title: str, body: str) -> str:
    """Return a complete HTML document.

    Parameters
    ----------
    title : str
        Page title.
    body : str
        HTML of the body (already escaped where needed).

    Returns
    -------
    str
    """
    return (f"<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>{esc(title)}</title>"
            f"<style>{_CSS}</style></head><body>\n<h1>{esc(title)}</h1>\n{body}\n</body></html>\n")


def write_report_files(folder, files: dict, protect=()) -> list[Path]:
    """Write report files into a folder, each whole or not at all.

    Parameters
    ----------
    folder : path-like
        Destination folder (created).
    files : dict of str to str or bytes or dict
        File name -> content (a dict is written as indented JSON).
    protect : sequence of path-like
        Input files that must never be overwritten (the record, the setup).

    Returns
    -------
    list of Path
        The paths written.

    Raises
    ------
    ConfigFileError
        When ``folder`` is a file, or a report file would replace an input.
    """
    folder = Path(folder)
    if folder.exists() and not folder.is_dir():
        raise ConfigFileError(f"--report {folder} is a file, not a folder")
    guarded = {Path(p).resolve() for p in protect if p}
    targets = {folder / name: content for name, content in files.items()}
    for path in targets:
        if path.resolve() in guarded:
            raise ConfigFileError(f"report file {path} would overwrite an input file: choose another --report folder")
    written = []
    for path, content in targets.items():
        if isinstance(content, dict):
            content = json.dumps(content, indent=2, allow_nan=False)
        written.append(write_atomic(path, content))
    return written
