"""The records of the diagnosis benchmark: deterministic, readable by kilnctl, truths consistent.

Truths: the record list itself (every class present in the quick subset), the
catalogue (every expected effect exists and carries the parameters named in
the truth), byte equality of two independent generations, and the ramp start
kilnctl infers from the written CSV (the generator puts it at t = 1 s).
"""

import json

import numpy as np
import pytest

from benchmarks.diagnose_records import PRETRIGGER_S, QUICK, RECORDS, find, make, write
from kilnctl import Parameters
from kilnctl.measure import read_csv
from kilnctl.measure.effects import CATALOGUE
from kilnctl.measure.synthetic import DEFAULT_GAINS


def test_names_are_unique_and_the_quick_subset_covers_every_class():
    names = [r.name for r in RECORDS]
    assert len(names) == len(set(names))
    classes = {r.klass for r in RECORDS}
    assert classes == {"torque_pair", "out_of_range", "foreign", "effect_free", "outside"}
    assert {find(n).klass for n in QUICK} == classes
    assert 10 <= len(QUICK) <= 14


def test_unknown_record_names_its_close_matches():
    with pytest.raises(KeyError, match="did you mean"):
        find("plant:drag/s9")


@pytest.mark.parametrize("name", ["plant:torque_law+drag/s1", "outside:offset_step/s1"])
def test_plant_record_is_deterministic_and_read_back(tmp_path, name):
    spec = find(name)
    a, ta, truth = write(spec, tmp_path / "a")
    b, _, _ = write(spec, tmp_path / "b")
    assert a.read_text() == b.read_text()  # the same bytes from the same name and seed
    with pytest.raises(FileExistsError):
        write(spec, tmp_path / "a")  # never overwrites a record
    setup = Parameters(DEFAULT_GAINS)
    m = read_csv(a, setup)
    assert m.t[-1] == pytest.approx(PRETRIGGER_S + 40.0 - 0.02, abs=1e-6)
    assert m.experiment(setup).t0 == pytest.approx(PRETRIGGER_S, abs=0.05)
    assert json.loads(ta.read_text()) == truth
    for e in truth["expected"]:
        assert e in CATALOGUE
    names = {fp.name for e in truth["expected"] for fp in CATALOGUE[e].parameters} \
        | {fp.partner for e in truth["expected"] for fp in CATALOGUE[e].parameters if fp.partner}
    assert set(truth["catalogue_values"]) <= names
    assert set(truth["base"]) == {"m_v", "mu_c", "mu_s", "J_v"}
    # nuisance of a few per cent, never more than 5 %
    for k, v in truth["base"].items():
        assert 0.0 < abs(v / float(setup[k]) - 1.0) <= 0.05 + 1e-12 or k == "mu_s"


def test_offset_step_is_in_the_logged_current_only():
    # Truth: the record's current jumps by the recorded step at the recorded time (means of 2 s either side;
    # the plant's current is steady there, at full speed, and the noise is 4 A white + 4 A AR(1))
    spec = find("outside:offset_step/s1")
    m, truth = make(spec)
    step = truth["sensor_offset_step"]
    assert 40.0 <= step["A"] <= 70.0
    k = np.searchsorted(m.t, step["t_s"])
    before, after = m.current[k - 100:k], m.current[k:k + 100]
    assert np.mean(after) - np.mean(before) == pytest.approx(step["A"], abs=15.0)


def test_visibility_sees_the_true_structure_reproduce_a_kilnctl_record():
    # Truth: a record from kilnctl's own generator is its model plus noise, so the true structure at the true
    # values leaves only the noise: 4 A white + 4 A AR(1) on the current -> rms about sqrt(32) = 5.7 A.  A drag
    # of 3x the plausible range (B_o = 3e7) is far above the noise; a 0.6 ms sensor lag (a hundredth of the
    # speed loop's time scale) is below it.
    from benchmarks.diagnose_records import visibility

    m, truth = make(find("range:viscous_drag@3x/s1"))
    v = visibility(m, truth)
    assert v["gain"]["viscous_drag"] > 10.0 and v["invisible"] == []
    setup = Parameters(DEFAULT_GAINS)
    active = m.t >= m.experiment(setup).t0 - 1e-9
    y = m.current[active]
    rms_noise = np.sqrt(32.0)
    # fit % = 100 (1 - |e| / |y - mean y|) with |e| = rms_noise sqrt(n), within 15 % of the noise level
    expected_fit = 100.0 * (1.0 - rms_noise * np.sqrt(y.size) / np.linalg.norm(y - y.mean()))
    assert v["true_fit"] == pytest.approx(expected_fit, abs=0.15 * (100.0 - expected_fit))
    m2, truth2 = make(find("range:speed_sensor_lag@0.3x/s1"))
    assert visibility(m2, truth2)["invisible"] == ["speed_sensor_lag"]


def test_summary_counts_against_the_targets_of_issue_12():
    # Truth: counts by hand over five made-up outcomes (one failed record counts against every share)
    from benchmarks.diagnose_confusion import hard_summary

    def rec(klass, exact, dfit, selected=(), unexplained=None, wall=10.0):
        return {"name": klass, "class": klass, "exact": exact, "dfit": dfit, "selected": list(selected),
                "unexplained": unexplained, "wall_s": wall}

    rs = [rec("foreign", True, 0.0, ["viscous_drag"], wall=12.0), rec("foreign", False, -3.5, ["backlash"], wall=30.0),
          rec("effect_free", True, 0.0, wall=8.0), rec("outside", True, -0.5, unexplained="a local failure", wall=25.0),
          {"name": "x", "error": "RuntimeError: boom", "wall_s": 1.0}]
    lines = "\n".join(hard_summary(rs))
    assert "3/5 (60 %)" in lines          # exact: 3 of 5 (the failed record is a miss)
    assert "worst -3.50 points" in lines  # and that misses the 3-point target
    assert "1/1 (unexplained 1)" in lines
    assert "median wall time <= 20 s per 40 s record                      18 s" in lines  # median of 12, 30, 8, 25
    assert "1 record(s) failed" in lines
