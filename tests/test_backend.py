"""The backend choice (taichi_pneuma/backend.py): a forced backend that is missing, or unknown, is one clear
error naming what to do; the kernel cache goes where the backend's own environment variable says."""

import os
import subprocess
import sys

from taichi_pneuma import backend


def python(code: str, **env) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-c", code], env={**os.environ, **env}, capture_output=True, text=True)


def test_a_forced_backend_that_does_not_import_names_its_install_command():
    other = "quadrants" if backend.NAME == "taichi" else "taichi"
    proc = python(f"import sys; sys.modules[{other!r}] = None; import taichi_pneuma.backend", PNEUMA_BACKEND=other)
    assert proc.returncode != 0
    last = proc.stderr.strip().splitlines()[-1]
    assert f"PNEUMA_BACKEND={other}, but {other} does not import" in last and backend.INSTALL[other] in last


def test_an_unknown_backend_is_named():
    proc = python("import taichi_pneuma.backend", PNEUMA_BACKEND="jax")
    assert "PNEUMA_BACKEND='jax' is not one of taichi, quadrants" in proc.stderr.strip().splitlines()[-1]


def test_the_kernel_cache_goes_where_the_backends_variable_says(tmp_path):
    """TI_OFFLINE_CACHE_FILE_PATH for Taichi, QD_OFFLINE_CACHE_FILE_PATH for Quadrants: a kernel compiled
    in a fresh process is written under it."""
    code = (
        "from taichi_pneuma import runtime; runtime.init('cpu'); "
        "from taichi_pneuma.scene.build import reference_scene; "
        "reference_scene(0.15, max_area=0.05).build().model.energy()"
    )
    proc = python(code, **{backend.environment_name("cache"): str(tmp_path / "cache"), "PNEUMA_BACKEND": backend.NAME})
    assert proc.returncode == 0, proc.stderr
    assert any(path.is_file() for path in (tmp_path / "cache").rglob("*"))
