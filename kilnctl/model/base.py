"""Building blocks of the symbolic plant: states, guards and components.

A *component* is one physical effect with a name, its parameters and its
documentation (``dc_motor``, ``burden``, ``mesh`` ...).  A plant is assembled
from a list of component names.  Each component

* declares its continuous states (with units and a nominal scale) and its
  discrete modes (``declare``);
* contributes signals, torques and rigid links for a given mode
  (``signals``, ``loads``);
* and, once the mechanical accelerations are known, its remaining state
  derivatives, its guards (mode-switch conditions) and its outputs
  (``finish``).

Parameters enter the equations as CasADi symbols, so one compiled structure
serves every parameter value; string options (``friction_law`` ...) select
the structure.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable, ClassVar

import casadi as ca

from ..errors import ModelError, close_matches_hint
from ..params import SPECS, ParamSpec, Parameters

__all__ = ["StateVar", "Guard", "Component", "REGISTRY", "register", "SymParams", "OPTION_NAMES",
           "NUMERIC_NAMES", "option_names", "numeric_names"]


#: (declaration table, option names, numeric names): the split of the last declaration table seen, kept
#: until the registry changes (SPECS.snapshot() then returns a new table)
_NAMES: list = [None, (), ()]


def _split_names() -> list:
    table = SPECS.snapshot()
    if _NAMES[0] is not table:
        _NAMES[:] = [table, tuple(n for n, s in table.items() if s.is_option),
                     tuple(n for n, s in table.items() if not s.is_option)]
    return _NAMES


def option_names() -> tuple[str, ...]:
    """Names of the string options (they select the structure, not a value), in declaration order."""
    return _split_names()[1]


def numeric_names() -> tuple[str, ...]:
    """Names of the numeric parameters (symbolic inputs of every model function), in declaration order."""
    return _split_names()[2]


def __getattr__(name: str):
    # OPTION_NAMES and NUMERIC_NAMES are derived from the registered components' declarations when asked for
    if name == "OPTION_NAMES":
        return option_names()
    if name == "NUMERIC_NAMES":
        return numeric_names()
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


@dataclass(frozen=True)
class StateVar:
    """A continuous state of the plant.

    Attributes
    ----------
    name : str
        State name (``x_a``, ``omega_motor``, ``psi`` ...).
    unit : str
        Unit of the state.
    scale : float
        Nominal magnitude; the integrator works on ``x / scale``.
    doc : str
        What the state is.
    """

    name: str
    unit: str
    scale: float
    doc: str


@dataclass
class Guard:
    """A mode-switch condition of the current mode.

    The mode stays valid while ``expr > 0``; when it crosses zero the
    simulator switches the component's mode to ``target`` (or to
    ``alt_target`` when ``selector < 0``).

    Attributes
    ----------
    kind : str
        Physical name of the event (``breakaway``, ``restick``, ``contact``,
        ``separation``, ``current_limit`` ...).
    component : str
        Component whose mode changes.
    expr : casadi.SX
        Guard function, scaled to order one.
    target : str
        Mode entered when the guard crosses zero.
    alt_target : str, optional
        Mode entered instead when ``selector < 0``.
    selector : casadi.SX, optional
        Chooses between ``target`` and ``alt_target``.
    """

    kind: str
    component: str
    expr: ca.SX
    target: str
    alt_target: str | None = None
    selector: ca.SX | None = None


class SymParams:
    """Symbolic view of a parameter set: numbers are CasADi symbols.

    Attribute access returns the SX symbol of a numeric parameter, the string
    of an option, and evaluates the derived quantities of
    :class:`kilnctl.params.Parameters` (``n_p``, ``k_e``, ``J_kiln`` ...)
    symbolically.

    Parameters
    ----------
    options : dict
        Values of the string options (structure).
    names : sequence of str, optional
        The numeric parameters, in the order of the symbol vector (default:
        :func:`numeric_names` now; a plant passes the names it was built with).
    """

    def __init__(self, options: dict[str, str], names=None):
        self._options = dict(options)
        names = numeric_names() if names is None else tuple(names)
        self.vector = ca.SX.sym("P", len(names))
        self._sym = {name: self.vector[i] for i, name in enumerate(names)}

    def __getattr__(self, key: str):
        if key.startswith("_"):
            raise AttributeError(key)
        if key in self._sym:
            return self._sym[key]
        if key in self._options:
            return self._options[key]
        prop = getattr(Parameters, key, None)
        if isinstance(prop, property):
            return prop.fget(self)
        raise AttributeError(f"unknown parameter {key!r}: {close_matches_hint(key, SPECS)}")


class Component:
    """Base class of a physical effect.

    Subclasses set the class attributes and override the phase methods they
    need.  The docstring of a subclass is its user documentation.

    Attributes
    ----------
    name : str
        Registry name.
    summary : str
        One line shown in listings.
    param_names : tuple of str
        Parameters it uses (documentation and calibration).
    requires : tuple of str
        Components that must be present too.
    replaces : tuple of str
        Components it takes the place of when added as an effect.
    modes : tuple of str
        Its discrete modes; empty for a smooth component.
    parameters : tuple of ParamSpec
        The parameters it owns, declared once here (:func:`kilnctl.params.param`:
        name, default, unit, source, description, group, bound);
        :data:`kilnctl.params.SPECS` is derived from these.  Parameters it
        only uses (owned by another component) appear in ``param_names``.
    smooth_twin : str or None
        For a component with modes: the registered mode-free twin (same
        physics, switches regularised) that the ramp optimizer uses instead.
    catalogue : tuple of Effect
        Entries of the effect catalogue (:data:`kilnctl.measure.CATALOGUE`)
        this component stands for: what the diagnosis tries, with its
        residual signature, fitted parameters and starting points.
    phase_after : str or None
        For a component outside :data:`kilnctl.model.ORDER`: the component
        after which it is evaluated (default: just before ``bending_stress``).
    """

    name: ClassVar[str] = ""
    summary: ClassVar[str] = ""
    param_names: ClassVar[tuple[str, ...]] = ()
    requires: ClassVar[tuple[str, ...]] = ()
    replaces: ClassVar[tuple[str, ...]] = ()
    modes: ClassVar[tuple[str, ...]] = ()
    parameters: ClassVar[tuple[ParamSpec, ...]] = ()
    smooth_twin: ClassVar[str | None] = None
    catalogue: ClassVar[tuple] = ()
    phase_after: ClassVar[str | None] = None

    def declare(self, spec) -> None:
        """Declare states and mechanical nodes on the model spec."""

    def initial_mode(self, params: Parameters, x0: dict[str, float]) -> str | None:
        """Return the mode at t = 0 (default: the first of ``modes``)."""
        return self.modes[0] if self.modes else None

    def initial_state(self, params: Parameters) -> dict[str, float]:
        """Return initial values of this component's states (default zero)."""
        return {}

    def rest_kiln_torque(self, params: Parameters) -> float:
        """Return the torque this component puts on the kiln at rest at t = 0 [N*m] (default zero): what a drive
        that is on before the start-up holds (:mod:`kilnctl.model.rest`)."""
        return 0.0

    def held_state(self, params: Parameters, torque: float) -> dict[str, float]:
        """Return this component's states while the drive train carries ``torque`` to the kiln at rest [N*m]
        (default none: a rigid link; :mod:`kilnctl.model.rest`)."""
        return {}

    def signals(self, e, mode: str | None) -> None:
        """Phase 1: define signals (references, controller outputs, currents)."""

    def loads(self, e, mode: str | None) -> None:
        """Phase 2: add torques on nodes and rigid links."""

    def finish(self, e, mode: str | None) -> None:
        """Phase 3: state derivatives, guards and outputs (accelerations known)."""

    def sliding_mode(self, cycle: frozenset[str]) -> str | None:
        """Return the Filippov sliding mode for a zero-time cycle of modes.

        Parameters
        ----------
        cycle : frozenset of str
            Modes of this component that would switch into one another at
            once, without time passing (chattering).

        Returns
        -------
        str or None
            The mode that gives the cycle a defined meaning, or None.
        """
        return None


