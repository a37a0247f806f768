"""Every public function and method of the ramp optimization documents each of its parameters.

Truth: the numpydoc convention (STYLE.md, practice 8): a ``Parameters`` section that
names every argument of the signature.
"""

import importlib
import inspect
import pkgutil
import re

import pytest

import kilnctl.optimize

MODULES = ["kilnctl.model.ramps", "kilnctl.model.smooth", "kilnctl.cli.optimize_cmd"] + sorted(
    m.name for m in pkgutil.walk_packages(kilnctl.optimize.__path__, "kilnctl.optimize."))
#: CasADi Callback protocol methods (their meaning is CasADi's)
CASADI_PROTOCOL = {"get_n_in", "get_n_out", "get_sparsity_in", "get_sparsity_out", "eval", "has_jacobian",
                   "get_jacobian", "init", "finalize"}
#: component phase methods documented once on kilnctl.model.base.Component
COMPONENT_PHASES = {"declare", "signals", "loads", "finish", "initial_state", "initial_mode", "reference"}


def _public_callables():
    for name in MODULES:
        mod = importlib.import_module(name)
        for attr, obj in vars(mod).items():
            if attr.startswith("_") or getattr(obj, "__module__", None) != name:
                continue
            if inspect.isfunction(obj):
                yield f"{name}.{attr}", obj
            elif inspect.isclass(obj):
                yield f"{name}.{attr}", obj
                for m, f in vars(obj).items():
                    if inspect.isfunction(f) and not m.startswith("_") and m not in CASADI_PROTOCOL | COMPONENT_PHASES:
                        yield f"{name}.{attr}.{m}", f


def _documented(doc: str) -> set:
    sec = re.search(r"Parameters\n-+\n(.*?)(\n\n[A-Z][a-z]+\n-+\n|\Z)", doc, re.S)
    if not sec:
        return set()
    names = set()
    for line in sec.group(1).splitlines():
        m = re.match(r"^(\*{0,2}[A-Za-z_][\w, *]*?)\s*(:|$)", line)
        if m and not line.startswith(" "):
            names.update(n.strip().lstrip("*") for n in m.group(1).split(","))
    return names


@pytest.mark.parametrize("qualname, obj", list(_public_callables()), ids=lambda x: x if isinstance(x, str) else "")
def test_every_parameter_is_documented(qualname, obj):
    doc = inspect.getdoc(obj) or ""
    assert doc.strip(), f"{qualname} has no docstring"
    if inspect.isclass(obj):
        return
    params = [p for p in inspect.signature(obj).parameters.values()
              if p.name not in ("self", "cls")]
    if not params:
        return
    missing = {p.name for p in params} - _documented(doc)
    assert not missing, f"{qualname}: parameters not documented: {sorted(missing)}"
