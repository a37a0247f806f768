"""Tables from the plant: CSV, Excel, Parquet and MATLAB files, units in headers, column mappings.

This module turns a file exported by a plant historian or a drive's trace tool
into a :class:`RawTable` (column names as written, cells as read, and where each
row came from, for messages), and says what a column name means:

* :func:`split_unit` reads a unit written in the header, ``I_arm [A]`` or
  ``n_mot (1/min)``;
* :func:`convert` scales a channel to kilnctl's unit (s, A, rpm);
* :func:`parse_columns` reads a mapping ``current_A=I_arm,time_s=t [ms]`` from
  the command line (``--columns``) or the setup file (``[measurement] columns``).

:func:`kilnctl.measure.io.read_record` puts them together.  Files are only read.
"""

from __future__ import annotations

import csv
import math
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import ConfigFileError, DataError, close_matches_hint

__all__ = ["RawTable", "UNITS", "FORMATS", "split_unit", "convert", "parse_columns", "read_table"]

#: kilnctl's channels and the quantity each holds
QUANTITY = {"time_s": "time", "current_A": "current", "speed_rpm": "speed", "speed_ref_rpm": "speed"}

#: units understood in headers, per quantity: unit (lower case) -> factor to kilnctl's unit (s, A, rpm)
UNITS: dict[str, dict[str, float]] = {
    "time": {"s": 1.0, "sec": 1.0, "ms": 1e-3, "us": 1e-6, "µs": 1e-6, "min": 60.0, "h": 3600.0, "d": 86400.0},
    "current": {"a": 1.0, "ka": 1e3, "ma": 1e-3},
    "speed": {"rpm": 1.0, "1/min": 1.0, "min^-1": 1.0, "min-1": 1.0, "u/min": 1.0, "r/min": 1.0,
              "rev/min": 1.0, "rad/s": 60.0 / (2.0 * math.pi), "rev/s": 60.0, "r/s": 60.0, "rps": 60.0},
}
#: what each quantity is converted to
TARGET = {"time": "s", "current": "A", "speed": "rpm"}
#: units refused because they mean two things
AMBIGUOUS = {"1/s": "rev/s or rad/s: write [rev/s] or [rad/s]", "%": "per cent of what? convert to rpm or A"}

#: file formats by suffix
FORMATS = {".csv": "csv", ".txt": "csv", ".tsv": "csv", ".xlsx": "excel", ".xlsm": "excel", ".parquet": "parquet",
           ".pq": "parquet", ".mat": "matlab"}

_UNIT_RE = re.compile(r"^(?P<base>.*?)\s*(?:\[(?P<b>[^\[\]]*)\]|\((?P<p>[^()]*)\))\s*$")


def _quantity_of_unit(unit: str) -> str | None:
    u = unit.strip().lower()
    for q, table in UNITS.items():
        if u in table:
            return q
    return None


def split_unit(name: str) -> tuple[str, str | None]:
    """Split a column name into its base name and the unit written after it.

    ``I_arm [A]`` -> (``I_arm``, ``A``); ``n_mot (1/min)`` -> (``n_mot``,
    ``1/min``).  Parentheses count as a unit only when they hold one kilnctl
    knows (``speed (motor)`` stays a name); brackets always do.

    Parameters
    ----------
    name : str
        A column name as written in the file.

    Returns
    -------
    tuple of (str, str or None)
        The base name and the unit (None when none is written).
    """
    m = _UNIT_RE.match(name.strip())
    if not m or not m.group("base"):
        return name.strip(), None
    if m.group("b") is not None:
        return m.group("base"), m.group("b").strip()
    unit = m.group("p").strip()
    if _quantity_of_unit(unit) or unit.lower() in AMBIGUOUS:
        return m.group("base"), unit
    return name.strip(), None


