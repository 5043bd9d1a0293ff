"""A trained reduced model as one .npz file: the basis, the sampled elements and their weights, the training
commands and coordinates, the singular values, and the SHA-256 of the scene it was trained for (result.scene_sha256:
of the scene's TOML). Loading it for a scene of another hash is refused with one line: its basis and elements
belong to another mesh, material or chamber layout.
"""

from __future__ import annotations

import io
import os
import zipfile

import numpy as np

from ..errors import PneumaInputError, quoted, require
from ..io.output import read_input, save_npz
from ..result import scene_sha256
from ..scene.build import BuiltScene
from .model import ReducedModel

MAX_BYTES = 2**31  # the largest reduced model file read
FIELDS = ("basis", "elements", "weights", "commands", "coordinates", "singular_values", "scene_sha256")


def save_reduced(path: str | os.PathLike, model: ReducedModel, singular_values: np.ndarray) -> None:
    """Write the model (trained: model.training set) to path, whole or not at all."""
    assert model.training is not None, "only a trained model is saved"
    save_npz(
        path,  # type: ignore[arg-type]
        basis=model.basis,
        elements=model.elements,
        weights=model.weights,
        commands=model.training[0],
        coordinates=model.training[1],
        singular_values=singular_values,
        scene_sha256=np.array(scene_sha256(model.built.scene)),
    )


def load_reduced(path: str | os.PathLike, built: BuiltScene) -> ReducedModel:
    """The reduced model of the file at path for the built scene; PneumaInputError (one line) when the file is no
    reduced model or was trained for another scene."""
    try:
        with np.load(io.BytesIO(read_input(path, MAX_BYTES, "reduced model")), allow_pickle=False) as data:
            arrays = {name: data[name] for name in FIELDS}
    except (OSError, ValueError, KeyError, zipfile.BadZipFile) as exc:
        if isinstance(exc, PneumaInputError):
            raise
        raise PneumaInputError(f"reduced model {quoted(path)} cannot be read as one ({exc})") from None
    trained, now = str(arrays["scene_sha256"]), scene_sha256(built.scene)
    require(
        trained == now,
        f"reduced model {quoted(path)} was trained for another scene (scene_sha256 {trained[:12]}, this scene's "
        f"{now[:12]}): train it again for this scene with pneuma-reduce",
    )
    basis, elements = arrays["basis"], arrays["elements"]
    require(
        basis.ndim == 2 and basis.shape[0] == built.model.n_dofs and elements.max(initial=0) < built.mesh.n_elements,
        f"reduced model {quoted(path)} does not fit this scene's mesh ({built.model.n_dofs} DOFs)",
    )
    return ReducedModel(built, basis, elements, arrays["weights"], (arrays["commands"], arrays["coordinates"]))
