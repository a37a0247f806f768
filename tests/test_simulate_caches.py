"""What the simulator caches between runs gives the numbers of an uncached computation (issue 12, item 5).

Cached between runs: the component registry look-up, the parameter declarations and the option/numeric name
lists derived from it (rebuilt when ``REGISTRY.version`` changes), the plants (keyed on that version too),
and ``Parameters.replace`` checking only the changed values.  Truths, named in each test: a fresh Python
process (nothing cached), a full construction ``Parameters(values)`` (every value checked), the uncompiled
CasADi output function evaluated point by point, another component with the same physics, and the same run
with recording buffers that never grow.
"""

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import kilnctl.simulate as sim
from kilnctl import Parameters
from kilnctl.errors import ParameterError
from kilnctl.model import REGISTRY, Component, component_names, get_plant, register
from kilnctl.model.base import numeric_names, option_names
from kilnctl.params import SPECS, param
from kilnctl.simulate import simulate

ROOT = Path(__file__).resolve().parents[1]


def _full(p: Parameters, **changes) -> Parameters:
    """The uncached path: a new set built from all values, each checked."""
    return Parameters(dict(p.as_dict(), **changes))


def _error(fn):
    try:
        fn()
    except ParameterError as exc:
        return type(exc), str(exc)
    return None


@pytest.mark.parametrize("changes", [
    {"mu_c": 0.31},
    {"mu_c": 0.31, "mu_s": 0.36, "m_v": 7e5},
    {"friction_law": "torque"},
    {"J_e_mode": "table", "J_e": 9e6},
    {"mu_c": -0.1},                       # a bad value
    {"mu_c": 0.5, "mu_s": 0.4},           # each valid, impossible together
    {"mu_cc": 0.3},                       # an unknown name
    {"m_v": -1.0, "mu_c": "x", "zz": 1},  # several bad: the first in declaration order is reported
    {"mu_c": True},
    {"R_a": 1e300},                       # beyond the plausible magnitude
])
def test_replace_checks_like_a_full_construction(changes):
    # truth: Parameters(all values), which checks every value and the cross checks
    p = Parameters(gains="given", mu_c=0.3, mu_s=0.35)
    want = _error(lambda: _full(p, **changes))
    got = _error(lambda: p.replace(**changes))
    assert got == want
    if want is None:
        q, ref = p.replace(**changes), _full(p, **changes)
        assert q == ref and list(q) == list(ref)
        assert all(type(q[k]) is type(ref[k]) for k in ref)
        assert p == Parameters(gains="given", mu_c=0.3, mu_s=0.35)  # unchanged


def _outputs(r):
    return {**{f"o_{k}": v for k, v in r.outputs.items()}, **{f"s_{k}": v for k, v in r.states.items()},
            "t": r.t, "ev": np.array([(e.t, e.rate) for e in r.events]).ravel()}


def test_a_component_registered_after_a_run_is_seen_and_changes_nothing_else():
    # truths: the run before the registration (an unrelated new component must not change it), and the
    # component viscous_drag, which has the same physics (torque -B*omega on the kiln) as the new one
    p = Parameters(gains="given")
    before = simulate(p, t_end=2.0)
    names0, opts0, specs0 = numeric_names(), option_names(), set(SPECS)
    version0 = REGISTRY.version

    @register
    class _TestDrag(Component):
        """Viscous drag on the kiln under another parameter (test only)."""

        name = "_test_drag"
        param_names = ("B_test",)
        parameters = (param("B_test", 2.0e5, "N*m*s/rad", "assumed: test", "test drag", "effects", "nonnegative"),)
        requires = ("kiln",)

        def loads(self, e, mode):
            e.add_torque("kiln", -e.p.B_test * e.x["omega_kiln"])

    try:
        assert REGISTRY.version > version0
        assert set(SPECS) == specs0 | {"B_test"}
        assert numeric_names() == names0 + ("B_test",) and option_names() == opts0
        # a set made before the registration gets the new declaration's default when it is replaced
        q = p.replace(mu_c=p.mu_c)
        assert q.B_test == 2.0e5 and q == Parameters(gains="given")
        plant = get_plant(component_names("macro"), q)
        assert plant.numeric_names == names0 + ("B_test",)
        after = simulate(q, t_end=2.0)
        a, b = _outputs(before), _outputs(after)
        assert a.keys() == b.keys()
        for k in a:
            assert np.array_equal(a[k], b[k]), k
        drag = simulate(q, t_end=2.0, effects=("_test_drag",))
        same = simulate(q.replace(B_o=2.0e5), t_end=2.0, effects=("viscous_drag",))
        assert len(drag.t) == len(same.t)
        for k in ("i_a", "speed_rpm", "kiln_rpm"):
            assert np.allclose(drag.outputs[k], same.outputs[k], rtol=1e-9, atol=1e-9 * np.abs(same.outputs[k]).max())
        assert not np.allclose(drag.outputs["i_a"], after.outputs["i_a"])  # the drag does act
    finally:
        del REGISTRY["_test_drag"]
    assert set(SPECS) == specs0 and numeric_names() == names0
    with pytest.raises(ParameterError, match="B_test"):
        Parameters(B_test=1.0)


