"""``python -m kilnctl.cli``: the same command line as ``kilnctl`` and ``python -m kilnctl`` (:func:`run`)."""
from . import run

run()
