"""docs/extending.md's worked examples are code the tests run: a new term (a tip load, checked here against
Timoshenko beam theory), a new law's material form (read, checked, written and listed by the scene format once
registered), and every Python block of the page appears verbatim in the package or the tests."""

import re
import tomllib
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest
from test_materials import SaintVenantKirchhoff

import taichi_pneuma as tp
from taichi_pneuma.errors import PneumaInputError
from taichi_pneuma.fem.planar import Geometry
from taichi_pneuma.fem.shapes import Rectangle
from taichi_pneuma.fem.supports import PointSet
from taichi_pneuma.io.registry import key
from taichi_pneuma.materials import LAW_FORMS, MaterialForm
from taichi_pneuma.materials.neo_hookean import youngs_modulus_key
from taichi_pneuma.materials.registry import poisson_ratio_key
from taichi_pneuma.scene.build import Material, Scene
from taichi_pneuma.scene.material_keys import material_entries
from taichi_pneuma.scene.scenefile import key_reference, read_scene
from taichi_pneuma.solve.simulate import run_schedule
from taichi_pneuma.terms.base import Term
from taichi_pneuma.terms.effects import EFFECTS, Effect

ROOT = Path(__file__).resolve().parents[1]


class TipLoad(Term):
    """A dead load f shared equally by the k tip nodes: E = -sum_i f . u_i / k, gradient -f / k, Hessian 0."""

    name = "tip_load"

    def __init__(self, config, tip: np.ndarray, force):
        self.config, self.tip = config, np.asarray(tip)
        self.share = np.asarray(force, dtype=np.float64) / len(self.tip)

    def energy(self) -> float:
        return -float(np.sum(self.config.u[self.tip] @ self.share))

    def gradient(self) -> np.ndarray:
        g = np.zeros_like(self.config.u)
        g[self.tip] = -self.share
        return g


@dataclass(frozen=True)
class TipForce(Effect):
    """[effects.tip_force] fx, fy: a dead load on the scene's tip nodes."""

    fx: float = 0.0
    fy: float = 0.0
    name = "tip_force"

    def terms(self, config, mesh, lumped_area, budget) -> list:
        return [TipLoad(config, mesh.tip, (self.fx, self.fy))]


@pytest.fixture
def tip_force_registered():
    EFFECTS.register(TipForce)
    yield
    del EFFECTS["tip_force"]


def test_tip_load_bends_a_cantilever_as_timoshenko_predicts(tip_force_registered):
    """A clamped 3.5 x 0.8 plane-strain beam (quadratic triangles, no chamber) under a small tip load F:
    delta = F L^3 / (3 E' I) + F L / (kappa G A), I = H^3 / 12, kappa = 5/6, with the moduli of the stable
    neo-Hookean law linearised at rest: shear G = mu and Lame constant lam - mu (not lam), so Young's modulus
    Y = mu (3 l + 2 mu) / (l + mu), Poisson's ratio v = l / (2 (l + mu)), l = lam - mu, and E' = Y / (1 - v^2);
    to 1 % (the clamp holds the whole wall, which beam theory does not)."""
    E, nu, L, H, F = 1e4, 0.3, 3.5, 0.8, -1.0
    body = Rectangle((0.0, 0.0), (L, H))
    scene = Scene(
        Geometry(body, (), 0.01, PointSet("left"), order=2), (), 1, Material(E, nu), effects=(TipForce(fy=F),)
    )
    deflection = run_schedule(scene.build()).steps[-1].tip_dy
    mu, lam = E / (2 * (1 + nu)), E * nu / ((1 + nu) * (1 - 2 * nu))
    lame = lam - mu
    young, poisson = mu * (3 * lame + 2 * mu) / (lame + mu), lame / (2 * (lame + mu))
    theory = F * L**3 / (3 * young / (1 - poisson**2) * H**3 / 12) + F * L / (5 / 6 * mu * H)
    assert deflection == pytest.approx(theory, rel=0.01)