_FRESH = """
import json, sys
import numpy as np
from kilnctl import Parameters
from kilnctl.measure import example_paths, load_setup, read_csv
from kilnctl.measure.runner import run_model
rec_path, setup_path = example_paths()
setup = load_setup(setup_path)
rec = read_csv(rec_path, setup.params)
exp = rec.experiment(setup.params)
out = {}
for k, (effects, values) in enumerate(json.loads(sys.argv[2])):
    r = run_model(Parameters(values), rec, exp, effects=tuple(effects))
    for c, v in r.outputs.items():
        out[f"{k}_{c}"] = v
    for c, v in r.response.outputs.items():
        out[f"{k}_y_{c}"] = v
    out[f"{k}_t"] = r.response.t
np.savez(sys.argv[1], **out)
"""


def test_runs_with_warm_caches_equal_a_fresh_process(tmp_path):
    # truth: the same runs in a new Python process, where nothing is cached (each parameter set built whole)
    from kilnctl.measure import example_paths, load_setup, read_csv
    from kilnctl.measure.runner import run_model

    rec_path, setup_path = example_paths()
    setup = load_setup(setup_path)
    rec = read_csv(rec_path, setup.params)
    exp = rec.experiment(setup.params)
    base = setup.params.replace(ramp_rate=exp.ramp_rate, omega_ref=exp.omega_ref)
    cases = [((), 0.97), (("second_motor",), 1.02), ((), 1.01)]
    warm, jobs = {}, []
    run_model(base, rec, exp)  # warm every cache first
    for k, (effects, f) in enumerate(cases):
        p = base.replace(mu_c=base.mu_c * f)  # the cached path calibration takes
        r = run_model(p, rec, exp, effects=effects)
        warm.update({f"{k}_{c}": v for c, v in r.outputs.items()})
        warm.update({f"{k}_y_{c}": v for c, v in r.response.outputs.items()})
        warm[f"{k}_t"] = r.response.t
        jobs.append([list(effects), p.as_dict()])
    path = tmp_path / "fresh.npz"
    subprocess.run([sys.executable, "-c", _FRESH, str(path), json.dumps(jobs)], check=True, cwd=ROOT,
                   env={**os.environ, "PYTHONPATH": str(ROOT)})
    fresh = np.load(path)
    assert set(fresh.files) == set(warm)
    for k in fresh.files:
        assert np.array_equal(fresh[k], warm[k]), k


@pytest.mark.parametrize("effects, t_end, storm", [(("second_motor",), 40.0, False),
                                                   (("speed_sensor_lag", "second_motor"), 8.0, True)])
