"""The shipped example, diagnosed end to end (the last step of ``make demo``)."""

from __future__ import annotations

from pathlib import Path

__all__ = ["diagnose_example"]


def diagnose_example(out, progress=print, workers: int = 2) -> dict:
    """Diagnose the shipped example record and write the report.

    Parameters
    ----------
    out : path-like
        Folder; the report goes to ``out/diagnose`` (``diagnose.html`` and more).
    progress : callable or None, default print
        Receives one line per step.
    workers : int, default 2
        Processes refitting the candidates (see :class:`Diagnosis`).

    Returns
    -------
    dict
        The diagnosis as JSON-ready data (see :meth:`Diagnosis.to_dict`).
    """
    from . import Diagnosis, example_paths, load_setup, read_csv
    from .effects import DEFAULT_CALIBRATE

    rec_path, setup_path = example_paths()
    setup = load_setup(setup_path)
    rec = read_csv(rec_path, setup.params)
    d = Diagnosis(setup.params, setup.options.get("calibrate", DEFAULT_CALIBRATE), workers=workers).fit(
        rec, progress=progress)
    files = d.report(Path(out) / "diagnose", protect=(rec_path, setup_path))
    if progress:
        progress(d.headline())
        for note in d.caveats_:
            progress("caution: " + note)
        progress(f"report: {files[0]}")
    return d.to_dict()
