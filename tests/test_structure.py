"""The plant-structure object (kilnctl.structure.Structure) and the functions that take it.

Truths: the component tuples and keywords the same functions took before a Structure existed
(``component_names``, ``effects=``, ``friction_law`` set by hand): a Structure must give the very same plant,
run and linearization; the component lists are checked against ``MODELS`` written out by hand; a diagnosis
file's effects are the ones written in it.
"""

import json

import numpy as np
import pytest

from kilnctl import Parameters
from kilnctl.errors import ConfigFileError, ModelError
from kilnctl.model import MODELS, component_names
from kilnctl.structure import PRESETS, Structure


def test_presets_are_the_papers_models():
    # hand-written from the paper's macro model (eqs. 1-21) as kilnctl.model.MODELS declares it
    assert PRESETS["macro"].components() == ("ramp", "pid", "voltage_limit", "dc_motor", "current_limit",
                                             "gearbox", "kiln", "bearing_friction", "burden", "bending_stress")
    assert {n: s.components() for n, s in PRESETS.items()} == MODELS


def test_components_effects_and_options():
    s = Structure("macro", ("drivetrain_compliance", "torque_friction_law"), ("current_limit",))
    # drivetrain_compliance replaces the rigid gearbox; the friction law is an option, not a component
    assert "gearbox" not in s.components() and "drivetrain_compliance" in s.components()
    assert "current_limit" not in s.components()
    assert s.components() == component_names("macro", ["drivetrain_compliance"], ["current_limit"])
    assert s.options == {"friction_law": "torque"}
    assert s.apply(Parameters()).friction_law == "torque"
    assert str(s) == "macro + drivetrain_compliance + torque_friction_law - current_limit (friction_law = 'torque')"
    # with_effects keeps the order and each name once; the object is frozen and hashable
    t = Structure("macro").with_effects("second_motor").with_effects("speed_sensor_lag", "second_motor")
    assert t.effects == ("second_motor", "speed_sensor_lag") and t == Structure("macro", ["second_motor",
                                                                                           "speed_sensor_lag"])
    assert hash(t) == hash(Structure("macro", ("second_motor", "speed_sensor_lag")))
    # it stands where a component tuple stood (learned_structure returned a tuple before)
    assert tuple(t) == t.components() and list(t) == list(t.components()) and "second_motor" in t
    assert "mesh" in PRESETS["micro"] and "mesh" not in PRESETS["macro"]


@pytest.mark.parametrize("bad, match", [
    (dict(model="mcro"), "macro"),                         # close match named
    (dict(effects=("second_motr",)), "second_motor"),
    (dict(effects="second_motor"), "sequence of names"),   # a bare string is not a list of names
    (dict(effects=("backlash",)), "micro"),                # backlash needs the micro model
    (dict(remove=("mesh",)), "mesh"),                      # not in the macro model
])
def test_bad_structures_are_refused_by_name(bad, match):
    with pytest.raises(ModelError, match=match):
        Structure(**bad)


def test_simulate_with_a_structure_is_the_tuple_run():
    from kilnctl.gains import resolve_gains
    from kilnctl.simulate import simulate

    p = resolve_gains(Parameters())
    by_tuple = simulate(p, "macro", 15.0, effects=["second_motor"])
    by_structure = simulate(p, components=Structure("macro", ("second_motor",)), t_end=15.0)
    assert by_structure.model == "macro" and by_structure.components == by_tuple.components
    np.testing.assert_allclose(by_structure["i_a"], by_tuple["i_a"], rtol=1e-12, atol=1e-9)
    # an effect that is an option: the structure sets friction_law = 'torque' itself
    by_hand = simulate(p.replace(friction_law="torque"), "macro", 15.0)
    by_law = simulate(p, components=Structure("macro", ("torque_friction_law",)), t_end=15.0)
    assert by_law.params.friction_law == "torque"
    np.testing.assert_allclose(by_law["i_a"], by_hand["i_a"], rtol=1e-12, atol=1e-9)
    with pytest.raises(ModelError, match="inside the Structure"):
        simulate(p, components=Structure("macro"), effects=["second_motor"])


