"""The shipped example, diagnosed end to end (the last step of ``make demo``)."""

from __future__ import annotations

from pathlib import Path

__all__ = ["diagnose_example"]


def diagnose_example(out, progress=print) -> dict:
    """Diagnose the shipped example record and write the report.

    Parameters
    ----------
    out : path-like
        Folder; the report goes to ``out/diagnose`` (``diagnose.html`` and more).
    progress : callable or None, default print
        Receives one line per step.

    Returns
    -------
    dict
        The diagnosis as JSON-ready data (see :meth:`Diagnosis.to_dict`).
    """
    from . import Diagnosis, example_paths, load_setup, read_csv

    rec_path, setup_path = example_paths()
    setup = load_setup(setup_path)
    rec = read_csv(rec_path, setup.params)
    d = Diagnosis(setup.params, setup.options.get("calibrate", ("mu_c", "mu_s", "m_v"))).fit(rec, progress=progress)
    files = d.report(Path(out) / "diagnose", protect=(rec_path, setup_path))
    if progress:
        progress(d.headline())
        progress(f"report: {files[0]}")
    return d.to_dict()
