"""--quality on 3D scene files: given, it remeshes a body from shapes at the 3D preset's factors on the scene's own
sizes and its order; not given, the scene keeps its own [mesh]; a mesh file's tetrahedra are never remeshed (the
preset sets their order)."""

import dataclasses

import pytest

from taichi_pneuma.apps.cli import scene_of_flags
from taichi_pneuma.apps.inflate import parser


def scene(*flags):
    return scene_of_flags(parser().parse_args(list(flags)))


@pytest.mark.parametrize(
    "quality, sizes",
    [  # pneunet_3d.toml's [mesh]: 0.3, 0.12 near the chambers, distance 0.3, quadratic
        ("draft", (0.45, 0.45, 0.45, 1)),
        ("default", (0.45, 0.18, 0.45, 2)),
        ("high", (0.45, 0.12, 0.45, 2)),
        ("accurate", (0.3, 0.096, 0.3, 2)),
    ],
)
def test_a_given_quality_remeshes_a_body_from_shapes_relative_to_its_own_sizes(quality, sizes):
    geometry = scene("--scene", "pneunet_3d", "--quality", quality).geometry
    assert (geometry.sizes.size, geometry.sizes.near, geometry.sizes.distance, geometry.order) == sizes


def test_without_quality_the_scene_keeps_its_mesh_and_set_overrides_the_preset():
    own = scene("--scene", "pneunet_3d").geometry
    assert (own.sizes.size, own.sizes.near, own.order) == (0.3, 0.12, 2)  # pneunet_3d.toml's [mesh]
    assert scene("--scene", "pneunet_3d", "--quality", "draft", "--set", "mesh.size=0.25").geometry.sizes.size == 0.25


def test_a_mesh_file_keeps_its_tetrahedra_in_the_presets_order():
    own, accurate = scene("--scene", "beam_3d").geometry, scene("--scene", "beam_3d", "--quality", "accurate").geometry
    assert (accurate.body, accurate.order, own.order) == (own.body, 2, 1)


def test_the_first_line_names_the_preset_and_its_measured_error_where_a_preset_made_the_mesh():
    from taichi_pneuma.apps.quality import MEASURED_ERROR_3D, QUALITY_ERROR, preset_note

    def note(*flags, name=None):
        args = parser().parse_args(list(flags))
        scene = scene_of_flags(args)
        return preset_note(scene if name is None else dataclasses.replace(scene, name=name), args)

    assert (
        note("--cy", "0.15") == f"; --quality default: tip within {QUALITY_ERROR[2]['default']:g} % of converged "
        "on the reference beam"
    )
    high = QUALITY_ERROR[3]["high"]
    measured = note("--scene", "beam_3d_ellipsoid", "--quality", "high")
    assert measured == f"; --quality high: tip within {high:g} % of converged (-0.1974)"
    assert note("--scene", "pneunet_3d", "--quality", "high", name="my_finger") == (
        f"; --quality high: not measured on this scene (on beam_3d_ellipsoid: tip within {high:g} %)"
    )
    assert note("--scene", "pneunet_3d", name="my_finger") == ""  # its own [mesh], not measured
    pneunet = MEASURED_ERROR_3D["pneunet_3d"]["high"]
    assert (
        note("--scene", "pneunet_3d", "--quality", "high")
        == f"; --quality high: tip within {pneunet:g} % of converged (-1.1)"
    )
    bending = MEASURED_ERROR_3D["fiber_bending_3d"]
    assert note("--scene", "fiber_bending_3d") == (
        f"; mesh as written: tip_rotation within {bending['as written']:g} % of converged (-154.1)"
    )
    assert note("--scene", "fiber_bending_3d", "--quality", "high") == (
        f"; --quality high: tip_rotation within {bending['high']:g} % of converged (-154.1)"
    )
    assert note("--scene", "fiber_bending_3d", "--set", "mesh.near_chambers=3") == ""  # no longer the one measured
    assert note("--scene", "beam_3d", "--quality", "high") == ""  # a mesh file's tetrahedra
    assert note("--scene", "pneunet_finger") == ""