class _Registry(dict):
    """A dict of components whose ``version`` changes at every change, so that tables derived from it
    (:data:`kilnctl.params.SPECS`, the parameter names, the cached plants) know when to rebuild."""

    version = 0

    def _changed(self) -> None:
        self.version += 1

    def __setitem__(self, key, value):
        super().__setitem__(key, value)
        self._changed()

    def __delitem__(self, key):
        super().__delitem__(key)
        self._changed()

    def __ior__(self, other):
        super().__ior__(other)
        self._changed()
        return self

    def pop(self, *args):
        """Remove a component (see :meth:`dict.pop`)."""
        try:
            return super().pop(*args)
        finally:
            self._changed()

    def popitem(self):
        """Remove the last component (see :meth:`dict.popitem`)."""
        try:
            return super().popitem()
        finally:
            self._changed()

    def clear(self):
        """Remove every component."""
        super().clear()
        self._changed()

    def update(self, *args, **kwargs):
        """Add or replace components (see :meth:`dict.update`)."""
        super().update(*args, **kwargs)
        self._changed()

    def setdefault(self, key, default=None):
        """See :meth:`dict.setdefault`."""
        try:
            return super().setdefault(key, default)
        finally:
            self._changed()


#: all known components, by name (a dict whose ``version`` counts its changes)
REGISTRY: dict[str, type[Component]] = _Registry()


def register(cls: type[Component]) -> type[Component]:
    """Class decorator adding a component to :data:`REGISTRY`.

    Parameters
    ----------
    cls : type
        A :class:`Component` subclass with a unique ``name``.

    Returns
    -------
    type
        ``cls`` unchanged.
    """
    if not cls.name or cls.name in REGISTRY:
        raise ModelError(f"component name {cls.name!r} is empty or registered twice")
    REGISTRY[cls.name] = cls
    return cls


@dataclass
class NodeDecl:
    """A rotating body of the drive train (its speed is a state)."""

    name: str
    doc: str


@dataclass
class ModelSpec:
    """What the components declared: states, nodes and modes, in order."""

    states: list[StateVar] = field(default_factory=list)
    nodes: list[NodeDecl] = field(default_factory=list)

    def add_state(self, name: str, unit: str, scale: float, doc: str) -> None:
        """Declare a continuous state (name must be new)."""
        if any(s.name == name for s in self.states):
            raise ModelError(f"state {name!r} declared twice: two components claim it")
        self.states.append(StateVar(name, unit, float(scale), doc))

    def add_node(self, name: str, doc: str, speed_scale: float) -> None:
        """Declare a rotating body; its speed state is ``omega_<name>`` [rad/s]."""
        if any(n.name == name for n in self.nodes):
            raise ModelError(f"node {name!r} declared twice")
        self.nodes.append(NodeDecl(name, doc))
        self.add_state(f"omega_{name}", "rad/s", speed_scale, f"angular velocity of {doc}")


Transition = Callable[..., str]
