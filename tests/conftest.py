"""Tests run on Taichi's CPU backend (float64)."""

import pytest

from taichi_pneuma import runtime


@pytest.fixture(scope="session", autouse=True)
def taichi_cpu():
    runtime.init("cpu")
