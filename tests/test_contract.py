"""Contract between the component registry, the parameter specs and the effect catalogue (issue 13 item 2).

Adding a physical effect touches the component (kilnctl/model), its parameters (kilnctl/params.SPECS) and
its catalogue entry (kilnctl/measure/effects.CATALOGUE); these tests keep the three agreeing. Truth: the
declarations themselves (every name used is declared, with a unit and a source), and the plant: every
catalogue effect must assemble, simulate a start-up and linearize to a finite model.
"""

import numpy as np
import pytest

from kilnctl import Parameters
from kilnctl.measure.effects import CATALOGUE
from kilnctl.model import REGISTRY, component_names
from kilnctl.params import SPECS


@pytest.mark.parametrize("name", sorted(REGISTRY))
def test_every_component_parameter_is_declared_with_unit_and_source(name):
    import re

    for p in REGISTRY[name].param_names:
        derived = getattr(Parameters, p, None)
        if p not in SPECS and isinstance(derived, property):  # derived from declared ones, e.g. n_r = n / n_p
            assert re.search(r"\[[^\]]+\]", derived.__doc__ or ""), f"derived parameter {p!r} states no unit"
            continue
        assert p in SPECS, f"component {name!r} uses parameter {p!r}, which params.SPECS does not declare"
        spec = SPECS[p]
        assert spec.unit, f"parameter {p!r} of {name!r} has no unit"
        assert spec.source, f"parameter {p!r} of {name!r} has no source"


@pytest.mark.parametrize("name", sorted(CATALOGUE))
def test_every_catalogue_effect_is_declared(name):
    eff = CATALOGUE[name]
    for c in eff.components:
        assert c in REGISTRY, f"effect {name!r} adds component {c!r}, which is not registered"
    for p in eff.parameters:
        assert p.name in SPECS, f"effect {name!r} fits {p.name!r}, which params.SPECS does not declare"
        assert SPECS[p.name].unit
    for k in eff.options:
        assert k in SPECS and SPECS[k].choices, f"effect {name!r} sets option {k!r}, not a declared option"


def _structure(name):
    """Components and parameters of the catalogue effect ``name`` on the model it needs."""
    from kilnctl.measure.effects import effect_components

    model = CATALOGUE[name].model or "macro"
    extra, params = effect_components([name], Parameters(), model)
    return component_names(model, extra), params


@pytest.mark.parametrize("name", sorted(CATALOGUE))
def test_every_catalogue_effect_simulates_and_linearizes(name):
    from kilnctl.linearize import linearize
    from kilnctl.simulate import simulate

    comps, params = _structure(name)
    r = simulate(params, components=comps, t_end=10.0)
    assert np.all(np.isfinite(r["i_a"])) and r.t[-1] == pytest.approx(10.0)
    lin = linearize(params, components=comps, t_op=10.0)
    A = np.asarray(lin.sys.A)
    assert A.shape == (len(lin.x_op), len(lin.x_op)) and np.all(np.isfinite(A))
    assert np.all(np.isfinite(lin.poles()))


# --- one declaration per effect: the derived tables are exactly what the components declare ------------------

def _own(comp, attr):
    return vars(comp).get(attr, ())


def test_specs_are_exactly_the_components_declarations():
    # truth: the declarations on the component classes themselves; each parameter has one owner
    from kilnctl.params import GROUPS, RegistryView

    declared = [s for c in REGISTRY.values() for s in _own(c, "parameters")]
    assert isinstance(SPECS, RegistryView)
    assert len({s.name for s in declared}) == len(declared), "a parameter is declared by two components"
    assert dict(SPECS) == {s.name: s for s in declared}
    for s in declared:
        assert s.group in GROUPS and s.unit and s.source and s.description, s.name
        assert s.rule in ("finite", "positive", "nonnegative", "fraction"), s.name
        if s.is_option:
            assert s.default in s.choices, s.name
    assert Parameters().as_dict() == {s.name: s.default for s in declared}  # every default passes its own bound