def convert(values: np.ndarray, unit: str | None, channel: str, where: str) -> tuple[np.ndarray, str | None]:
    """Convert a channel to kilnctl's unit.

    Parameters
    ----------
    values : ndarray
        The channel as read [its unit].
    unit : str or None
        The unit written in the header or the mapping; None: already kilnctl's.
    channel : str
        kilnctl's channel (``time_s``, ``current_A``, ``speed_rpm``, ``speed_ref_rpm``).
    where : str
        File and column, for messages.

    Returns
    -------
    values : ndarray
        The channel in s, A or rpm.
    note : str or None
        What was converted, for the record's notes.

    Raises
    ------
    DataError
        The unit is unknown, ambiguous, or of another quantity (a current unit on the speed).
    """
    if unit is None:
        return values, None
    q = QUANTITY[channel]
    u = unit.strip().lower()
    if u in AMBIGUOUS:
        raise DataError(f"{where}: unit [{unit}] is ambiguous ({AMBIGUOUS[u]})")
    if u not in UNITS[q]:
        other = _quantity_of_unit(u)
        if other:
            raise DataError(f"{where}: unit [{unit}] is a {other} unit, but the column is read as {channel} "
                            f"(a {q}); check the column mapping (--columns or [measurement] columns)")
        raise DataError(f"{where}: unknown {q} unit [{unit}]; kilnctl understands "
                        + ", ".join(sorted({k for k in UNITS[q] if k.isascii()})))
    factor = UNITS[q][u]
    if factor == 1.0:
        return values, None
    return values * factor, f"{channel} converted from {unit} to {TARGET[q]} (x {factor:.6g})"


def parse_columns(text, source: str = "--columns") -> dict[str, str]:
    """Read a column mapping: kilnctl channel -> column name in the file (optionally with a unit).

    Parameters
    ----------
    text : str or mapping or None
        ``current_A=I_arm,speed_rpm=n_mot,time_s=t [ms]`` (command line) or a
        TOML table ``{current_A = "I_arm", ...}`` (setup file).
    source : str, default '--columns'
        Where it came from, for messages.

    Returns
    -------
    dict of str to str
        Channel -> column name; empty for None or an empty string.

    Raises
    ------
    ConfigFileError
        An unknown channel (with close matches), an item without ``=``, an
        empty name, a channel given twice.
    """
    if text is None:
        return {}
    if isinstance(text, dict):
        items = list(text.items())
        for k, v in items:
            if not isinstance(v, str):
                raise ConfigFileError(f"{source}: {k} = {v!r} must be a column name in quotes, e.g. {k} = \"I_arm\"")
    else:
        if not str(text).strip():
            return {}
        items = []
        for part in str(text).split(","):
            if "=" not in part:
                raise ConfigFileError(f"{source} {text!r}: item {part.strip()!r} has no '=': write CHANNEL=COLUMN, "
                                      "e.g. current_A=I_arm,speed_rpm=n_mot,time_s=t")
            k, v = part.split("=", 1)
            items.append((k.strip(), v.strip()))
    out: dict[str, str] = {}
    for k, v in items:
        if k not in QUANTITY:
            raise ConfigFileError(f"{source}: unknown channel {k!r}: {close_matches_hint(k, QUANTITY)} "
                                  "(the left side is kilnctl's channel, the right side your column)")
        if not v:
            raise ConfigFileError(f"{source}: {k}= has no column name")
        if k in out:
            raise ConfigFileError(f"{source}: channel {k!r} is mapped twice")
        out[k] = v
    return out


@dataclass
class RawTable:
    """A table as read from a file, before any channel is interpreted.

    Attributes
    ----------
    names : list of str
        Column names as written.
    columns : list of ndarray
        One array per column: float, datetime64, or object (cells as read:
        numbers, strings, datetimes, None).  A MATLAB file may give columns of
        different lengths.
    rows : ndarray of int
        Where each sample is in the file (line, row or sample number).
    row_word : str
        ``line`` (text), ``row`` (spreadsheet, Parquet) or ``sample`` (MATLAB).
    source : str
        The file.
    header : str
        Where the header is, for messages (``line 3 (header)``; empty when
        the names are not on a line or row: Parquet, MATLAB).
    notes : list of str
        Remarks made while reading.
    decimal_clash : str
        Why decimal commas were not read (a cell with a decimal point elsewhere), for the message of a cell
        that is then not a number; empty otherwise.
    """

    names: list
    columns: list
    rows: np.ndarray
    row_word: str
    source: str
    header: str
    notes: list = field(default_factory=list)
    decimal_clash: str = ""

    def where(self, k: int, column: str | None = None) -> str:
        """Return ``file: line N, column 'X'`` for sample ``k``.

        Parameters
        ----------
        k : int
            Sample index (0-based).
        column : str, optional
            Column name as written.

        Returns
        -------
        str
        """
        s = f"{self.source}: {self.row_word} {int(self.rows[min(k, len(self.rows) - 1)])}"
        return s + (f", column {column!r}" if column else "")


