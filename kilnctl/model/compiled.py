"""Compile CasADi functions to C once, and cache the shared library on disk.

CasADi's code generator writes C for a function; gcc turns it into a shared
library that :func:`casadi.external` loads.  The library is named by a hash of
the generated source, so a model structure compiled once is reused by every
later run (and every later session on the same machine).  Without a C
compiler the function is used as it is (CasADi's virtual machine), which is
slower but gives the same numbers.

The cache folder is ``$KILNCTL_CACHE`` or ``~/.cache/kilnctl``.
"""

from __future__ import annotations

import functools
import hashlib
import os
import platform
import shutil
import subprocess
import tempfile
import warnings
from pathlib import Path

import casadi as ca

__all__ = ["compile_function", "cache_dir", "compiler_available", "toolchain_id"]

_CC = shutil.which(os.environ.get("CC", "gcc")) or shutil.which("cc")


def cache_dir() -> Path:
    """Folder of compiled model libraries (created on demand)."""
    return Path(os.environ.get("KILNCTL_CACHE", Path.home() / ".cache" / "kilnctl"))


def compiler_available() -> bool:
    """True when a C compiler was found (``$CC``, ``gcc`` or ``cc``) and ``KILNCTL_NO_COMPILE`` is unset."""
    return _CC is not None and not os.environ.get("KILNCTL_NO_COMPILE")


@functools.lru_cache(maxsize=1)
def toolchain_id() -> str:
    """Compiler identity and target (first line of ``$CC --version``, machine, OS), part of the cache key.

    A library built by another compiler or for another architecture (a cache
    folder shared between machines) is then never picked up by mistake.
    """
    try:
        ver = subprocess.run([_CC, "--version"], capture_output=True, timeout=30).stdout.decode(errors="replace")
        first = ver.splitlines()[0] if ver else "unknown"
    except (OSError, subprocess.SubprocessError, TypeError):
        first = "unknown"
    return f"{_CC}|{first}|{platform.machine()}|{platform.system()}"


def compile_sources(stem: str, sources: dict[str, bytes]) -> Path | None:
    """Compile C sources into a shared library in the cache, named by their hash.

    Parameters
    ----------
    stem : str
        Start of the library file name.
    sources : dict of str to bytes
        File name -> C source.

    Returns
    -------
    Path or None
        The library, or None without a compiler or when compiling fails.
    """
    if not compiler_available():
        return None
    h = hashlib.sha256(b"|O2|" + toolchain_id().encode() + b"|")
    for name in sorted(sources):
        h.update(name.encode() + b"\0" + sources[name])
    folder = cache_dir()
    lib = folder / f"{stem}_{h.hexdigest()[:20]}.so"
    if lib.exists():
        return lib
    try:
        folder.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryDirectory() as tmp:
            paths = []
            for name, text in sources.items():
                p = Path(tmp) / name
                p.write_bytes(text)
                paths.append(str(p))
            tmp_lib = Path(tmp) / "lib.so"
            proc = subprocess.run([_CC, "-O2", "-fPIC", "-shared", *paths, "-o", str(tmp_lib), "-lm"],
                                  capture_output=True, timeout=300)
            if proc.returncode != 0:
                warnings.warn(f"kilnctl: compiling {stem} failed, falling back to the slower uncompiled path: "
                              + proc.stderr.decode(errors="replace")[:800], RuntimeWarning, stacklevel=2)
                return None
            fd, staged = tempfile.mkstemp(dir=folder, suffix=".so.tmp")
            os.close(fd)
            shutil.copyfile(tmp_lib, staged)
            os.replace(staged, lib)  # whole or not at all, safe against a parallel build
    except (OSError, subprocess.SubprocessError):
        return None
    return lib


def generate_c(functions, name: str = "gen") -> bytes:
    """C source of CasADi functions (one translation unit, no header).

    Parameters
    ----------
    functions : sequence of casadi.Function
    name : str
        Base file name used by the generator.

    Returns
    -------
    bytes
    """
    with tempfile.TemporaryDirectory() as tmp:
        cg = ca.CodeGenerator(f"{name}.c", {"with_header": False})
        for f in functions:
            cg.add(f)
        cg.generate(tmp + os.sep)
        return (Path(tmp) / f"{name}.c").read_bytes()


def compile_function(f: ca.Function) -> tuple[ca.Function, bool]:
    """Return a compiled equivalent of ``f`` and whether compiling worked.

    Parameters
    ----------
    f : casadi.Function
        An SX or MX function without external plugins (no integrators).

    Returns
    -------
    casadi.Function
        The loaded shared library, or ``f`` itself if compiling failed.
    bool
        True if the compiled library is used.
    """
    lib = compile_sources(f.name(), {f"{f.name()}.c": generate_c([f], f.name())})
    if lib is None:
        return f, False
    try:
        return ca.external(f.name(), str(lib)), True
    except RuntimeError:
        return f, False
