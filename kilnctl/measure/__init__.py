"""Learn from measurements: import, compare, calibrate, diagnose the missing effect.

The loop an engineer follows when the model does not match the kiln:

1. :func:`read_record` a measured start-up (CSV, Excel, Parquet, MATLAB; ``docs/measurements.md``),
   or cut several out of a long log with :func:`split_startups`;
2. :func:`compare` it with the model: fit %, residual tests, where it fails;
3. :class:`Calibration` fits chosen parameters by simulation-error least squares;
4. :class:`Diagnosis` tries each effect of the :data:`CATALOGUE` and keeps the
   ones the data support (``docs/tutorial_diagnose.md``).
"""

from .calibrate import Calibration, holdout_masks, sweep
from .compare import Comparison, compare
from .diagnose import Diagnosis
from .effects import CATALOGUE, Effect
from .io import Experiment, Measurement, Setup, load_setup, read_csv, read_record
from .split import Startups, split_startups

__all__ = ["CATALOGUE", "Calibration", "Comparison", "Diagnosis", "Effect", "Experiment", "Measurement", "Setup",
           "Startups", "compare", "holdout_masks", "load_setup", "read_csv", "read_record", "split_startups", "sweep",
           "example_paths"]


def example_paths():
    """Return the shipped example record and its setup file.

    Returns
    -------
    (Path, Path)
        ``example_record.csv`` and ``example_setup.toml`` in ``kilnctl/data``
        (a synthetic start-up; its hidden effect is named in
        ``docs/tutorial_diagnose.md``, not in the files).
    """
    from importlib import resources
    from pathlib import Path

    folder = Path(str(resources.files("kilnctl") / "data"))
    return folder / "example_record.csv", folder / "example_setup.toml"
