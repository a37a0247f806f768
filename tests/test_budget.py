"""Size limits checked before work starts (kilnctl.budget): simulations and sweeps."""

from __future__ import annotations

import math
import tracemalloc

import pytest

from kilnctl.budget import DEFAULT_MAX_SAMPLES, check_points, estimate_run, run_bytes
from kilnctl.cli import main
from kilnctl.errors import ParameterError, SimulationError
from kilnctl.model import component_names, get_plant
from kilnctl.params import Parameters
from kilnctl.simulate import simulate
from kilnctl.sweep import Grid, LatinHypercube, Study, Uniform
from kilnctl.sweep.spec import load_spec


def _sizes(model):
    pl = get_plant(component_names(model), Parameters(gains="given"))
    return len(pl.state_names), len(pl.output_names), len(pl.moded)


@pytest.mark.parametrize("model, t_end", [("macro", 10.0), ("micro", 3.0)])
def test_estimate_counts_the_samples_a_run_records(model, t_end):
    # independent truth: the recording rule of kilnctl.simulate (grid k*dt from 0 to t_end, plus two
    # samples per mode switch), checked against the response actually returned
    r = simulate(model=model, t_end=t_end)
    nx, ny, nm = _sizes(model)
    est = estimate_run(t_end, r.info["dt"], nx, ny, nm, max_events=r.info["n_events"])
    assert len(r.t) == est.samples == math.floor(t_end / r.info["dt"]) + 1 + 2 * r.info["n_events"]


def test_memory_estimate_matches_the_measured_peak():
    # independent truth: tracemalloc's peak of the run with its mode labels read (they are spelled out when
    # first read; numpy reports its buffers to tracemalloc)
    simulate(model="macro", t_end=1.0)  # plant built and compiled outside the measurement
    tracemalloc.start()
    try:
        r = simulate(model="macro", t_end=20.0)
        labels = list(r.modes.values())
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    est = run_bytes(len(r.t), *_sizes("macro"))
    assert len(labels) == _sizes("macro")[2] and all(len(v) == len(r.t) for v in labels)
    assert 0.7 < peak / est < 1.3


def test_a_huge_horizon_is_refused_before_any_memory_is_taken():
    tracemalloc.start()
    try:
        with pytest.raises(SimulationError) as exc:
            simulate(model="micro", t_end=1e9)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    msg = str(exc.value)
    assert "t_end = 1e+09 s" in msg and "dt = 0.001 s" in msg and "max_samples" in msg
    assert "KILNCTL_MAX_SAMPLES" in msg
    assert peak < 50e6  # the 1e12-sample run was never started (it would need terabytes)


def test_the_sample_limit_can_be_raised_by_keyword_and_environment(monkeypatch):
    # 2 s of the macro model at 5 ms: 401 grid samples
    with pytest.raises(SimulationError, match="401 output samples"):
        simulate(model="macro", t_end=2.0, max_samples=400)
    assert len(simulate(model="macro", t_end=2.0, max_samples=450).t) >= 401
    monkeypatch.setenv("KILNCTL_MAX_SAMPLES", "400")
    with pytest.raises(SimulationError, match="limit of 400 samples"):
        simulate(model="macro", t_end=2.0)
    monkeypatch.setenv("KILNCTL_MAX_SAMPLES", "lots")
    with pytest.raises(ParameterError, match="KILNCTL_MAX_SAMPLES"):
        simulate(model="macro", t_end=2.0)
    with pytest.raises(ParameterError, match="max_samples"):
        simulate(model="macro", t_end=2.0, max_samples=0)


@pytest.mark.parametrize("t_end", ["1e9", "1e5", "1e300"])
def test_cli_simulate_huge_horizon_is_one_clear_line(t_end, capsys):
    assert main(["simulate", "--t-end", t_end]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--t-end" in err and "--max-samples" in err
    assert "Traceback" not in err


def test_cli_max_samples_option_is_applied(capsys):
    assert main(["simulate", "--t-end", "2", "--max-samples", "100", "--json"]) == 2
    assert "limit of 100 samples" in capsys.readouterr().err


def test_default_limit_allows_a_long_start_up():
    # 1000 s of the micro model (25 start-ups' worth) stays under the default
    assert DEFAULT_MAX_SAMPLES >= 1000 / 1e-3


def test_grid_is_counted_before_it_is_built(tmp_path, capsys):
    spec = tmp_path / "big.toml"
    spec.write_text('model = "macro"\n[parameters.m_v]\nmin = 240e3\nmax = 974e3\nnum = 10000000\n')
    tracemalloc.start()
    try:
        code = main(["sweep", str(spec), "--dry-run"])
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    err = capsys.readouterr().err
    assert code == 2 and "num = 10000000" in err and "--max-points" in err and "[parameters.m_v]" in err
    assert peak < 50e6  # 10 million values would take several hundred MB


def test_product_of_grid_counts_and_sampled_n_are_limited(tmp_path):
    spec = tmp_path / "grid.toml"
    spec.write_text('model = "macro"\n[parameters.m_v]\nmin = 240e3\nmax = 974e3\nnum = 1000\n'
                    '[parameters.delta_x]\nmin = 0.0\nmax = 0.01\nnum = 1000\n')
    with pytest.raises(ParameterError, match="1,000,000 points"):
        load_spec(spec)
    with pytest.raises(ParameterError, match="1,000,000,000 points"):
        Study(LatinHypercube({"m_v": Uniform(3e5, 6e5)}, n=10**9), model="macro")
    study = Study(Grid({"m_v": [3e5, 4e5, 5e5]}), model="macro", max_points=3)
    assert len(study) == 3
    with pytest.raises(ParameterError, match="limit of 2"):
        Study(Grid({"m_v": [3e5, 4e5, 5e5]}), model="macro", max_points=2)
    assert check_points(5, 5) == 5


def test_sweep_with_too_long_start_ups_is_refused_up_front(tmp_path, capsys):
    spec = tmp_path / "long.toml"
    spec.write_text('model = "micro"\nt_end = 1e6\n[parameters.m_v]\nvalues = [3e5, 5e5]\n')
    assert main(["sweep", str(spec), "--dry-run"]) == 2
    err = capsys.readouterr().err
    assert "t_end = 1e+06 s" in err and "[options]" in err
    spec.write_text('model = "macro"\nt_end = 20\n[options]\nmax_samples = 100\n[parameters.m_v]\nvalues = [3e5]\n')
    assert main(["sweep", str(spec), "--dry-run"]) == 2
    assert "limit of 100 samples" in capsys.readouterr().err