def test_outputs_equal_the_uncompiled_output_function_point_by_point(effects, t_end, storm):
    # truth: the CasADi output function of each sample's mode (SX, not the generated C), one point at a time;
    # checks that the outputs evaluated per segment (few switches) or per mode (a run that keeps switching)
    # are put back at their own samples
    p = Parameters(gains="given", k_p=2.0, k_I=5.0, ramp_rate=74.0, omega_ref=500.0)
    r = simulate(p, t_end=t_end, effects=effects)
    assert (len(r.events) > 100) == storm
    plant = get_plant(r.components, p, rtol=1e-7, atol=1e-8)
    P = plant.param_vector(p)
    xs = np.vstack([r.states[n] / s for n, s in zip(plant.state_names, plant.scales)])
    Y = np.vstack([r.outputs[n] for n in plant.output_names])
    assert len({tuple(r.modes[c.name][i] for c in plant.moded) for i in range(len(r.t))}) >= 3
    rng = np.random.default_rng(3)
    idx = np.unique(np.concatenate([rng.integers(0, len(r.t), 60), [0, len(r.t) - 1],
                                    np.searchsorted(r.t, [e.t for e in r.events])]))
    for i in idx:
        mode = tuple(str(r.modes[c.name][i]) for c in plant.moded)
        want = np.asarray(plant.functions(mode).output(xs[:, i], r.t[i], P)).ravel()
        assert np.allclose(Y[:, i], want, rtol=1e-12, atol=1e-12 * np.abs(want).max()), (i, mode)


def test_results_do_not_depend_on_growing_the_recording_buffers(monkeypatch):
    # truth: the same run with buffers reserved up front (never grown); here they start with one row and
    # grow at every stepper call and through 400 mode switches (speed-sensor lag cycling)
    p = Parameters(gains="given", k_p=2.0, k_I=5.0, ramp_rate=74.0, omega_ref=500.0)
    ref = simulate(p, t_end=10.0, effects=("speed_sensor_lag",))
    grown = []
    reserve = sim._Engine.reserve

    def counted(self, k):
        grown.append(self.n_rec + k > len(self.t_buf))
        reserve(self, k)

    monkeypatch.setattr(sim, "_initial_rows", lambda t_end, dt: 1)
    monkeypatch.setattr(sim._Engine, "reserve", counted)
    small = simulate(p, t_end=10.0, effects=("speed_sensor_lag",))
    assert len(ref.events) > 300 and sum(grown) >= 3
    a, b = _outputs(ref), _outputs(small)
    assert a.keys() == b.keys()
    for k in a:
        assert np.array_equal(a[k], b[k]), k
    assert all(np.array_equal(ref.modes[c], small.modes[c]) for c in ref.modes)


def test_the_stepper_follows_a_changed_parameter_vector():
    # truth: the CasADi guard and projection functions (SX, not the generated C) at the same point; the stepper
    # keeps the address of the last vector it checked, so alternating vectors (and a strided copy, which is
    # not kept) must each give their own values
    p = Parameters(gains="given")
    plant = get_plant(component_names("macro"), p)
    xs, mode = plant.initial(p)
    mode = tuple("slip_pos" if c.name == "burden" else m for c, m in zip(plant.moded, mode))
    mf = plant.functions(mode)
    assert mf.stepper is not None and mf.guards
    xs = xs + 0.01 * np.arange(1, len(xs) + 1)
    other = p.replace(mu_c=0.2, mu_s=0.3, m_v=9e5, k_p=3.0, R_a=0.02, J_m=30.0)
    P1, P2 = plant.param_vector(p), plant.param_vector(other)
    wide = np.zeros((len(P2), 2))
    wide[:, 0] = P2
    for P in (P1, P2, P1, wide[:, 0], P2):
        g, sel, gdot = mf.stepper.guard(P, xs, 0.7)
        want = [np.asarray(v).ravel() for v in mf.guard(xs, 0.7, P)]
        for got, ref in zip((g, sel, gdot), want):
            assert np.allclose(got, ref, rtol=1e-12, atol=1e-12 * max(1.0, np.abs(ref).max()))
        proj = np.asarray(mf.project(xs, 0.7, P)).ravel()
        assert np.allclose(mf.stepper.project(P, xs, 0.7), proj, rtol=1e-12, atol=1e-14)
    g1, g2 = (np.concatenate(mf.stepper.guard(P, xs, 0.7)) for P in (P1, P2))
    assert not np.allclose(g1, g2)