def test_linearize_with_a_structure_is_the_tuple_linearization():
    from kilnctl.linearize import linearize

    names = component_names("macro", ["second_motor"])
    a = linearize(Parameters(), components=names, burden="stick")
    b = linearize(Parameters(), components=Structure("macro", ("second_motor",)), burden="stick")
    np.testing.assert_allclose(b.sys.A, a.sys.A, rtol=1e-12, atol=1e-12)
    assert b.components == names


def test_check_gains_with_a_structure_is_the_tuple_check():
    from kilnctl.design.learned import check_gains

    p = Parameters(J_m2=21.5)
    a = check_gains(p, component_names("macro", ["second_motor"]))
    b = check_gains(p, Structure("macro", ("second_motor",)))
    assert b.zeta_min == pytest.approx(a.zeta_min, abs=1e-12) and b.components == a.components


def _diagnosis(tmp_path, selected, model="macro"):
    # the keys kilnctl diagnose --json writes (measure/report.diagnosis_dict): selected, final_parameters, settings
    d = {"selected": selected, "final_parameters": {"J_m2": {"value": 33.0, "stderr": 1.0}, "mu_c": {"value": 0.41}},
         "settings": {"model": model, "calibrate": ["mu_c"]}, "baseline": {}}
    f = tmp_path / "diagnose.json"
    f.write_text(json.dumps(d))
    return f, d


def test_from_diagnosis_gives_the_effects_written_in_it(tmp_path):
    from kilnctl.design.learned import learned_structure

    f, d = _diagnosis(tmp_path, ["second_motor", "torque_friction_law"])
    s = Structure.from_diagnosis(f)
    assert s == Structure("macro", ("second_motor", "torque_friction_law"))
    assert Structure.from_diagnosis(d) == s                      # the JSON already read
    assert Structure.from_diagnosis(f, model="micro").model == "micro"

    class Fitted:  # what a fitted Diagnosis offers
        def to_dict(self):
            return d

    assert Structure.from_diagnosis(Fitted()) == s
    structure, params, selected = learned_structure(f)
    assert structure == s and selected == d["selected"]
    assert (params.J_m2, params.mu_c, params.friction_law) == (33.0, 0.41, "torque")


def test_a_file_that_is_not_a_diagnosis_is_refused(tmp_path):
    bad = tmp_path / "x.json"
    bad.write_text('{"x": 1}')
    with pytest.raises(ConfigFileError, match="not a diagnosis"):
        Structure.from_diagnosis(bad)
    with pytest.raises(ConfigFileError, match="cannot read"):
        Structure.from_diagnosis(tmp_path / "missing.json")


def test_ramp_problem_and_study_take_a_structure():
    from kilnctl.optimize import RampProblem
    from kilnctl.sweep import Grid, Study

    p = Parameters()
    s = Structure("micro", ("second_motor", "viscous_drag"))
    assert RampProblem(p, effects=s).effects == RampProblem(p, effects=("second_motor", "viscous_drag")).effects
    with pytest.raises(Exception, match="micro"):
        RampProblem(p, effects=Structure("macro", ("second_motor",)))
    grid = Grid({"m_v": [300e3, 600e3]})
    by_keywords = Study(grid, model="micro", effects=("second_motor", "viscous_drag"))
    by_structure = Study(grid, model=s)
    ps = by_keywords.parameter_sets()[0]
    # the same cache key: the same simulation, found in the same cache
    assert by_structure.task(ps)["key"] == by_keywords.task(ps)["key"]
    assert by_structure.task(ps)["structure"].components() == by_keywords.task(ps)["structure"].components()


def test_cli_simulate_remove_and_catalogue_effects(capsys):
    from kilnctl.cli import main
    from kilnctl.gains import resolve_gains
    from kilnctl.simulate import simulate

    assert main(["simulate", "--t-end", "15", "--effects", "torque_friction_law", "--remove", "current_limit",
                 "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert "current_limit" not in out["components"] and out["friction_law"] == "torque"
    direct = simulate(resolve_gains(Parameters(friction_law="torque")), "macro", 15.0, remove=["current_limit"])
    assert out["peak_current_A"] == pytest.approx(float(np.max(np.abs(direct["i_a"]))), rel=1e-9)
