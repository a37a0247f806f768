"""Help texts, unknown options and --version of the `kilnctl` command, run as a user would (a subprocess)."""

import os
import subprocess
import sys
from pathlib import Path

import pytest

import kilnctl
from kilnctl.cli import build_parser

ROOT = Path(__file__).resolve().parents[1]


def _run(*argv, module="kilnctl.cli"):
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    return subprocess.run([sys.executable, "-m", module, *argv], capture_output=True, text=True,
                          env=env, timeout=120)


def _subcommands():
    sub = next(a for a in build_parser()._actions if a.choices and "params" in a.choices)
    return sub.choices


def test_every_subcommand_help_has_a_description_and_no_doubled_percent():
    # truth: argparse prints a description verbatim, so a '%%' written there reaches the user as '%%'
    # (it is only collapsed in option help); every subcommand must say what it does beyond the one-line help
    subs = _subcommands()
    assert {"params", "verify", "compare", "optimize-ramp", "sweep"} <= set(subs)
    for name, p in subs.items():
        text = p.format_help()
        assert "%%" not in text, f"kilnctl {name} --help shows a literal %%"
        assert p.description and len(p.description) > 60, f"kilnctl {name} has no description"


def test_compare_and_optimize_help_show_single_percent():
    out = _run("compare", "--help").stdout
    assert "fit % per channel" in out and "%%" not in out
    out = _run("optimize-ramp", "--help").stdout
    assert "95 % of its set point" in out and "%%" not in out


@pytest.mark.parametrize("argv, usage", [
    (["sweep", "spec.toml", "--treshold", "200"], "usage: kilnctl sweep"),
    (["params", "--jsn"], "usage: kilnctl params"),
    (["design", "--zeta", "0.7", "--bogus"], "usage: kilnctl design"),
])
def test_unknown_option_shows_the_subcommand_usage(argv, usage):
    r = _run(*argv)
    assert r.returncode == 2
    assert usage in r.stderr and "unrecognized arguments: " + argv[-1 if argv[-1].startswith("-") else -2] in r.stderr
    assert "usage: kilnctl [-h]" not in r.stderr and "Traceback" not in r.stderr
    assert f"see kilnctl {argv[0]} --help" in r.stderr


@pytest.mark.parametrize("module", ["kilnctl.cli", "kilnctl"])
def test_version_is_the_package_version(module):
    # `python -m kilnctl` is what a user tries without the console script on PATH (it said "No module named
    # kilnctl.__main__"); both entry points are the same command
    r = _run("--version", module=module)
    assert r.returncode == 0 and r.stdout.strip() == f"kilnctl {kilnctl.__version__}"
