"""Silicone (and strain-limiting layer) presets: published fits of the isochoric law, stored in SI (Pa) and
converted into a scene's units on use.

A scene names one with `preset = "ecoflex_00_30"` in its [material] table or a region; it may replace the
preset's Poisson's ratio (`nu`) or give a bulk modulus (`K`, in the scene's pressure unit). The silicones are
nearly incompressible; their default nu = 0.49 (K = 50 mu0) keeps linear triangles usable: nearer 1/2, prefer
quadratic ones (order = 2), which lock less.

Sources (docs/materials.md has the table, the data sheets' figures and the fit procedure):

[M] L. Marechal, P. Balland, L. Lindenroth, F. Petrou, C. Kontovounisios, F. Bello, "Toward a Common Framework
    and Database of Materials for Soft Robotics", Soft Robotics 8(3), 284-297 (2021), doi:10.1089/soro.2019.0115;
    its uniaxial tensile data (ASTM D412 die C, 450 mm/min, engineering strain from the crosshead), published in
    the Soft Robotics Materials Database (github.com/LucMarechal/Soft-Robotics-Materials-Database, ODbL).
    The Yeoh coefficients here are this project's least-squares fits of the incompressible uniaxial nominal
    stress 2 (lam - lam^-2) (C10 + 2 C20 (I1 - 3) + 3 C30 (I1 - 3)^2) to those data for engineering strains
    0 to 200 %, with the coefficients kept >= 0 (a negative C30 makes W unbounded below at large stretch; the
    fits then have C30 = 0).
[P] P. Polygerinos, Z. Wang, J. T. B. Overvelde, K. C. Galloway, R. J. Wood, K. Bertoldi, C. J. Walsh,
    "Modeling of Soft Fiber-Reinforced Bending Actuators", IEEE Transactions on Robotics 31(3), 778-789 (2015),
    doi:10.1109/TRO.2015.2428504: Elastosil M4601 as Yeoh C10 = 0.11 MPa, C20 = 0.02 MPa; the inextensible
    layer (paper) as linear elastic, E = 6.5 GPa, nu = 0.2.
[S] Smooth-On technical bulletins (Ecoflex series, Dragon Skin series) and the Wacker Elastosil M 4601 A/B
    data sheet: hardness, 100 % modulus, tensile strength, elongation at break.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import PneumaInputError, require, require_finite
from .isochoric import IsochoricMaterial, IsochoricPolynomial
from .law import Law
from .registry import PRESET_FORMS, Compressible


@dataclass(frozen=True)
class Preset:
    """A published material: its law and coefficients in Pa, where they come from and what they hold for."""

    title: str
    material: IsochoricMaterial  # moduli in Pa
    source: str
    valid: str
    data_sheet: str
    fitted_stretch: float | None = None  # the largest uniaxial stretch of the data it was fitted to (None: not stated)


MPA, KPA = 1e6, 1e3
PRESETS = {
    "ecoflex_00_30": Preset(
        "Ecoflex 00-30 (Smooth-On)",
        IsochoricMaterial("yeoh", 7.86 * KPA, C20=0.0943 * KPA, C30=0.0),
        "[M] data, Yeoh fit (this project)",
        "uniaxial tension, engineering strain 0-200 % (rms error 0.44 kPa)",
        "[S] Shore 00-30; 100 % modulus 10 psi (69 kPa); tensile strength 200 psi (1.38 MPa); elongation 900 %",
        3.0,  # engineering strain 200 %
    ),
    "ecoflex_00_50": Preset(
        "Ecoflex 00-50 (Smooth-On)",
        IsochoricMaterial("yeoh", 10.7 * KPA, C20=0.231 * KPA, C30=0.0),
        "[M] data, Yeoh fit (this project)",
        "uniaxial tension, engineering strain 0-200 % (rms error 0.65 kPa)",
        "[S] Shore 00-50; 100 % modulus 12 psi (83 kPa); tensile strength 315 psi (2.17 MPa); elongation 980 %",
        3.0,  # engineering strain 200 %
    ),
    "dragon_skin_10": Preset(
        "Dragon Skin 10 Medium (Smooth-On)",
        IsochoricMaterial("yeoh", 25.0 * KPA, C20=1.81 * KPA, C30=0.0),
        "[M] data, Yeoh fit (this project)",
        "uniaxial tension, engineering strain 0-200 % (rms error 3.9 kPa)",
        "[S] Shore 10A; 100 % modulus 22 psi (152 kPa); tensile strength 475 psi (3.28 MPa); elongation 1000 %",
        3.0,  # engineering strain 200 %
    ),
    "dragon_skin_30": Preset(
        "Dragon Skin 30 (Smooth-On)",
        IsochoricMaterial("yeoh", 103.0 * KPA, C20=5.08 * KPA, C30=0.0),
        "[M] data, Yeoh fit (this project)",
        "uniaxial tension, engineering strain 0-200 % (rms error 13 kPa)",
        "[S] Shore 30A; 100 % modulus 86 psi (593 kPa); tensile strength 500 psi (3.45 MPa); elongation 364 %",
        3.0,  # engineering strain 200 %
    ),
    "elastosil_m4601": Preset(
        "Elastosil M 4601 A/B (Wacker)",
        IsochoricMaterial("yeoh", 0.11 * MPA, C20=0.02 * MPA),
        "[P] Yeoh fit",
        "the strains of fiber-reinforced and PneuNet bending actuators (as used in [P])",
        "[S] Shore A 28; tensile strength 6.5 MPa; elongation at break 700 %",
    ),
    "paper": Preset(
        "paper, as an inextensible strain-limiting layer",
        IsochoricMaterial("neo_hookean", 6.5e9 / (4 * 1.2), poisson_ratio=0.2),
        "[P] linear elastic E = 6.5 GPa, nu = 0.2, here the neo-Hookean form with the same small-strain moduli "
        "(C10 = E / (4 (1 + nu)))",
        "small strains only: the layer barely stretches; its bending stiffness is "
        "that of the meshed layer's thickness (a thin sheet is far more flexible than a thick band of it)",
        "-",
    ),
}


@PRESET_FORMS.register
@dataclass(frozen=True)
class PresetMaterial(Compressible):
    """A scene's material from a preset: its name, and optionally a bulk modulus (in the scene's pressure unit) or
    a Poisson's ratio replacing the preset's own (keyword-only, registry.py Compressible). A scene file names it by
    `preset = "<name>"` (registry.py)."""

    preset: str
    selector = "preset"
    name, aliases = tuple(PRESETS)[0], tuple(PRESETS)[1:]
    summary = "a preset (docs/materials.md)"

    def __post_init__(self):
        require(self.preset in PRESETS, f"preset = {self.preset!r} is not one of {', '.join(PRESETS)}")
        self.resolved(1.0)  # validates K and nu

    @classmethod
    def refusal(cls, extra: list[str], values: dict) -> str:
        return f"preset = {values['preset']!r} gives the law and its coefficients: drop {', '.join(extra)}"

    @property
    def fitted_stretch(self) -> float | None:
        """The largest stretch of the data the preset was fitted to (Preset.fitted_stretch; None: not stated)."""
        return PRESETS[self.preset].fitted_stretch

    def resolved(self, pascal: float | None) -> IsochoricMaterial:
        """The preset's material in a pressure unit of `pascal` Pa (None: the scene is unitless, which a preset
        cannot be converted into), with this material's K or nu."""
        if pascal is None:
            raise PneumaInputError(
                f'preset = {self.preset!r} needs the scene\'s units (units = "mm-kPa", '
                f'"mm-MPa" or "m-Pa") to be converted into'
            )
        base = PRESETS[self.preset].material.scaled(1.0 / require_finite("pressure unit", pascal))
        if self.bulk_modulus is None and self.poisson_ratio is None:
            return base
        return IsochoricMaterial(
            base.law,
            base.C10,
            base.C01,
            base.C20,
            base.C30,
            bulk_modulus=self.bulk_modulus,
            poisson_ratio=self.poisson_ratio,
        )

    def law_parameters(self, units) -> tuple[type[Law], np.ndarray]:
        """The law and its parameter vector in the scene's units (io/units.py; a unitless scene's name is None)."""
        return IsochoricPolynomial, self.resolved(None if units.name is None else units.pascal).row()
