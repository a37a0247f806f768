"""``python -m kilnctl``: the ``kilnctl`` command line (:func:`kilnctl.cli.main`)."""
import sys

from .cli import main

sys.exit(main())
