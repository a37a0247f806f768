"""The sweep engine: results against a hand calculation, resume from the cache, failures, executors.

Truths used: the static equilibrium of the sliding burden (hand calculation:
tan psi* = mu_c R / L, so the running current is affine in the burden mass
m_v), Routh's criterion for a loop that must fail, and the count of
simulations actually run (a counting wrapper around ``simulate``).
"""

import math

import numpy as np
import pandas as pd
import pytest

import kilnctl.sweep.engine as engine
from kilnctl import Parameters
from kilnctl.errors import ParameterError
from kilnctl.sweep import Grid, Study, run_sweep

MASSES = [240e3, 480e3, 720e3, 960e3]  # kg: about the paper's 240 000 to 974 000 kg range (Fig. 14)


def _running_current(p: Parameters) -> float:
    """Armature current [A] with the burden sliding at tan(psi*) = mu_c R / L (hand calculation)."""
    psi = math.atan(p.mu_c * p.R / p.L)
    torque = p.m_v * p.g * p.L * math.sin(psi) + p.T_brg
    return torque / (p.n * p.k_i) + p.B_m * (p.omega_ref / p.K_fb) / p.k_i


def test_sweep_over_burden_mass_follows_the_sliding_equilibrium():
    st = Study(Grid({"m_v": MASSES}), outputs=["final_current_A", "peak_current_A"], model="macro", t_end=40.0)
    res = st.run(executor="serial", progress=False)
    t = res.table
    assert list(t["m_v"]) == MASSES and (t["status"] == "ok").all()
    for m, i_final in zip(t["m_v"], t["final_current_A"]):
        assert i_final == pytest.approx(_running_current(Parameters(m_v=m)), rel=0.01)
    # the running current is affine in m_v: equal steps in mass give equal steps in current
    steps = np.diff(t["final_current_A"])
    assert steps == pytest.approx(np.full(3, steps.mean()), rel=0.02)
    assert res.worst("final_current_A", n=1)["m_v"].item() == MASSES[-1]


class _Counting:
    """Wraps simulate: counts calls; raises KeyboardInterrupt at call number ``interrupt_at``."""

    def __init__(self, interrupt_at=None):
        self.calls = 0
        self.interrupt_at = interrupt_at
        self.real = engine.simulate

    def __call__(self, *a, **kw):
        self.calls += 1
        if self.interrupt_at is not None and self.calls == self.interrupt_at:
            raise KeyboardInterrupt
        return self.real(*a, **kw)


def _study(t_end=10.0):
    return Study(Grid({"m_v": MASSES, "ramp_rate": [74.0, 148.0]}), outputs=["peak_current_A"], model="macro",
                 t_end=t_end)


def test_interrupted_sweep_resumes_computing_only_the_missing_points(tmp_path, monkeypatch):
    cache = tmp_path / "cache"
    st = _study()
    first = _Counting(interrupt_at=4)
    monkeypatch.setattr(engine, "simulate", first)
    with pytest.raises(KeyboardInterrupt):
        st.run(executor="serial", cache=cache, progress=False)
    stored = list(cache.rglob("*.json"))
    assert len(stored) == 3  # the three points finished before the interruption, each in its own file

    second = _Counting()
    monkeypatch.setattr(engine, "simulate", second)
    res = st.run(executor="serial", cache=cache, progress=False)
    assert second.calls == len(st) - 3
    assert res.info["n_cached"] == 3 and res.info["n_computed"] == len(st) - 3
    assert res.table["cached"].sum() == 3

    third = _Counting()
    monkeypatch.setattr(engine, "simulate", third)
    again = st.run(executor="serial", cache=cache, progress=False)
    assert third.calls == 0
    # the resumed table is the one an uninterrupted run gives
    monkeypatch.setattr(engine, "simulate", first.real)
    fresh = st.run(executor="serial", progress=False)
    cols = ["m_v", "ramp_rate", "peak_current_A"]
    pd.testing.assert_frame_equal(res.table[cols], fresh.table[cols], check_exact=True)
    pd.testing.assert_frame_equal(again.table[cols], fresh.table[cols], check_exact=True)


def test_cache_key_covers_horizon_and_parameters(tmp_path, monkeypatch):
    cache = tmp_path / "cache"
    _study(t_end=5.0).run(executor="serial", cache=cache, progress=False)
    count = _Counting()
    monkeypatch.setattr(engine, "simulate", count)
    _study(t_end=6.0).run(executor="serial", cache=cache, progress=False)
    assert count.calls == 8  # another horizon: nothing reused
    base = Parameters(mu_c=0.35)
    Study(Grid({"m_v": MASSES[:2]}), outputs=["peak_current_A"], model="macro", t_end=5.0, base=base).run(
        executor="serial", cache=cache, progress=False)
    assert count.calls == 10  # another base parameter set: nothing reused


def test_a_failing_point_is_recorded_and_the_others_run():
    # Routh (see test_simulate_errors): k_I = 1e6 V/(rpm s) with k_p = 0.1 V/rpm is an unstable loop
    base = Parameters(gains="given", k_p=0.1, k_I=1.0, k_D=0.0)
    st = Study(Grid({"k_I": [1.0, 1e6]}), outputs=["peak_current_A"], model="macro", t_end=5.0, base=base,
               remove=("current_limit", "voltage_limit"))
    res = st.run(executor="serial", progress=False)
    ok, bad = res.table.iloc[0], res.table.iloc[1]
    assert ok["status"] == "ok" and np.isfinite(ok["peak_current_A"])
    assert bad["status"] == "failed" and "unstable" in bad["error"] and np.isnan(bad["peak_current_A"])
    assert res.info["n_failed"] == 1