def test_catalogue_is_exactly_the_components_entries():
    # truth: the entries on the component classes; the owner's physics is in the structure the entry builds
    from kilnctl.model import MODELS

    entries = {e.name: (c.name, e) for c in REGISTRY.values() for e in _own(c, "catalogue")}
    assert list(CATALOGUE) == list(entries)
    for name, (owner, eff) in entries.items():
        assert CATALOGUE[name] is eff
        assert owner in eff.components or owner in MODELS[eff.model or "macro"], (name, owner)
        for fp in eff.parameters:  # fitting bounds lie within the declaration's own bound
            spec = SPECS[fp.name]
            assert fp.lower < fp.upper, fp.name
            if spec.rule in ("positive", "nonnegative", "fraction"):
                assert fp.lower >= 0, fp.name


@pytest.mark.parametrize("name", sorted(REGISTRY))
def test_component_uses_what_it_declares(name):
    # a numeric parameter a component owns is one it uses (listed in param_names: calibration, describe)
    comp = REGISTRY[name]
    for s in _own(comp, "parameters"):
        if not s.is_option:
            assert s.name in comp.param_names, f"{name!r} declares {s.name!r} but does not list it in param_names"
    if comp.modes and comp.smooth_twin:
        twin = REGISTRY[comp.smooth_twin]
        assert not twin.modes and twin.replaces == (name,) and set(twin.param_names) == set(comp.param_names)


def test_optimizer_component_lists_are_derived_from_models():
    # truth: MODELS['micro'] as declared, with each moded component replaced by its twin and the limits left out
    from kilnctl.model import MODELS
    from kilnctl.optimize.model import _HYBRID_CORE, _SMOOTH_CORE

    assert ("ramp",) + _HYBRID_CORE == MODELS["micro"]
    expected = tuple(REGISTRY[c].smooth_twin or c for c in _HYBRID_CORE if c not in ("voltage_limit", "current_limit"))
    assert _SMOOTH_CORE == expected
    assert all(not REGISTRY[c].modes for c in _SMOOTH_CORE)


@pytest.mark.parametrize("name", sorted(CATALOGUE))
def test_every_catalogue_effect_smooths(name):
    # the smooth twin of the structure with the effect has no modes besides the ramp's and runs a start-up;
    # truth: the hybrid structure itself, whose speed at the end of the ramp the twin must reach within 2 %
    # (the smoothing widths are 1 um of mesh penetration and 1e-4 rad/s of burden creep)
    from kilnctl.model import get_plant
    from kilnctl.model.smooth import smooth_names
    from kilnctl.simulate import simulate

    hybrid, params = _structure(name)
    smooth = smooth_names(hybrid)
    assert [c.name for c in get_plant(smooth, params).moded] == ["ramp"]
    rs = simulate(params, components=smooth, t_end=8.0)
    rh = simulate(params, components=hybrid, t_end=8.0)
    assert np.all(np.isfinite(rs["i_a"]))
    assert rs["speed_rpm"][-1] == pytest.approx(rh["speed_rpm"][-1], rel=0.02)


def test_optimizer_refuses_an_effect_with_modes_and_no_twin_and_takes_one_with_a_twin():
    # truth: the declarations: current_limit has modes and no smooth_twin, motor_coulomb_friction names its twin
    from kilnctl.errors import ModelError
    from kilnctl.optimize.model import check_effects, hybrid_components, smooth_components
    from kilnctl.optimize.problem import Profile

    with pytest.raises(ModelError, match="'current_limit'.*modes and no smooth twin"):
        check_effects(("current_limit",))
    prof = Profile.parse("constant")
    for name, comp in REGISTRY.items():
        if comp.modes and comp.smooth_twin and name not in component_names("micro"):
            assert check_effects((name,)) == (name,)
            assert comp.smooth_twin in smooth_components(prof, (name,)) and name not in smooth_components(prof, (name,))
            assert name in hybrid_components(prof, (name,))