def read_table(path, kind: str | None = None) -> RawTable:
    """Read a record file of any supported format into a :class:`RawTable`.

    Parameters
    ----------
    path : path-like
        ``.csv``/``.txt``/``.tsv`` (text), ``.xlsx``/``.xlsm`` (first sheet;
        openpyxl), ``.parquet`` (pyarrow) or ``.mat`` (MATLAB v4-v7; scipy).
    kind : {"csv", "excel", "parquet", "matlab"}, optional
        The format; by default from the suffix (text for an unknown one).

    Returns
    -------
    RawTable

    Raises
    ------
    DataError
        The file is missing, a folder, of an unknown or unreadable format, or
        needs a library that is not installed (the message says which).
    """
    path = Path(path)
    if path.is_dir():
        raise DataError(f"{path}: is a folder, not a measurement file")
    if not path.exists():
        raise DataError(f"{path}: no such measurement file")
    kind = kind or FORMATS.get(path.suffix.lower(), "csv")
    return {"csv": _read_text, "excel": _read_excel, "parquet": _read_parquet, "matlab": _read_mat}[kind](path)


def _refuse_unknown_separator(path, lineno: int, header: str) -> None:
    """Refuse a header read as one column that another separator splits into several (``|``, spaces).

    A record needs at least three columns, so a one-column header is never a record; the missing-column
    message that followed ("missing column 'time_s'; the header has time_s|current_A|speed_rpm") did not say why.
    """
    for sep, shown, fix in (("|", "'|'", "or write a first line 'sep=|'"), (":", "':'", "or write a first line 'sep=:'"),
                            (None, "spaces", "")):
        parts = [p for p in (header.split(sep) if sep else header.split()) if p.strip()]
        if len(parts) >= 3:
            raise DataError(f"{path}: line {lineno} (header): read as one column {header!r}: its columns look "
                            f"separated by {shown}, but kilnctl reads columns separated by a comma, a semicolon or "
                            f"a tab; save the file with one of those{(' ' + fix) if fix else ''}")


#: the first line Excel writes (and reads) to name a CSV file's separator: ``sep=;``
_SEP_LINE = re.compile(r'^"?sep=(.)"?$', re.IGNORECASE)
_DECIMAL_COMMA = re.compile(r"^[+-]?\d+,\d*(?:[eE][+-]?\d+)?$")


def _unit_cell(cell: str) -> str | None:
    """A cell of a units row under the header: ``s``, ``[A]``, ``(1/min)`` -> the unit; None if it is not one."""
    u = cell.strip()
    if len(u) >= 2 and u[0] + u[-1] in ("[]", "()"):
        u = u[1:-1].strip()
    return u if (_quantity_of_unit(u) or u.lower() in AMBIGUOUS) else None


