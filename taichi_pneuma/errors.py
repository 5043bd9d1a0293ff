"""The one exception type for mistakes a user can make (bad parameters, bad files, bad paths)."""


class PneumaInputError(ValueError):
    """A user-supplied value is not allowed; the message names the value and what is allowed."""


def require(condition: bool, message: str) -> None:
    """Raise PneumaInputError(message) unless condition holds."""
    if not condition:
        raise PneumaInputError(message)


def require_finite(name: str, value: float) -> float:
    """Return value as float if it is a finite number, else raise naming it."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise PneumaInputError(f"{name} = {value!r} is not a number") from None
    require(v == v and abs(v) != float("inf"), f"{name} = {value!r} must be a finite number")
    return v
