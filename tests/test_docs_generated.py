"""The generated pages committed under docs/ (the scene-key tables, the apps' flag tables and the benchmark result
tables in docs/_generated/, readable in the repository) are what docs/_generate.py makes of the code and the tracked
results now: a key or a flag added without running the generator fails here."""

import importlib
import sys
from pathlib import Path

import pytest

from taichi_pneuma.scene.scenefile import key_reference

DOCS = Path(__file__).resolve().parent.parent / "docs"
sys.path.insert(0, str(DOCS))
generate = importlib.import_module("_generate")


@pytest.mark.parametrize("dim", sorted(generate.SCENE_KEYS))
def test_each_committed_scene_key_table_is_what_the_generator_writes_now(dim):
    path = DOCS / generate.SCENE_KEYS[dim]
    assert path.read_text() == generate.scene_keys_page(dim), (
        f"docs/{generate.SCENE_KEYS[dim]} is out of date: run `{generate.REGENERATE}` and commit it"
    )


def test_each_committed_generated_piece_is_what_the_generator_writes_now():
    pages = generate.committed_pages()
    pieces = [path for path in pages if path.parent == generate.GENERATED]
    assert len(pieces) == len(generate.APPS) + 5  # an app page each, five results pages
    stale = [path.name for path in pieces if not path.exists() or path.read_text() != pages[path]]
    assert not stale, f"docs/_generated/{', '.join(stale)} out of date: run `{generate.REGENERATE}` and commit them"


def test_the_two_tables_list_every_key_once_the_3d_shapes_in_the_second():
    keys = key_reference()
    pages = {dim: generate.scene_keys_page(dim) for dim in generate.SCENE_KEYS}
    rows = {dim: [line for line in page.splitlines() if line.startswith("| `")] for dim, page in pages.items()}
    assert len(rows[2]) + len(rows[3]) == len(keys)
    assert all(f"| `{k.key}` |" in pages[2] + pages[3] for k in keys)
    solid = "\n".join(rows[3])
    assert '`body.shape = "cylinder"`' in solid and '`chambers[].shape = "mesh_surface"`' in solid
    assert "`body.profile.rectangles[].size`" in solid  # inside a 3D shape (an extrusion's profile)
    assert '`body.shape = "rectangle"`' not in solid and '`chambers[].shape = "ellipse"`' not in solid  # 2D: first
    assert "`body.rectangles[].center`" in pages[2] and "`material.E`" in pages[2] and "`name`" in pages[2]