def _read_text(path: Path) -> RawTable:
    raw = path.read_bytes()
    notes = []
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        if b"\x00" in raw:
            raise DataError(f"{path}: not a text file ({exc.reason} at byte {exc.start}); export it as UTF-8 CSV, "
                            "or give the .xlsx/.parquet/.mat file itself") from None
        # exports of Windows tools are often Windows-1252 (a degree sign, an umlaut in a name): read so, and say so
        text = raw.decode("cp1252", errors="replace")
        notes.append(f"not UTF-8 ({exc.reason} at byte {exc.start}): read as Windows-1252")
    header = None
    cells: list[list[str]] = []
    lines: list[int] = []
    delim, forced = ",", None
    units_line = None
    for lineno, line in enumerate(text.splitlines(), start=1):
        s = line.strip()
        if not s or s.startswith("#"):
            continue
        sep = _SEP_LINE.match(line.strip(" \r\n")) if header is None else None
        if sep:  # Excel's separator line ('sep=;') before the header
            delim = forced = sep.group(1)
            continue
        if header is None:
            if not forced:
                delim = ";" if (";" in s and "," not in s) else ("\t" if ("\t" in s and "," not in s) else ",")
            names = [h.strip() for h in next(csv.reader([s], delimiter=delim))]
            while len(names) > 1 and not names[-1]:  # a trailing separator: an empty last column
                names.pop()
            if len(names) == 1 and not forced:
                _refuse_unknown_separator(path, lineno, s)
            header = (lineno, names)
            continue
        row = [c.strip() for c in next(csv.reader([s], delimiter=delim))]
        while len(row) > len(header[1]) and not row[-1]:
            row.pop()
        if not cells and units_line is None and any(row) and all(_unit_cell(c) or not c for c in row) \
                and len(row) == len(header[1]):
            # a units row under the header (``s;A;rpm``): the units join the names, as ``Time [s]``
            units_line = lineno
            header = (header[0], [f"{nm} [{_unit_cell(u)}]" if u and split_unit(nm)[1] is None else nm
                                  for nm, u in zip(header[1], row)])
            notes.append(f"units read from line {lineno} (under the header)")
            continue
        if len(row) != len(header[1]):
            raise DataError(f"{path}: line {lineno}: {len(row)} cells, but the header (line {header[0]}) "
                            f"has {len(header[1])} columns")
        cells.append(row)
        lines.append(lineno)
    if header is None:
        raise DataError(f"{path}: empty file (no header line with time_s, current_A, speed_rpm)")
    hline, names = header
    if not cells:
        raise DataError(f"{path}: no data rows after the header (line {hline})")
    arr = np.array(cells, dtype=object)
    clash = ""
    if delim != ",":
        # decimal commas (``1,5``) in a file separated by ';' or tabs, where a comma can mean nothing else;
        # only when no cell of the file has a decimal point, so a file never mixes both readings
        flat = [c for r in cells for c in r]
        if any(_DECIMAL_COMMA.match(c) for c in flat):
            point = next(((k, j) for k, r in enumerate(cells) for j, c in enumerate(r) if "." in c and _is_number(c)),
                         None)
            if point is None:
                arr = np.array([[c.replace(",", ".") if _DECIMAL_COMMA.match(c) else c for c in r] for r in cells],
                               dtype=object)
                notes.append("decimal commas read as decimal points (a ';'- or tab-separated file)")
            else:
                k, j = point
                clash = (f"decimal commas are not read, because line {lines[k]}, column {names[j]!r} has a decimal "
                         f"point ({cells[k][j]!r}): give every number of the file with one decimal sign")
    head = f"line {hline} (header)" + (f" and {units_line} (units)" if units_line else "")
    return RawTable(names, [arr[:, j] for j in range(len(names))], np.array(lines), "line", str(path), head, notes,
                    clash)


def _is_number(c: str) -> bool:
    try:
        float(c)
        return True
    except ValueError:
        return False


def _need(module: str, extra: str, path: Path):
    import importlib

    try:
        return importlib.import_module(module)
    except ImportError:
        raise DataError(f"{path}: reading {path.suffix} files needs the Python package {extra!r}, which is not "
                        f"installed: pip install 'kilnctl[plant]' (or pip install {extra})") from None


