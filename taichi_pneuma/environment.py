"""The environment variables that choose an implementation, and their check: PNEUMA_BACKEND names the kernels'
compiler (backend.py), PNEUMA_TRIANGLE the Triangle binding (fem/triangulation.py); unset, the first installed
of each is used. This module imports neither, so the commands can check the variables before either loads."""

from __future__ import annotations

import importlib.util
import os

from .errors import quoted, require

BACKENDS = ("taichi", "quadrants")  # what PNEUMA_BACKEND may name (backend.py)
TRIANGLE_BINDINGS = ("triangle", "meshpy")  # what PNEUMA_TRIANGLE may name (fem/triangulation.py)
CHOICES = {"PNEUMA_BACKEND": BACKENDS, "PNEUMA_TRIANGLE": TRIANGLE_BINDINGS}


def check_environment() -> None:
    """Refuse (PneumaInputError) a variable of CHOICES set to a name not among its choices, or to a module not
    installed here; the commands ask this first, before any run or worker starts."""
    for variable, names in CHOICES.items():
        value = os.environ.get(variable, "")
        if value:
            require(
                value in names,
                f"environment variable {variable}={quoted(value)} is not one of {', '.join(names)} (or unset)",
            )
            require(
                importlib.util.find_spec(value) is not None,
                f"environment variable {variable}={value}, but {value} is not installed here",
            )
