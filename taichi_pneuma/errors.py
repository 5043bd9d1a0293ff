"""The one exception type for mistakes a user can make (bad parameters, bad files, bad paths)."""

import numpy as np


class PneumaInputError(ValueError):
    """A user-supplied value is not allowed; the message names the value and what is allowed."""


MAX_QUOTED = 200  # characters of a user's value quoted in a message


def quoted(value) -> str:
    """repr(str(value)) for a message; a value of more than MAX_QUOTED characters is cut to its first ones and its
    length."""
    text = str(value)
    if len(text) <= MAX_QUOTED:
        return repr(text)
    return f"{text[:MAX_QUOTED]!r}... ({len(text)} characters)"


def require(condition: object, message: str) -> None:
    """Raise PneumaInputError(message) unless condition holds (is true: a bool, a NumPy bool, a non-empty list)."""
    if not condition:
        raise PneumaInputError(message)


def require_distinct(label: str, values: list) -> None:
    """Raise naming the values (label: what they are, e.g. 'chamber names') unless no two are equal."""
    require(len(set(values)) == len(values), f"{label} {values!r} must be distinct")


def require_finite(name: str, value: float) -> float:
    """Return value as float if it is a finite number, else raise naming it."""
    try:
        if isinstance(value, (str, bytes, bool)):
            raise TypeError
        v = float(value)
    except (TypeError, ValueError):
        raise PneumaInputError(f"{name} = {value!r} is not a number") from None
    except OverflowError:  # an integer past the float range
        v = float("inf")
    require(v == v and abs(v) != float("inf"), f"{name} = {value!r} must be a finite number")
    return v


def require_positive(name: str, value, allow_none: bool = False) -> None:
    """Raise naming the value unless it is a finite number (require_finite) > 0; with allow_none, None passes too
    (a default the Scene resolves later, units.si_default)."""
    if value is None and allow_none:
        return
    require(require_finite(name, value) > 0, f"{name} = {value!r} must be > 0")


def parse_number(name: str, text: str) -> float:
    """Text (a command-line or CSV field) as a float; whether it is finite and in range is the caller's check."""
    try:
        return float(text)
    except ValueError:
        raise PneumaInputError(f"{name} = {text!r} is not a number") from None


def shape_of(value) -> tuple | None:
    """np.shape(value), or None where value is ragged (lists of different lengths) and has no shape."""
    try:
        return np.shape(value)
    except ValueError:
        return None
