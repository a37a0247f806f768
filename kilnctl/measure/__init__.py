"""Learn from measurements: import, compare, calibrate, diagnose the missing effect.

The loop an engineer follows when the model does not match the kiln:

1. :func:`read_csv` a measured start-up (``docs/measurements.md``);
2. :func:`compare` it with the model: fit %, residual tests, where it fails;
3. :class:`Calibration` fits chosen parameters by simulation-error least squares;
4. :class:`Diagnosis` tries each effect of the :data:`CATALOGUE` and keeps the
   ones the data support (``docs/tutorial_diagnose.md``).
"""

from .io import Experiment, Measurement, Setup, load_setup, read_csv

__all__ = ["Experiment", "Measurement", "Setup", "load_setup", "read_csv"]
