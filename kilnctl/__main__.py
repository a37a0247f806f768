"""``python -m kilnctl``: the ``kilnctl`` command line (:func:`kilnctl.cli.run`)."""
from .cli import run

run()
