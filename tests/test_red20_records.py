"""Red team 20's independent plant and records (benchmarks/red20_plant.py, benchmarks/red20_records.py).

The plant was written apart from kilnctl; these tests regenerate its records E6 and N1 and check them
against truths that do not come from kilnctl: the red team's own files (their hashes, taken from
/work/runs/red20 when the plant was moved here), the base kiln's friction regime and E6's holding current
worked out by hand, and what the red team's plant holds (truth.json: E6's coating rings, N1 without any
effect).
"""

import hashlib
import math
import subprocess
import sys

import pytest

from benchmarks import red20_records as rr
from conftest import imported_packages, read_written_record

#: sha256 of red team 20's own E6.csv and E6.toml (/work/runs/red20, written by their make_records.py)
E6_CSV_SHA256 = "6923071e012c903764387aba08e4fbfa7b598549edd63f9a913177c431daa31f"
E6_TOML_SHA256 = "79a720026470fdb8f53052baaa6702d72eeeead8d179b9b1cc32b2d8c5fca080"

#: E6's plant values as the red team's truth.json gives them (the nuisance draw on K-20's setup values)
E6_TRUTH = dict(m_v=249784.13578, mu_c=0.39089, mu_s=0.46425, J_v=417734.43654)


@pytest.fixture(scope="module")
def e6(tmp_path_factory):
    """E6 regenerated (about 5 s): the truth dict of :func:`benchmarks.red20_records.write_record`."""
    return rr.write_record("E6", tmp_path_factory.mktemp("red20"))


@pytest.fixture(scope="module")
def n1(tmp_path_factory):
    """N1 regenerated (about 5 s): the base kiln K-20 as its setup, no effect in the plant."""
    return rr.write_record("N1", tmp_path_factory.mktemp("red20"))


def _rest_current(tr):
    """The plant's noise-free current [A] over the last half second at rest before the ramp (1 s after the
    record's first time stamp)."""
    t = tr["t"] - tr["t"][0]
    return float(tr["i_clean"][(t >= 0.5) & (t < 1.0)].mean())


def test_the_plant_imports_no_kilnctl():
    """The plant's independence: its module imports numpy and the standard library only (ast scan)."""
    import benchmarks.red20_plant as plant

    assert imported_packages(plant) <= {"__future__", "math", "numpy"}


@pytest.mark.slow  # about 5 s on this machine (2 cores, shared with other jobs): E6 regenerated
def test_e6_regenerated_is_the_red_teams_file_byte_for_byte(e6):
    """Truth: the red team's own E6.csv and E6.toml, by their sha256 computed from /work/runs/red20 when the
    plant and generator were moved here (all twelve records were then checked byte for byte, CSV and TOML, and
    their truth JSONs against the red team's truth.json)."""
    sha = {k: hashlib.sha256(open(e6[k], "rb").read()).hexdigest() for k in ("csv", "toml")}
    assert sha == {"csv": E6_CSV_SHA256, "toml": E6_TOML_SHA256}
    # and the truth written beside it is the red team's (truth.json: 2051 samples, 1 burden mode switch)
    assert e6["record"]["samples"] == 2051 and e6["record"]["burden_switches"] == 1
    assert e6["catalogue_effects"] == ["kiln_unbalance"] and e6["setup_changes"] == {"omega_ref": 780.0}
    assert {k: round(v, 5) for k, v in e6["nuisance_true"].items()} == E6_TRUTH


@pytest.mark.slow  # about 6 s on this machine: N1 regenerated (4 s), kilnctl imported and 2 setup runs (2 s)
def test_the_base_kiln_slides_smoothly_under_the_paper_law(n1):
    """Truth (hand, the paper's friction law): at the set speed the burden slides steadily when mu_s < mu_c R / L
    and sticks and breaks away again and again when mu_s > mu_c R / L.  K-20: mu_c R / L = 0.38 x 1.9 / 1.15 =
    0.628 > mu_s 0.45, so it is held and then slides smoothly, no cycles (the red team: one burden mode switch in
    the whole run).  kilnctl's base model at N1's setup (the base kiln's nominal values) must then have no
    cycles after the ramp (``Diagnosis._cycles_at_setup``), and under the torque law at the same values it must
    (the red team's base check: 19 switches, a cycle of about 3 s), so the check tells the two apart."""
    from kilnctl.measure.diagnose import Diagnosis

    params, m = read_written_record(n1)
    assert (params.mu_c, params.R, params.L) == (0.38, 1.9, 1.15)
    assert params.mu_c * params.R / params.L == pytest.approx(0.6278, abs=1e-4)
    assert params.mu_s == 0.45 and params.friction_law == "paper"
    assert n1["record"]["burden_switches"] == 1            # the plant itself (nuisance on): held, then sliding
    d = Diagnosis(params)
    exp = m.experiment(params, t0=d.t0)
    assert d._cycles_at_setup(m, params, exp) is False
    torque = params.replace(friction_law="torque")
    d = Diagnosis(torque)
    assert d._cycles_at_setup(m, torque, m.experiment(torque, t0=d.t0)) is True


@pytest.mark.slow  # about 11 s on this machine alone (E6 and N1 regenerated), 0.05 s after the tests above
def test_e6_is_read_as_held_at_rest_and_n1_is_not(e6, n1):
    """Truth: what the red team's plant holds (truth.json) and the current that follows from it by hand.  E6's
    coating rings load the kiln with -U1 sin(theta + 2.0) - U2 sin(2 theta + 0.7) (U1 1.2e5, U2 4e4 N m) and the
    plant's speed loop runs from the start, so before the ramp the drive holds the kiln at theta 0 with
    (U1 sin 2.0 + U2 sin 0.7) / (n k_i) = 1.354e5 / (820 x 5.0) = 32.9 A (the record: about +30 A at rest); N1's
    plant has no unbalance, and no current at rest.  kilnctl must read E6's experiment as held (the model then
    starts where its speed loop holds the kiln) and N1's as not held."""
    from kilnctl.measure.diagnose import Diagnosis

    hand = (1.2e5 * math.sin(2.0) + 4.0e4 * math.sin(0.7)) / (820.0 * 5.0)
    assert hand == pytest.approx(32.90, abs=0.01)
    assert _rest_current(e6) == pytest.approx(hand, abs=0.05)
    assert _rest_current(n1) == 0.0
    for tr, held in ((e6, True), (n1, False)):
        params, m = read_written_record(tr)
        assert m.experiment(params, t0=Diagnosis(params).t0).held is held


def test_cli_lists_the_twelve_records():
    """``--list`` names the twelve records of the red team (N1 N2 E1..E8 P1 X1, truth.json's order); ``--help``
    shows ``--write DIR``."""
    out = subprocess.run([sys.executable, "-m", "benchmarks.red20_records", "--list"], capture_output=True, text=True,
                         timeout=60)
    assert out.returncode == 0
    assert [ln.split()[0] for ln in out.stdout.strip().splitlines()] == \
        ["N1", "N2", "E1", "E2", "E3", "E4", "E5", "E6", "E7", "E8", "P1", "X1"]
    out = subprocess.run([sys.executable, "-m", "benchmarks.red20_records", "--help"], capture_output=True, text=True,
                         timeout=60)
    assert out.returncode == 0 and "--write DIR" in out.stdout
