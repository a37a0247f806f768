"""Griffe extension for the API pages: show doctest examples in free text as code.

numpydoc puts examples under an ``Examples`` heading, which mkdocstrings renders
as code; a module docstring that shows ``>>>`` lines in its free text would
otherwise be read as Markdown (``>`` starts a block quote, ``[0]["x"]`` a
reference link).  This extension fences every such block (the ``>>>`` line to
the next blank line) as ``pycon`` code, leaving ``Examples`` sections and
existing fences alone.
"""

from __future__ import annotations

import re

import griffe

_HEADING = re.compile(r"^\s*-{3,}\s*$")


def fence_doctests(text: str) -> str:
    """Return ``text`` with each free-text doctest block wrapped in a pycon code fence.

    Parameters
    ----------
    text : str
        A docstring, dedented.

    Returns
    -------
    str
    """
    lines = text.split("\n")
    out: list[str] = []
    in_fence = in_examples = False
    i = 0
    while i < len(lines):
        line = lines[i]
        stripped = line.strip()
        if stripped.startswith("```"):
            in_fence = not in_fence
        nxt = lines[i + 1] if i + 1 < len(lines) else ""
        if not in_fence and stripped and _HEADING.match(nxt):
            in_examples = stripped == "Examples"
        if not in_fence and not in_examples and stripped.startswith(">>>"):
            indent = line[: len(line) - len(line.lstrip())]
            block = []
            while i < len(lines) and lines[i].strip():
                block.append(lines[i])
                i += 1
            out += [f"{indent}```pycon", *block, f"{indent}```"]
            continue
        out.append(line)
        i += 1
    return "\n".join(out)


class FenceDoctests(griffe.Extension):
    """Fence free-text doctest blocks of every docstring (see the module text)."""

    def on_instance(self, *, obj, **kwargs) -> None:
        """Rewrite the docstring of each loaded object."""
        if obj.docstring is not None:
            obj.docstring.value = fence_doctests(obj.docstring.value)
