"""Red team 9's independent plant (benchmarks/red9_plant.py: numpy RK4 at 0.5 ms, its own burden switches).

Truth: the red team's plant against kilnctl's model at the same values, two plants of the same physics written
apart.  The red team measured 0.0033 A rms without an effect, and with kilnctl's effect of the same physics
every catalogue record at 100.0 % (the largest difference its tanh Coulomb friction against kilnctl's sticking
one, 0.078 A).  Here, Table 1 with the example's gains, no noise: a lightly damped drive train (R03's k_po 1e8,
C_po 3e5, which rings for seconds) and a motor Coulomb friction of 300 N m (R04's), each within 0.2 A rms
(measured when written: 0.025 and 0.11 A; without the effect 26 and 65 A).
"""

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from benchmarks.red9_plant import Plant
from kilnctl import Parameters
from kilnctl.simulate import simulate

GIVEN = dict(gains="given", k_p=2.0, k_I=5.0, k_D=0.01)


@pytest.mark.parametrize("effect, values", [
    ("drivetrain_compliance", {"k_po": 1.0e8, "C_po": 3e5}),
    ("motor_coulomb_friction", {"T_cm": 300.0}),
])
def test_kilnctl_follows_the_red_teams_plant(effect, values):
    out, _ = Plant(law="paper", **values).run(30.0, 50.0)
    t, current = out[:, 0], out[:, 1]
    on = t >= 1.0  # the plant rests 1 s before its ramp
    r = simulate(Parameters(**GIVEN).replace(**values), "macro", 29.0, effects=(effect,), dt=0.02)
    model = np.interp(t[on] - 1.0, r.t, r.outputs["i_a"])
    rms = float(np.sqrt(np.mean((model - current[on]) ** 2)))
    assert rms < 0.2, rms
    # the effect is seen: without it kilnctl's model misses the red team's current by far more
    bare = simulate(Parameters(**GIVEN), "macro", 29.0, dt=0.02)
    miss = float(np.sqrt(np.mean((np.interp(t[on] - 1.0, bare.t, bare.outputs["i_a"]) - current[on]) ** 2)))
    assert miss > 20 * max(rms, 0.2)



@pytest.mark.parametrize("option", ["--list", "--help"])
def test_an_option_in_place_of_the_folder_gets_the_usage_line(tmp_path, option):
    # truth: the generator's usage (benchmarks/red9_records.py): OUTDIR first.  `--list` had written the ten
    # records into a folder named --list; now it exits with the usage line and writes nothing
    root = Path(__file__).resolve().parents[1]
    out = subprocess.run([sys.executable, "-m", "benchmarks.red9_records", option], capture_output=True, text=True,
                         timeout=60, cwd=tmp_path, env=dict(os.environ, PYTHONPATH=str(root)))
    assert out.returncode != 0 and "usage: python -m benchmarks.red9_records OUTDIR" in out.stderr
    assert list(tmp_path.iterdir()) == []