def _peak_speed(resp) -> float:
    """Custom output: peak motor speed [rpm]."""
    return float(np.max(resp["speed_rpm"]))


def test_local_processes_give_the_serial_table_and_custom_outputs():
    st = Study(Grid({"m_v": MASSES[:2], "ramp_rate": [74.0, 148.0]}),
               outputs={"peak_speed_rpm": _peak_speed}, model="macro", t_end=10.0)
    serial = st.run(executor="serial", progress=False)
    local = st.run(workers=2, progress=False)
    assert local.info["executor"].startswith("local (2")
    cols = ["m_v", "ramp_rate", "peak_speed_rpm"]
    pd.testing.assert_frame_equal(serial.table[cols], local.table[cols], check_exact=True)
    assert (serial.table["peak_speed_rpm"] > 490).all()  # the set point is 500 rpm


def test_bad_executor_and_workers_are_errors():
    st = _study()
    with pytest.raises(ParameterError, match="executor"):
        run_sweep(st, "threads", progress=False)
    with pytest.raises(ParameterError, match="workers"):
        run_sweep(st, "local", workers=0, progress=False)
    with pytest.raises(ParameterError, match="local executor only"):
        run_sweep(st, "serial", workers=2, progress=False)


def test_result_files_are_written_whole(tmp_path):
    res = Study(Grid({"m_v": MASSES[:2]}), outputs=["peak_current_A"], model="macro", t_end=5.0).run(
        executor="serial", progress=False)
    csv = res.save(tmp_path / "r.csv")
    back = pd.read_csv(csv, index_col="point")
    assert back["peak_current_A"].tolist() == res.table["peak_current_A"].tolist()  # exact round trip
    js = res.save(tmp_path / "r.json")
    assert '"rows"' in js.read_text()
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".tmp")] == []
    with pytest.raises(Exception, match="table format"):
        res.save(tmp_path / "r.xlsx")


def _fake_result(space, stress):
    """A SweepResult with outputs from a formula (no simulation), for the table and figure code."""
    from kilnctl.sweep import SweepResult

    st = Study(space, outputs=["peak_stress_Pa"], model="macro", t_end=5.0)
    cols = st.samples()
    recs = [{"key": str(i), "status": "ok", "error": "", "custom": {},
             "summary": {"peak_stress_Pa": stress({k: cols[k][i] for k in cols})}} for i in range(len(st))]
    return SweepResult.from_records(st, recs, [False] * len(st), {"n_failed": 0, "n_points": len(st)})


def test_exceedance_counts_and_wilson_interval():
    from kilnctl.sweep import MonteCarlo, Uniform, wilson_interval

    res = _fake_result(MonteCarlo({"m_v": Uniform(200e3, 1000e3)}, n=100, seed=4), lambda p: p["m_v"] * 200.0)
    ex = res.exceedance("peak_stress_Pa", 180e6)  # stress > 180 MPa <=> m_v > 900 t
    assert ex["n_exceed"] == int((res.table["m_v"] > 900e3).sum()) and ex["n"] == 100
    # truth: Wilson 95 % interval of 10/100 is [0.0552, 0.1744] (hand calculation, z = 1.96)
    lo, hi = wilson_interval(10, 100)
    assert (round(lo, 4), round(hi, 4)) == (0.0552, 0.1744)


def test_plots_of_each_space_kind():
    from kilnctl.sweep import MonteCarlo, Uniform

    grid = _fake_result(Grid({"m_v": [3e5, 6e5, 9e5], "delta_x": [0.0, 0.008, 0.016], "ramp_rate": [74.0, 740.0]}),
                        lambda p: p["m_v"] * 200 + p["delta_x"] * p["ramp_rate"] * 2e7)
    fig = grid.plot(threshold=150e6)
    maps = [ax for ax in fig.axes if ax.get_title().startswith("ramp_rate")]
    assert [ax.get_title() for ax in maps] == ["ramp_rate = 74 rpm/s", "ramp_rate = 740 rpm/s"]
    assert maps[0].get_xlabel() == "delta_x [mm]" and maps[0].get_ylabel() == "m_v [t]"  # display units
    assert fig.axes[-1].get_ylabel().startswith("peak_stress_Pa [MPa]")     # the colour bar
    sample = _fake_result(MonteCarlo({"m_v": Uniform(2e5, 1e6)}, n=50, seed=1), lambda p: p["m_v"] * 200.0)
    fig = sample.plot()
    assert fig.axes[0].get_xlabel() == "m_v [t]"  # one variable: the output against it
    assert grid.worst(n=1)["m_v"].item() == 9e5 and grid.worst(n=1)["ramp_rate"].item() == 740.0


def test_a_script_without_a_main_guard_gets_the_fix_not_a_broken_pool(tmp_path):
    # truth: Python's spawn start method imports the calling script in every worker; a script whose code is not
    # under `if __name__ == "__main__":` makes each worker stop at once (the pool said only "BrokenProcessPool")
    from conftest import failing_script

    last = failing_script(tmp_path, "from kilnctl.sweep import Grid, Study, run_sweep\n"
                                    "st = Study(Grid({'m_v': [5e5, 6e5]}), outputs=['peak_current_A'], "
                                    "model='macro', t_end=2.0)\n"
                                    "run_sweep(st, workers=2, progress=False, confirm=False)\n")
    assert last.startswith("kilnctl.errors.WorkerError: run_sweep of study")
    assert "a worker process ended abruptly" in last
    assert 'if __name__ == "__main__":' in last and "executor='serial'" in last
