"""`kilnctl sweep SPEC.toml`: spec errors, written files, interruption and resume.

Runs through ``kilnctl.cli.main`` once the command is registered there, and
through the module's own ``register``/``run`` (with main's error handling)
until then.
"""

import argparse
import csv
import json
import math

import pytest

import kilnctl.sweep.engine as engine
from kilnctl import Parameters
from kilnctl.cli import COMMANDS, main, sweep_cmd
from kilnctl.errors import KilnctlError


def cli(argv) -> int:
    """Run ``kilnctl ARGV``; exit code as the command line gives it."""
    if "sweep_cmd" in COMMANDS:
        return main(argv)
    parser = argparse.ArgumentParser(prog="kilnctl")
    sweep_cmd.register(parser.add_subparsers(dest="command", required=True))
    args = parser.parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except KilnctlError as exc:
        import sys

        print(f"kilnctl {args.command}: error: {exc}", file=sys.stderr)
        return 2


SPEC = """
model = "macro"
t_end = 40.0
outputs = ["final_current_A", "peak_stress_Pa"]

[parameters.m_v]
min = 300e3
max = 900e3
num = 3
"""


def _write(tmp_path, text, name="spec.toml"):
    p = tmp_path / name
    p.write_text(text)
    return p


def test_sweep_writes_table_and_plot_and_prints_the_summary(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    spec = _write(tmp_path, SPEC)
    out, fig = tmp_path / "res.csv", tmp_path / "res.png"
    assert cli(["sweep", str(spec), "--executor", "serial", "--out", str(out), "--plot", str(fig), "--quiet"]) == 0
    text = capsys.readouterr().out
    assert "3 points: 3 computed" in text and "max" in text
    rows = list(csv.DictReader(out.open()))
    assert [float(r["m_v"]) for r in rows] == [300e3, 600e3, 900e3]
    # truth: Lewis stress of the sliding-equilibrium torque, sigma = T / R_o / (b m Y) (hand calculation),
    # which scales with m_v; the peak of a start-up is at least the running value
    for r in rows:
        p = Parameters(m_v=float(r["m_v"]))
        psi = math.atan(p.mu_c * p.R / p.L)
        sigma = (p.m_v * p.g * p.L * math.sin(psi) + p.T_brg) / p.R_o / (p.face_width * p.module * p.Y_lewis)
        assert float(r["peak_stress_Pa"]) >= 0.99 * sigma
    assert fig.stat().st_size > 10_000
    # second run: everything from the default cache in the current folder
    assert cli(["sweep", str(spec), "--executor", "serial", "--json", "--quiet"]) == 0
    s = json.loads(capsys.readouterr().out)
    assert s["info"]["n_cached"] == 3 and s["info"]["n_computed"] == 0
    assert s["peak_stress_Pa"]["argmax"] == {"m_v": 900e3}


def test_interrupted_sweep_writes_nothing_and_resumes(tmp_path, capsys, monkeypatch):
    spec = _write(tmp_path, SPEC)
    out, cache = tmp_path / "res.csv", tmp_path / "cache"
    calls = []
    real = engine.simulate

    def flaky(*a, **kw):
        calls.append(1)
        if len(calls) == 2:
            raise KeyboardInterrupt
        return real(*a, **kw)

    monkeypatch.setattr(engine, "simulate", flaky)
    argv = ["sweep", str(spec), "--executor", "serial", "--out", str(out), "--cache", str(cache), "--quiet"]
    assert cli(argv) == 130
    assert not out.exists()  # whole or nothing
    assert "run again to resume" in capsys.readouterr().err
    assert cli(argv) == 0
    assert len(calls) == 4  # 2 before the interruption (one finished), then the 2 missing points
    assert "1 from the cache" in capsys.readouterr().out
    assert len(list(csv.DictReader(out.open()))) == 3


def test_threshold_prints_the_exceedance(tmp_path, capsys):
    spec = _write(tmp_path, SPEC.replace('["final_current_A", "peak_stress_Pa"]', '["peak_stress_Pa"]'))
    assert cli(["sweep", str(spec), "--executor", "serial", "--no-cache", "--threshold", "150", "--quiet"]) == 0
    assert "above 150.0 MPa: 1 of 3 points" in capsys.readouterr().out  # only 900 t exceeds (stress ~ m_v)


def test_threshold_in_pa_is_refused_with_the_mpa_value(tmp_path, capsys):
    # kilnctl 0.1 took --threshold in Pa: 150e6 now means 150e6 MPa; the message gives the MPa value instead
    spec = _write(tmp_path, SPEC.replace('["final_current_A", "peak_stress_Pa"]', '["peak_stress_Pa"]'))
    assert cli(["sweep", str(spec), "--executor", "serial", "--no-cache", "--threshold", "150e6", "--quiet"]) == 2
    assert "give --threshold 150 if you meant 1.5e+08 Pa" in capsys.readouterr().err


@pytest.mark.parametrize("body, message", [
    (SPEC.replace("[parameters.m_v]", "[parameters.m_vv]"), "did you mean 'm_v'"),
    (SPEC.replace("max = 900e3", "max = 100e3"), "empty range"),
    (SPEC.replace("num = 3", "num = 0"), "num = 0"),
    ('method = "montecaro"\nn = 5\n' + SPEC, "did you mean 'montecarlo'"),
    ('method = "lhs"\n' + SPEC, "needs n"),
    ('seeds = 3\n' + SPEC, "unknown key 'seeds': did you mean 'seed'"),
    (SPEC + 'nun = 3\n', "[parameters.m_v]: unknown key 'nun'"),
    (SPEC.replace('outputs = ["final_current_A", "peak_stress_Pa"]', 'outputs = ["peak_stress"]'),
     "did you mean 'peak_stress_Pa'"),
    ('method = "montecarlo"\nn = 4\n[parameters.mu_c]\ndist = "gauss"\nmean = 0.4\nstd = 0.02\n',
     "unknown dist 'gauss'"),
    ('method = "montecarlo"\nn = 4\n[parameters.mu_c]\ndist = "normal"\nmean = 0.4\n', "missing: std"),
    ('[parameters.mu_c]\ndist = "normal"\nmean = 0.4\nstd = 0.1\n', "'dist' is for method"),
    ('model = "mikro"\n' + SPEC.replace('model = "macro"\n', ""), "did you mean 'micro'"),
    ("[parameters]\n", "at least one variable"),
    ("model = [", "not a valid TOML"),
])
def test_bad_specs_are_clear_errors(tmp_path, capsys, body, message):
    spec = _write(tmp_path, body)
    assert cli(["sweep", str(spec), "--dry-run"]) == 2
    err = capsys.readouterr().err
    assert message in err and str(spec) in err


def test_dry_run_lists_the_study(tmp_path, capsys):
    spec = _write(tmp_path, 'method = "lhs"\nn = 8\nseed = 1\n[parameters.ramp_rate]\nmin = 37.0\nmax = 740.0\n'
                            'scale = "log"\n[parameters.friction]\nfactor = ["mu_c", "mu_s"]\nmin = 0.9\nmax = 1.1\n')
    assert cli(["sweep", str(spec), "--dry-run"]) == 0
    text = capsys.readouterr().out
    assert "8 micro start-ups" in text and "loguniform(37, 740)" in text and "factor on mu_c, mu_s" in text


def test_outputs_never_overwrite_the_spec(tmp_path, capsys):
    spec = _write(tmp_path, SPEC)
    assert cli(["sweep", str(spec), "--out", str(spec)]) == 2
    assert "refusing to overwrite" in capsys.readouterr().err
    assert cli(["sweep", str(spec), "--out", str(tmp_path / "r.xlsx")]) == 2
    assert cli(["sweep", str(spec), "--plot", str(tmp_path / "r.xyz")]) == 2
