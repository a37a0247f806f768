"""Writing files whole or not at all, and reading TOML input with clear errors.

kilnctl never leaves a half-written output: it writes to a temporary file in
the destination folder and renames it over the destination in one step.
"""

from __future__ import annotations

import contextlib
import os
import tempfile
import tomllib
from pathlib import Path

from .errors import ConfigFileError

__all__ = ["write_atomic", "atomic_path", "read_toml"]

#: the UTF-8 byte-order mark some editors put at the start of a file
_BOM = "\ufeff"


def _umask() -> int:
    """The process umask: from /proc on Linux (no change of process state), else set and restored at once."""
    try:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("Umask:"):
                return int(line.split()[1], 8)
    except (OSError, ValueError, IndexError):
        pass
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


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

    Raises
    ------
    ConfigFileError
        The folder cannot be made or written into (a file on its path, no permission); nothing is written.
    """
    path = Path(path)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=".tmp-", suffix=path.suffix if suffix is None else suffix)
    except OSError as exc:  # a file on the folder's path, no permission, a read-only or pseudo file system
        raise ConfigFileError(f"{path}: cannot write it in {path.parent} ({exc.strerror or exc}); give a path in a "
                              "folder you may write into") from None
    os.close(fd)
    try:
        yield Path(tmp)
        # mkstemp makes the file private (0600); an output gets the mode any new file gets here (0644 under
        # the usual umask 022), like the outputs written without a temporary file
        if os.path.exists(tmp):
            os.chmod(tmp, 0o666 & ~_umask())
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


def read_toml(path, kind: str = "configuration file", error: type = ConfigFileError) -> dict:
    """Read a TOML file; every way it can fail is an ``error`` naming the file and the fix.

    Parameters
    ----------
    path : path-like
        The file.
    kind : str, default 'configuration file'
        What the file is, for the messages (``sweep spec``, ``setup file`` ...).
    error : type, default ConfigFileError
        Exception class raised (a :class:`~kilnctl.errors.ConfigFileError`).

    Returns
    -------
    dict
        The parsed document.

    Raises
    ------
    ConfigFileError
        Missing file, a folder, unreadable, not UTF-8, a UTF-8 byte-order
        mark, or not TOML (with the line and column).
    """
    path = Path(path)
    try:
        data = path.read_bytes()
    except FileNotFoundError:
        raise error(f"{path}: no such {kind}") from None
    except IsADirectoryError:
        raise error(f"{path} is a folder, not a {kind}: give the file itself") from None
    except OSError as exc:
        raise error(f"{path}: cannot read the {kind} ({exc.strerror or exc})") from None
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise error(f"{path}: the {kind} is not UTF-8 text (byte {exc.start}); save it as UTF-8") from None
    if text.startswith(_BOM):
        raise error(f"{path}: the {kind} starts with a UTF-8 byte-order mark (BOM), which TOML does not allow; "
                    "save it as UTF-8 without BOM (in Notepad: 'UTF-8', not 'UTF-8 with BOM')")
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise error(f"{path}: not a valid TOML {kind} ({exc}); see docs/quickstart.md for the format") from None