def _read_excel(path: Path) -> RawTable:
    _need("openpyxl", "openpyxl", path)
    pd = _need("pandas", "pandas", path)

    try:
        book = pd.ExcelFile(path, engine="openpyxl")
        sheet = book.sheet_names[0]
        df = pd.read_excel(book, sheet_name=sheet, header=None, dtype=object)
    except Exception as exc:  # openpyxl raises many types on a damaged file
        raise DataError(f"{path}: not a readable Excel workbook ({type(exc).__name__}: {exc})") from None
    notes = []
    if len(book.sheet_names) > 1:
        notes.append(f"read the first sheet {sheet!r} of {len(book.sheet_names)} "
                     f"({', '.join(map(repr, book.sheet_names[1:]))} not read)")
    values = df.to_numpy(dtype=object)

    def empty(c):
        return c is None or (isinstance(c, float) and math.isnan(c)) or (isinstance(c, str) and not c.strip())

    hrow = None
    for i in range(values.shape[0]):
        row = values[i]
        if all(empty(c) for c in row):
            continue
        first = next(c for c in row if not empty(c))
        if isinstance(first, str) and first.strip().startswith("#"):
            continue
        hrow = i
        break
    src = f"{path} (sheet {sheet!r})"
    if hrow is None:
        raise DataError(f"{src}: empty sheet (no header row with time_s, current_A, speed_rpm)")
    used = [j for j in range(values.shape[1]) if not empty(values[hrow, j])]
    names = [str(values[hrow, j]).strip() for j in used]
    body = [i for i in range(hrow + 1, values.shape[0]) if not all(empty(c) for c in values[i])]
    if not body:
        raise DataError(f"{src}: no data rows after the header (row {hrow + 1})")
    cols = [np.array([None if empty(values[i, j]) else values[i, j] for i in body], dtype=object) for j in used]
    return RawTable(names, cols, np.array(body) + 1, "row", src, f"row {hrow + 1} (header)", notes)


def _read_parquet(path: Path) -> RawTable:
    _need("pyarrow", "pyarrow", path)
    pd = _need("pandas", "pandas", path)

    try:
        df = pd.read_parquet(path, engine="pyarrow")
    except Exception as exc:  # pyarrow raises ArrowInvalid, OSError ... on a damaged file
        raise DataError(f"{path}: not a readable Parquet file ({type(exc).__name__}: {exc})") from None
    if df.shape[0] == 0:
        raise DataError(f"{path}: no data rows")
    names = [str(c) for c in df.columns]
    cols, notes = [], []
    for c in df.columns:
        s = df[c]
        if pd.api.types.is_datetime64_any_dtype(s.dtype):
            if getattr(s.dt, "tz", None) is not None:  # compare instants in UTC
                s = s.dt.tz_convert("UTC").dt.tz_localize(None)
                notes.append(f"column {str(c)!r}: timestamps with a time zone, read in UTC")
            cols.append(s.to_numpy(dtype="datetime64[ns]"))
        elif pd.api.types.is_numeric_dtype(s.dtype) and not pd.api.types.is_bool_dtype(s.dtype):
            cols.append(s.to_numpy(dtype=float, na_value=np.nan))
        else:
            cols.append(s.to_numpy(dtype=object))
    return RawTable(names, cols, np.arange(df.shape[0]) + 1, "row", str(path), "", notes)


def _read_mat(path: Path) -> RawTable:
    import scipy.io

    try:
        data = scipy.io.loadmat(path, simplify_cells=True)
    except NotImplementedError:
        raise DataError(f"{path}: a MATLAB v7.3 (HDF5) file, which kilnctl cannot read: in MATLAB save it with "
                        "save(FILE, ..., '-v7') or export a CSV") from None
    except Exception as exc:  # scipy raises ValueError, TypeError ... on a damaged file
        raise DataError(f"{path}: not a readable MATLAB .mat file ({type(exc).__name__}: {exc})") from None
    found: dict[str, np.ndarray] = {}

    def take(prefix, obj):
        if isinstance(obj, dict):
            for k, v in obj.items():
                take(f"{prefix}{k}.", v)
            return
        a = np.asarray(obj)
        if a.dtype.kind in "iufb" and a.ndim >= 1 and a.size > 1 and max(a.shape) == a.size:
            found[prefix[:-1]] = a.ravel().astype(float)

    structs = [k for k in data if not k.startswith("__")]
    for k in structs:
        take(f"{k}.", data[k])
    # fields of a single struct are named without its prefix: rec.t -> t
    if len(structs) == 1 and isinstance(data[structs[0]], dict):
        found = {k.split(".", 1)[1]: v for k, v in found.items()}
    if not found:
        raise DataError(f"{path}: no numeric vector in the file; kilnctl reads one variable per channel (vectors "
                        "of equal length, e.g. t, I_arm, n_mot) or one struct whose fields are such vectors")
    n = max(v.size for v in found.values())
    return RawTable(list(found), list(found.values()), np.arange(n) + 1, "sample", str(path), "")
