"""The package as released: every app answers --version with the package's version (from the console script
pyproject.toml names), and the wheel's package data lists the shipped scenes the apps load by name."""

import importlib
import tomllib
from pathlib import Path

import pytest

import taichi_pneuma as tp

ROOT = Path(__file__).resolve().parent.parent
PYPROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text())
SCRIPTS = PYPROJECT["project"]["scripts"]


@pytest.mark.parametrize("script", sorted(SCRIPTS))
def test_every_app_prints_the_package_version(script, capsys):
    module, _, function = SCRIPTS[script].partition(":")
    main = getattr(importlib.import_module(module), function)
    with pytest.raises(SystemExit) as exit_:
        main(["--version"])
    assert exit_.value.code == 0
    assert capsys.readouterr().out.strip() == f"{script} {tp.__version__}"


def test_the_version_is_a_release_number():
    assert all(part.isdigit() for part in tp.__version__.split("."))
    assert PYPROJECT["project"]["dynamic"] == ["version"]  # read from taichi_pneuma.__version__, written once


def test_package_data_holds_every_shipped_file():
    """Every file under taichi_pneuma/scenes matches a package-data pattern, so the wheel carries it."""
    patterns = PYPROJECT["tool"]["setuptools"]["package-data"]["taichi_pneuma"]
    package = ROOT / "taichi_pneuma"
    shipped = [p.relative_to(package) for p in (package / "scenes").rglob("*") if p.is_file()]
    assert shipped and all(any(p.match(pattern) for pattern in patterns) for p in shipped), shipped
