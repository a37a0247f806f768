"""Bad input to the plant and the simulator gives clear errors, never a hang or a NaN."""

import math
import re

import numpy as np
import pytest

from kilnctl import Parameters
from kilnctl.errors import EventStormError, KilnctlError, ModelError, ParameterError, SimulationError
from kilnctl.model import component_names
from kilnctl.simulate import simulate

GIVEN = dict(gains="given", k_p=2.0, k_I=5.0, k_D=0.01)


@pytest.mark.parametrize("t_end", [0.0, -1.0, math.nan, math.inf])
def test_bad_horizon(t_end):
    with pytest.raises(SimulationError, match="t_end"):
        simulate(Parameters(**GIVEN), "macro", t_end=t_end)


def test_unknown_component_and_model():
    with pytest.raises(ModelError, match="second_motor"):
        simulate(Parameters(**GIVEN), "macro", 1.0, effects=("secnd_motor",))
    with pytest.raises(ModelError, match="micro"):
        component_names("mikro")
    with pytest.raises(ModelError, match="needs component 'kiln'"):
        simulate(Parameters(**GIVEN), components=("burden",), t_end=1.0)


def test_effect_replaces_gearbox():
    names = component_names("macro", add=("drivetrain_compliance",))
    assert "gearbox" not in names and "drivetrain_compliance" in names


def test_impossible_parameter_is_refused_before_simulating():
    with pytest.raises(ParameterError, match="J_p"):
        Parameters(J_p=0.0)


def test_unknown_initial_state():
    with pytest.raises(SimulationError, match="omega_kiln"):
        simulate(Parameters(**GIVEN), "macro", 1.0, initial={"omega_kil": 1.0})


def test_unstable_plant_is_an_error_not_a_nan():
    # Truth (Routh): L_a J s^3 + R_a J s^2 + (k_i k_b + K k_i k_p) s + K k_i k_I is unstable when
    # (R_a J)(k_i k_b + K k_i k_p) < (L_a J)(K k_i k_I); k_I = 1e6 V/(rpm s) violates it by 1e5 times.
    p = Parameters(gains="given", k_p=0.1, k_I=1e6, k_D=0.0)
    a3, a2 = p.L_a * p.J_stick, p.R_a * p.J_stick
    a1, a0 = p.k_i * p.k_b + p.K_fb * p.k_i * p.k_p, p.K_fb * p.k_i * p.k_I
    assert a2 * a1 < a3 * a0
    with pytest.raises(SimulationError, match="unstable"):
        simulate(p, "macro", 5.0, remove=("current_limit", "voltage_limit"))


def test_event_budget_names_the_mode_pair():
    p = Parameters(mu_c=0.005, mu_s=0.05, psi_0=0.3)
    with pytest.raises(EventStormError, match="burden"):
        simulate(p, components=("kiln", "kiln_fixed", "burden"), t_end=40.0, max_events=3)


def test_one_string_of_effects_and_a_number_for_the_model_are_named():
    # truth: the arguments typed here by hand; effects="second_motor" was read letter by letter ("unknown component
    # 's'") and model=1 ended in a TypeError inside difflib
    from kilnctl.errors import ModelError
    from kilnctl.simulate import simulate

    with pytest.raises(ModelError, match=r"effects = 'second_motor' must be a list of names.*\['second_motor'\]"):
        simulate(None, t_end=2.0, effects="second_motor")
    with pytest.raises(ModelError, match=r"remove = 'current_limit' must be a list"):
        simulate(None, t_end=2.0, remove="current_limit")
    with pytest.raises(ModelError, match=r"unknown model 1: valid names are: macro, micro"):
        simulate(None, model=1, t_end=2.0)


@pytest.mark.parametrize("kw, said", [({"rtol": -1.0}, "rtol = -1.0"), ({"rtol": "1e-6"}, "rtol = '1e-6'"),
                                      ({"atol": 0.0}, "atol = 0.0"), ({"max_step": -1.0}, "max_step = -1.0"),
                                      ({"n_grid": 0}, "n_grid = 0")])
def test_tolerances_and_steps_that_are_not_positive_numbers_are_named(kw, said):
    # truth: the values typed here by hand; rtol = -1 ran and returned a result, a string was a TypeError of the
    # compiled stepper, max_step = -1 was blamed on "the loop is probably unstable with these gains"
    with pytest.raises(SimulationError, match=rf"^{re.escape(said)} must be"):
        simulate(None, t_end=2.0, **kw)
