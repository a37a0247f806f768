"""Red team 11's independent plant (benchmarks/red11_plant.py: scipy RK45 between reference corners, its own
burden switches) as the truth for the residual signature's speed checks.

The red team measured its PID plant against kilnctl's model at 0.0033 A rms (Table 1, no effect, no noise).
Its cascade drive (a PI speed loop giving a current reference to a PI current loop, as most modern DC drives)
is outside kilnctl's model: given the paper's PID gains, kilnctl's diagnosis had selected a compliance and a
drag and said "no structure beyond noise" with the speed 6 rpm off; its inching drive turning the kiln at 2 %
before the start had been taken for 376 N m of motor friction, unnamed.  Here the model runs at the plant's
own values (no calibration): the speed checks name the cascade and the turning kiln, and say nothing of the
PID plant.
"""

import numpy as np
import pytest

from benchmarks.red11_plant import Sim, noise, table1
from kilnctl import Parameters
from kilnctl.measure import Measurement, compare
from kilnctl.measure.signature import residual_signature
from kilnctl.measure.standstill import standstill_offsets

SETUP = Parameters(gains="given", k_p=2.0, k_I=5.0, k_D=0.01)


def _record(seed, **plant):
    out = Sim(table1(**plant)).run(30.0)
    t = np.arange(0.0, 30.0, 0.02)
    rng = np.random.default_rng(seed)
    i = np.interp(t, out["t"], out["i"]) + noise(t.size, 0.02, rng, 2.0, 2.0, 0.4)
    w = np.interp(t, out["t"], out["w"]) + noise(t.size, 0.02, rng, 0.2, 0.15, 0.25)
    ref = np.interp(t, *zip(*table1()["ref"]))
    return Measurement.from_arrays(t, i, w, ref, source="red11", params=SETUP)


@pytest.mark.parametrize("ctrl, following", [("pid", False), ("cascade", True)])
def test_a_cascade_drive_is_named_by_the_speed(ctrl, following):
    m = _record(11, ctrl=ctrl)
    exp = m.experiment(SETUP)
    sig = residual_signature(compare(m, SETUP), SETUP.n, steady_from=exp.steady_from)
    assert sig["hint"].startswith("the measured speed departs from the model's") == following, sig["hint"]


def test_an_inching_drive_before_the_start_is_named():
    # the red team's R04: an inching drive turns the motor at 9.8 rpm through an overrunning clutch, the main
    # drive takes over at 3 s
    ref = [(0.0, 0.0), (3.0, 0.0), (3.0 + 500 / 74.0, 500.0)]
    out = Sim(table1(inch=(9.8, 2000.0, 3.0), ref=ref)).run(15.0)
    t = np.arange(0.0, 15.0, 0.02)
    m = Measurement.from_arrays(t, np.interp(t, out["t"], out["i"]), np.interp(t, out["t"], out["w"]),
                                np.interp(t, *zip(*ref)), source="inching", params=SETUP)
    (turning, *_) = standstill_offsets(m, m.experiment(SETUP))
    assert turning.get("turning") and turning["text"].startswith("the kiln turns before the start-up")
