"""Energy terms. A scene's total energy is the sum of the terms it names.

Every term reads the model's Configuration (rest positions X and displacements u, (n, d) NumPy
arrays; x = X + u) and offers

    energy() -> float                     its energy at the current x
    gradient() -> (n, d) array            dE/dx
    hessian_pattern() -> (rows, cols)     fixed DOF indices of its sparse PSD Hessian triplets
    hessian_values(psd_only) -> (nnz,)    the triplet values at the current x; with psd_only=True a
                                          PSD approximation (for terms whose Hessian is indefinite)
    low_rank() -> [(dofs, u, c)]          PSD rank-1 parts c u u^T on the DOF subset `dofs`
    max_step(dx) -> float                 largest safe step fraction along dx (inf when unbounded)

DOFs are interleaved: vertex i owns DOFs d i .. d i + d - 1 (x, y, (z)).
"""

from .base import Term, vertex_dofs
from .chambers import AreaChamber, PressureChamber
from .constraints import Clamp, NormalClamp
from .elastic import Elasticity
from .nodal_volume import MixedElasticity, NodalVolumeElasticity

# where the elastic term evaluates the law's volumetric part (Scene.volumetric, the scene file's mesh.volumetric)
VOLUMETRIC = {"element": Elasticity, "nodal": NodalVolumeElasticity, "mixed": MixedElasticity}

__all__ = [
    "VOLUMETRIC",
    "AreaChamber",
    "Clamp",
    "Elasticity",
    "MixedElasticity",
    "NodalVolumeElasticity",
    "NormalClamp",
    "PressureChamber",
    "Term",
    "vertex_dofs",
]
