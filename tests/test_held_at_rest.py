"""A drive that holds the kiln at rest before the start-up (kilnctl.model.rest, Experiment.held).

Red teams 19 and 20 wrote plants whose speed loop runs from before the ramp: a kiln unbalance makes it hold
the kiln with a current at standstill (+78.8 A and +30 A), which kilnctl's model, started from zero current at
the ramp, could not have; the diagnosis called it an offset it could not explain.
"""

import math

import numpy as np
import pytest

from kilnctl import Parameters
from kilnctl.model.rest import held_state, holding_current
from kilnctl.simulate import plant_structure, simulate


def _setup():
    from kilnctl.measure.synthetic import DEFAULT_GAINS

    return Parameters(DEFAULT_GAINS).replace(T_unb=2.0e5, phi_unb=1.0)


@pytest.mark.parametrize("effects", [("kiln_unbalance",), ("kiln_unbalance", "drivetrain_compliance")])
def test_a_held_drive_stays_where_it_is_and_holds_what_the_unbalance_asks(effects):
    """Truth: the torque balance by hand, k_i n i = T_unb sin(phi_unb) (the unbalance's -T_unb sin(theta_o +
    phi_unb) at theta_o = 0), and a second method, the same plant started from zero current, whose speed loop
    catches the rolling kiln and settles at that current within seconds.  Held, the kiln does not move and the
    current does not change; the compliant drive train starts twisted by the torque it carries."""
    p = _setup().replace(ramp_rate=0.01)  # a reference that hardly moves: the kiln at rest
    i_hand = 2.0e5 * math.sin(1.0) / (p.n * p.k_i)
    names, q, _ = plant_structure(p, "macro", effects)
    assert holding_current(q, names) == pytest.approx(i_hand, rel=1e-12)
    held = simulate(p, "macro", t_end=2.0, effects=effects, held=True)
    assert np.max(np.abs(held.outputs["i_a"] - i_hand)) < 0.05
    assert np.max(np.abs(held.outputs["speed_rpm"] - held.outputs["speed_ref_rpm"])) < 1e-3  # 0.02 rpm at 2 s
    free = simulate(p, "macro", t_end=3.0, effects=effects)
    assert free.outputs["i_a"][0] == 0.0 and np.min(free.outputs["speed_rpm"]) < -0.1  # it rolls back first
    # settled after the compliant train's ring; within 1.5 %: the free kiln rolls back a little before it is
    # caught (the twisting train lets it), and the unbalance's torque changes with its angle
    settled = (free.t > 2.0) & (free.t < 3.0)
    assert float(np.mean(free.outputs["i_a"][settled])) == pytest.approx(i_hand, rel=0.015)


def test_nothing_to_hold_without_a_load_at_rest():
    """Truth: the base kiln has no torque at rest (the burden lies at psi = 0, the bearing friction and the drag
    need motion), so the held start is the start from zero current."""
    p = _setup()
    names, q, _ = plant_structure(p, "macro", ())
    assert holding_current(q, names) == 0.0 and held_state(q, names) == {}
    names, q, _ = plant_structure(p.replace(phi_unb=0.0), "macro", ("kiln_unbalance",))
    assert held_state(q, names) == {}  # an unbalance hanging at its lowest point


def _record_with_rest(level: float, seed: int = 3):
    """The generator's effect-free record with a second at rest before its ramp whose current reads ``level``."""
    from kilnctl.measure import Measurement
    from kilnctl.measure.synthetic import DEFAULT_GAINS, make_record

    setup = Parameters(DEFAULT_GAINS)
    m0, _ = make_record((), seed=seed, t_end=12.0)
    rng = np.random.default_rng(seed)
    pre = np.arange(-50, 0) * 0.02
    t = np.concatenate([pre, m0.t]) + 1.0
    current = np.concatenate([level + rng.normal(0.0, 4.0, pre.size), m0.current])
    speed = np.concatenate([rng.normal(0.0, 0.3, pre.size), m0.speed])
    ref = np.concatenate([np.zeros(pre.size), m0.speed_ref])
    return Measurement.from_arrays(t, current, speed, ref, source=f"rest {level:+g} A", params=setup), setup


@pytest.mark.parametrize("level, held", [(0.0, False), (30.0, True)])
def test_a_current_at_rest_says_the_drive_holds_the_kiln(level, held):
    """Truth by construction: a record at rest for a second before its ramp, its current there 0 or +30 A
    (noise 4 A, 50 samples: a standard error of 0.6 A) marks the experiment held or not."""
    m, setup = _record_with_rest(level)
    exp = m.experiment(setup)
    assert exp.held is held and exp.to_dict()["held"] is held


def test_the_current_at_rest_is_read_against_the_models_holding_current():
    """Truth by construction: +30 A at rest is no offset for a model that holds the kiln with +30 A, an offset of
    +20 A for one that holds it with +10 A, and of +30 A for one that holds nothing; the text says which."""
    from kilnctl.measure.standstill import standstill_offsets

    m, setup = _record_with_rest(30.0)
    exp = m.experiment(setup)
    assert not [o for o in standstill_offsets(m, exp, held={"current_A": 30.0}) if o["channel"] == "current_A"]
    (o,) = [o for o in standstill_offsets(m, exp, held={"current_A": 10.0}) if o["channel"] == "current_A"]
    assert o["offset"] == pytest.approx(20.0, abs=2.0) and "where the model holds the kiln with +10 A" in o["text"]
    (o,) = [o for o in standstill_offsets(m, exp) if o["channel"] == "current_A"]
    assert o["offset"] == pytest.approx(30.0, abs=2.0) and "where the model has zero" in o["text"]
