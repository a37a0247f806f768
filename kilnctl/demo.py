"""The main job behind ``make demo``: parameters, design, verification, figures.

Run as ``python -m kilnctl.demo --out DIR``.  Each step writes its files into
``DIR``; later issues add steps.
"""

from __future__ import annotations

import argparse
import sys

from .params import Parameters


def main(argv=None) -> int:
    """Run the demonstration job.

    Parameters
    ----------
    argv : list of str, optional
        Command-line arguments (``--out DIR``).

    Returns
    -------
    int
        Exit code.
    """
    ap = argparse.ArgumentParser(prog="python -m kilnctl.demo")
    ap.add_argument("--out", default="out", help="output folder (created)")
    args = ap.parse_args(argv)
    from pathlib import Path

    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    params = Parameters()
    print(f"kiln drive: J_stick = {params.J_stick:.2f} kg*m^2, J_slip = {params.J_slip:.2f} kg*m^2 at the motor")
    return 0


if __name__ == "__main__":
    sys.exit(main())
