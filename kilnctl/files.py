"""Writing files whole or not at all.

kilnctl never leaves a half-written output: it writes to a temporary file in
the destination folder and renames it over the destination in one step.
"""

from __future__ import annotations

import contextlib
import os
import tempfile
from pathlib import Path

__all__ = ["write_atomic", "atomic_path"]


@contextlib.contextmanager
def atomic_path(path, suffix: str | None = None):
    """Yield a temporary path beside ``path``; rename it to ``path`` if the block succeeds.

    Parameters
    ----------
    path : path-like
        Destination (its folder is created).
    suffix : str, optional
        Suffix of the temporary file (default: that of ``path``), for writers
        that pick the format from it.

    Yields
    ------
    pathlib.Path
        Where to write.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=".tmp-", suffix=path.suffix if suffix is None else suffix)
    os.close(fd)
    try:
        yield Path(tmp)
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def write_atomic(path, data: bytes | str) -> Path:
    """Write ``data`` to ``path`` whole or not at all.

    Parameters
    ----------
    path : path-like
        Destination.
    data : bytes or str
        Content (str is written as UTF-8).

    Returns
    -------
    pathlib.Path
    """
    with atomic_path(path) as tmp:
        tmp.write_bytes(data.encode() if isinstance(data, str) else data)
    return Path(path)