@dataclass(frozen=True)
class SaintVenantKirchhoffMaterial(MaterialForm):
    """law = "saint_venant_kirchhoff": the Saint Venant-Kirchhoff law (tests/test_materials.py) of E and nu."""

    youngs_modulus: float = youngs_modulus_key()
    poisson_ratio: float = poisson_ratio_key(0.3)
    selector = "law"
    name = "saint_venant_kirchhoff"
    summary = "a Saint Venant-Kirchhoff material (law = saint_venant_kirchhoff: E and nu)"

    def __post_init__(self):
        Material(self.youngs_modulus, self.poisson_ratio)  # the checks of E and nu

    def law_parameters(self, units):
        return SaintVenantKirchhoff, SaintVenantKirchhoff.parameters(self.youngs_modulus, self.poisson_ratio)[0]


@pytest.fixture
def saint_venant_kirchhoff_registered():
    LAW_FORMS.register(SaintVenantKirchhoffMaterial)  # the scene format lists the forms registered when it is used
    yield
    del LAW_FORMS["saint_venant_kirchhoff"]


def test_a_registered_material_form_is_read_checked_written_and_listed_by_the_scene_format(
    saint_venant_kirchhoff_registered,
):
    """Once registered, the form's name is a value of material.law: its keys are read into the form, refused
    where it lacks them or lacks a value, written back (the scene reads back equal) and listed in the key
    reference; the scene's law is the form's."""
    scene = tp.reference_scene().with_values({"material.law": "saint_venant_kirchhoff", "material.E": 2e4})
    assert scene.material == SaintVenantKirchhoffMaterial(2e4)
    assert scene.law_parameters()[0] is SaintVenantKirchhoff
    assert 'law = "saint_venant_kirchhoff"' in scene.to_toml()
    assert read_scene(tomllib.loads(scene.to_toml()), scene.name) == scene
    law = next(row for row in key_reference() if row.key == "material.law")
    assert law.allowed.endswith(", saint_venant_kirchhoff")
    with pytest.raises(PneumaInputError, match="law = 'saint_venant_kirchhoff' needs E"):
        tp.reference_scene().with_value("material.law", "saint_venant_kirchhoff")
    with pytest.raises(PneumaInputError, match="law = 'saint_venant_kirchhoff' takes E, nu, not K"):
        scene.with_value("material.K", 1.0)
    with pytest.raises(PneumaInputError, match=r"nu = 0.5 must lie in \(-1, 0.5\)"):
        scene.with_value("material.nu", 0.5)


def test_a_form_whose_key_differs_from_another_forms_key_of_that_name_is_refused(monkeypatch):
    """Forms' keys of one name are one key (E, nu, K): a form declaring nu with another doc is refused, naming the
    form and the key, when the [material] table lists its keys; the shipped forms agree (the table lists them)."""

    @dataclass(frozen=True)
    class OddRatio(MaterialForm):
        poisson_ratio: float = key(0.3, "a ratio", name="nu")
        selector = "law"
        name = "odd_ratio"

    assert list(material_entries()) == ["preset", "law", "E", "nu", "K", "C10", "C01", "C20", "C30"]
    monkeypatch.setitem(LAW_FORMS, "odd_ratio", OddRatio)
    with pytest.raises(ValueError, match="OddRatio: key 'nu' is Key.*doc='a ratio'.*the other forms'.*Poisson's ratio"):
        material_entries()


def test_every_python_block_of_the_page_is_code_the_tests_or_the_package_run():
    page = (ROOT / "docs" / "extending.md").read_text()
    sources = "\n".join(p.read_text() for folder in ("tests", "taichi_pneuma") for p in (ROOT / folder).rglob("*.py"))
    blocks = re.findall(r"```python\n(.*?)```", page, re.S)
    assert len(blocks) >= 4
    for block in blocks:
        for line in block.strip().splitlines():
            assert line.strip() in sources, f"docs/extending.md shows a line no test or module runs: {line!r}"
