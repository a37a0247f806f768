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


@pytest.mark.parametrize("name", sorted(CATALOGUE))
def test_every_catalogue_effect_simulates_and_linearizes(name):
    from kilnctl.linearize import linearize
    from kilnctl.measure.effects import effect_components
    from kilnctl.simulate import simulate

    eff = CATALOGUE[name]
    model = eff.model or "macro"
    extra, params = effect_components([name], Parameters(), model)
    comps = component_names(model, extra)
    r = simulate(params, components=comps, t_end=10.0)
    assert np.all(np.isfinite(r["i_a"])) and r.t[-1] == pytest.approx(10.0)
    lin = linearize(params, components=comps, t_op=10.0)
    A = np.asarray(lin.sys.A)
    assert A.shape == (len(lin.x_op), len(lin.x_op)) and np.all(np.isfinite(A))
    assert np.all(np.isfinite(lin.poles()))
