"""Exceptions raised by kilnctl.

Every error a user can cause derives from :class:`KilnctlError`, and also from
the matching built-in (``ValueError``, ``RuntimeError`` ...), so callers may
catch either.  Messages name the offending parameter, file or option and say
how to fix it.
"""

from __future__ import annotations

import difflib

__all__ = [
    "KilnctlError",
    "ParameterError",
    "ConfigFileError",
    "ModelError",
    "SimulationError",
    "EventStormError",
    "DesignError",
    "DataError",
    "NotFittedError",
    "OptimizationError",
    "WorkerError",
    "close_matches_hint",
    "name_list",
]


class KilnctlError(Exception):
    """Base class of every error kilnctl raises on purpose."""


class ParameterError(KilnctlError, ValueError):
    """A parameter name or value is unknown or physically impossible."""


class ConfigFileError(KilnctlError, ValueError):
    """A configuration file cannot be read or does not have the expected form."""


class ModelError(KilnctlError, ValueError):
    """A plant cannot be assembled (unknown component, missing dependency)."""


class SimulationError(KilnctlError, RuntimeError):
    """A simulation could not be completed (bad horizon, integrator failure)."""


class EventStormError(SimulationError):
    """The hybrid simulation switched modes too often: it names the mode pair."""


class DesignError(KilnctlError, ValueError):
    """A controller design request is malformed or cannot be met at all."""


class DataError(KilnctlError, ValueError):
    """A measurement file is malformed: names the file, line and column."""


class NotFittedError(KilnctlError, RuntimeError):
    """An estimator was used before ``fit`` was called."""


class OptimizationError(KilnctlError, RuntimeError):
    """An optimization failed or is infeasible: carries the solver status."""


class WorkerError(KilnctlError, RuntimeError):
    """A worker process of a parallel job ended abruptly: says the usual cause and the fix."""

    @classmethod
    def abrupt(cls, what: str, serial: str) -> "WorkerError":
        """The error for a process pool whose worker ended abruptly (``BrokenProcessPool``).

        Parameters
        ----------
        what : str
            The call that used the pool, e.g. ``"Diagnosis(workers=2)"``.
        serial : str
            The argument that runs the same job in this process, e.g. ``"workers=1"``.

        Returns
        -------
        WorkerError
        """
        return cls(f"{what}: a worker process ended abruptly. Python starts each worker by importing the script "
                   "that runs the job: a script's own code must sit under `if __name__ == \"__main__\":` "
                   "(otherwise every worker runs the script again and stops). Otherwise a worker was killed "
                   f"(out of memory?): run with {serial} to see any error in this process.")


def close_matches_hint(name: str, known) -> str:
    """Return a "did you mean ..." sentence for an unknown ``name``.

    Parameters
    ----------
    name : str
        The unknown name the user gave.
    known : iterable of str
        The valid names.

    Returns
    -------
    str
        A sentence listing up to three close matches, or all valid names when
        none is close.
    """
    name = str(name)  # a number where a name belongs (model=1) is still "unknown", not a TypeError of difflib
    known = sorted(set(known))  # callers may pass a list with a name twice (an effect that is also a component)
    close = difflib.get_close_matches(name, known, n=3, cutoff=0.5)
    if not close:
        close = [k for k in known if k.lower() == name.lower()]
    if close:
        return "did you mean " + " or ".join(repr(c) for c in close) + "?"
    return "valid names are: " + ", ".join(known)


def name_list(value, what: str, error: type = ParameterError) -> tuple:
    """Return a sequence of names as a tuple; one string is refused (it would be read letter by letter).

    Parameters
    ----------
    value : sequence of str
        The names the caller gave (``effects``, ``candidates``, ``calibrate`` ...).
    what : str
        The argument's name, for the message.
    error : type, default ParameterError
        Exception class raised.

    Returns
    -------
    tuple of str

    Raises
    ------
    ParameterError
        ``value`` is a string (``effects="second_motor"`` read as 's', 'e', 'c' ...) or not iterable.
    """
    if isinstance(value, str):
        raise error(f"{what} = {value!r} must be a list of names, not one string: write {what}=[{value!r}]")
    try:
        return tuple(value)
    except TypeError:
        raise error(f"{what} = {value!r} must be a list of names, e.g. {what}=['second_motor']") from None
