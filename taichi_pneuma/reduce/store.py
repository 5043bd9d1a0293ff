"""A trained reduced model as one .npz file: the basis, the sampled pieces and their weights of each piecewise term
(pieces_<label>, weights_<label>, by its label: ecsw.piecewise_terms), the training commands and coordinates, the
singular values, and the SHA-256 of the scene it was trained for (result.scene_sha256: of the scene's TOML). Loading
it for a scene of another hash is refused with one line: its basis and pieces belong to another mesh, material or
chamber layout. A file of the first format (the elastic term's `elements` and `weights` alone) is read too: its other
piecewise terms are evaluated whole, as it was trained.
"""

from __future__ import annotations

import io
import os
import zipfile
from pathlib import Path

import numpy as np

from ..errors import PneumaInputError, quoted, require
from ..io.inputs import read_input
from ..io.output import save_npz
from ..result import scene_sha256
from ..scene.build import BuiltScene
from .model import ReducedModel, Samples

MAX_BYTES = 2**31  # the largest reduced model file read
FIELDS = ("basis", "commands", "coordinates", "singular_values", "scene_sha256")
PIECES, WEIGHTS = "pieces_", "weights_"  # the prefixes of a sampled term's arrays, before its label


def save_reduced(path: str | os.PathLike, model: ReducedModel, singular_values: np.ndarray) -> None:
    """Write the model (trained: model.training set) to path, whole or not at all."""
    assert model.training is not None, "only a trained model is saved"
    sampled: dict[str, np.ndarray] = {}
    for label, (pieces, weights) in model.samples.items():
        sampled[PIECES + label], sampled[WEIGHTS + label] = pieces, weights
    save_npz(
        Path(path),
        basis=model.basis,
        commands=model.training[0],
        coordinates=model.training[1],
        singular_values=singular_values,
        scene_sha256=np.array(scene_sha256(model.built.scene)),
        **sampled,
    )


def samples_of(data) -> Samples:
    """The sampled pieces and weights by label of an open .npz (either format)."""
    if "elements" in data.files:  # the first format: the elastic term's alone
        return {"elastic": (data["elements"], data["weights"])}
    labels = [name[len(PIECES) :] for name in data.files if name.startswith(PIECES)]
    return {label: (data[PIECES + label], data[WEIGHTS + label]) for label in labels}


def load_reduced(path: str | os.PathLike, built: BuiltScene) -> ReducedModel:
    """The reduced model of the file at path for the built scene; PneumaInputError (one line) when the file is no
    reduced model or was trained for another scene."""
    try:
        with np.load(io.BytesIO(read_input(path, MAX_BYTES, "reduced model")), allow_pickle=False) as data:
            arrays = {name: data[name] for name in FIELDS}
            samples = samples_of(data)
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
    basis = arrays["basis"]
    require(
        basis.ndim == 2 and basis.shape[0] == built.model.n_dofs,
        f"reduced model {quoted(path)} does not fit this scene's mesh ({built.model.n_dofs} DOFs)",
    )
    return ReducedModel(built, basis, samples, (arrays["commands"], arrays["coordinates"]))
