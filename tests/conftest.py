"""Tests run on Taichi's CPU backend (float64). The reference scene's full ramps are solved once per session
and shared (reference_ramp). The on-disk mesh cache (io/cache.py) is off: every test meshes afresh and none
reads or writes the user's cache folder (tests/test_fixed_costs.py turns it on in a folder of its own)."""

import pytest

from taichi_pneuma import runtime
from taichi_pneuma.io import cache


@pytest.fixture(scope="session", autouse=True)
def no_mesh_cache():
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv(cache.VARIABLE, "off")
        yield


@pytest.fixture
def cache_dir(tmp_path, monkeypatch):
    """The mesh cache on, in a folder of the test's own (tests/test_fixed_costs.py, tests/test_trust_fibres.py)."""
    folder = tmp_path / "cache"
    monkeypatch.setenv(cache.VARIABLE, str(folder))
    return folder


@pytest.fixture(scope="session", autouse=True)
def taichi_cpu():
    runtime.init("cpu")


@pytest.fixture(scope="session")
def reference_ramp(taichi_cpu):
    """reference_ramp(cy): (built scene, Result) of the reference scene's full ramp (35 increments to 3.5x on
    its 1632-vertex mesh) with the chamber at height cy, solved the first time it is asked for. Callers read
    it and leave it as it is."""
    from taichi_pneuma.result import Result
    from taichi_pneuma.scene.build import reference_scene
    from taichi_pneuma.solve.simulate import run_schedule

    ramps = {}

    def ramp(cy: float):
        if cy not in ramps:
            built = reference_scene(cy=cy).build()
            ramps[cy] = built, Result.of(run_schedule(built))
        return ramps[cy]

    return ramp
