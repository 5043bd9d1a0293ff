"""3D frames fit to print: the exact section (closed-form areas, a cut that moves with the body), the shading
(brightness by orientation, hue by value), the camera fitted to every step, the text and guides apart, the
scale bar's length, the clamp, an obstacle and the rest ghost drawn, the header's units."""

import colorsys
import dataclasses
from itertools import combinations, permutations

import numpy as np
import pytest
from test_render3d import finger  # noqa: F401  (the bent block fixture)

from taichi_pneuma.io.units import UNITS
from taichi_pneuma.render import guides3d
from taichi_pneuma.render.colours import BACKGROUND, OBSTACLE_FILL
from taichi_pneuma.render.frames3d import CLAMP, FrameRenderer3D, Track3D, body_colormap, step_captions
from taichi_pneuma.render.section import section_of
from taichi_pneuma.render.surface import AMBIENT, BACK_FACE, SPECULAR, shade_faces
from taichi_pneuma.render.text import label_box
from taichi_pneuma.terms.obstacle_shapes import Box

LO, HI = np.array([-2.0, -0.4, -0.4]), np.array([2.0, 0.4, 0.4])


def block(cells=(8, 2, 2)):
    """The box LO..HI split into cells, each cube into 6 tetrahedra about its main diagonal (Kuhn's: they
    match across cubes): nodes, tetrahedra, and the boundary triangles (faces of one tetrahedron) outward."""
    n = np.array(cells) + 1
    grid = np.stack(np.meshgrid(*[np.linspace(LO[k], HI[k], n[k]) for k in range(3)], indexing="ij"), -1)
    nodes = grid.reshape(-1, 3)
    index = np.arange(len(nodes)).reshape(*n)
    tets = []
    for i, j, k in np.ndindex(*cells):
        for order in permutations(range(3)):
            corner, path = np.array([i, j, k]), [index[i, j, k]]
            for axis in order:
                corner[axis] += 1
                path.append(index[tuple(corner)])
            tets.append(path)
    tets = np.array(tets)
    faces = tets[:, [[1, 2, 3], [0, 2, 3], [0, 1, 3], [0, 1, 2]]].reshape(-1, 3)
    opposite = tets.reshape(-1)  # face f of tetrahedron t is opposite corner f
    keys, first, count = np.unique(np.sort(faces, axis=1), axis=0, return_index=True, return_counts=True)
    once = first[count == 1]
    boundary, away = faces[once], nodes[opposite[once]]
    x = nodes[boundary]
    inward = np.sum(np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0]) * (away - x.mean(axis=1)), axis=1) > 0
    boundary[inward] = boundary[inward][:, ::-1]
    return nodes, tets, boundary


def area(x: np.ndarray) -> float:
    return float(np.linalg.norm(np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0]), axis=1).sum() / 2)


@pytest.mark.parametrize("value", [0.13, 0.0])
def test_the_section_cuts_the_surface_and_the_tetrahedra_exactly_on_the_plane(value):
    """Cut at z = value (0.13: between node layers; 0: through one), the +z side removed: the cut faces lie on the
    plane and fill the box's cross-section 4 x 0.8 exactly, their normals +z; the kept surface is the bottom face
    and the sides up to the plane (closed form); every kept point has z <= value."""
    nodes, tets, boundary = block()
    s = section_of(nodes, boundary, np.zeros((0, 3), int), tets, 2, value, 1.0)
    points = s.points(nodes)
    cut = points[s.cut]
    assert np.allclose(cut[..., 2], value, atol=1e-12)
    assert area(cut) == pytest.approx(4.0 * 0.8, rel=1e-12)
    normals = np.cross(cut[:, 1] - cut[:, 0], cut[:, 2] - cut[:, 0])
    assert np.all(normals[:, 2] > 0)
    kept = points[s.surface]
    assert kept[..., 2].max() <= value + 1e-12
    height = value - LO[2]
    assert area(kept) == pytest.approx(4.0 * 0.8 + 2 * 0.8 * height + 2 * 4.0 * height, rel=1e-12)


def test_the_cut_moves_with_the_body():
    """The section is fixed in the rest body: under an affine motion x = A X + b its points move as A p + b."""
    nodes, tets, boundary = block((4, 2, 2))
    s = section_of(nodes, boundary, np.zeros((0, 3), int), tets, 0, 0.3, -1.0)
    a, b = np.array([[1.1, 0.2, 0.0], [-0.3, 0.9, 0.1], [0.0, 0.2, 1.3]]), np.array([0.5, -1.0, 2.0])
    assert np.allclose(s.points(nodes @ a.T + b), s.points(nodes) @ a.T + b)
    assert np.all(s.points(nodes)[s.surface][..., 0] >= 0.3 - 1e-12)  # sign -1: the -x side removed


def block_track(**changes):
    nodes, tets, boundary = block()
    chamber = boundary[:2]  # a token chamber: the section is drawn only for a body with chambers
    positions = np.array([nodes, nodes + [0.0, 0.1, 0.0]])
    return Track3D(
        positions,
        boundary,
        (chamber,),
        color=np.full((2, len(boundary)), 0.5),
        color_label="v [-]",
        tetrahedra=tets,
        cell_color=np.array([np.full(len(tets), 0.5), np.linspace(0, 1, len(tets))]),
        **changes,
    )


def test_faces_facing_different_ways_differ_in_brightness_not_in_hue():
    """Faces of one value (0.5) are its colour times a shade in [AMBIENT BACK_FACE, 1] plus a white highlight up
    to SPECULAR; the top (+y), the end (-x) and the cut (+z) differ in brightness by more than 12 % but keep the
    value's hue (a shade and an added grey leave the hue alone)."""
    renderer = FrameRenderer3D(block_track(), 640, 360, backend="numpy", trace=False, guides=False)
    corners, colors = renderer.triangles(0)
    s = renderer.section
    body = len(s.surface) + len(s.cut)
    base = body_colormap(np.array([0.5]), 0.0, 1.0)[0]
    factor, highlight = shade_faces(corners[:body], renderer.camera)
    assert np.all((AMBIENT * BACK_FACE <= factor) & (factor <= 1) & (0 <= highlight) & (highlight <= SPECULAR))
    assert np.allclose(colors[:body], np.minimum(base * factor[:, None, None] + highlight[:, None, None], 1))
    normal = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    faces = {
        name: np.flatnonzero(normal[:body] @ axis > 0.99)
        for name, axis in (("top", [0, 1, 0]), ("end", [-1, 0, 0]), ("cut", [0, 0, 1]))
    }
    shade = {name: colors[f, 0].mean(axis=0) for name, f in faces.items()}
    hue = colorsys.rgb_to_hsv(*base)[0]
    for a, b in combinations(shade, 2):
        assert abs(shade[a].sum() / shade[b].sum() - 1) > 0.12
    for c in shade.values():
        assert abs(colorsys.rgb_to_hsv(*c)[0] - hue) < 0.02


def test_every_step_lies_inside_the_view(finger):  # noqa: F811
    """The camera is fitted to all steps: every node of every step projects inside the 3D view, clear of the
    rows the scale bar and the colour bar's label take."""
    renderer = FrameRenderer3D(finger, 480, 320, backend="numpy", trace=False)
    w, h = renderer.canvas.width, renderer.canvas.height
    pixels, depth = renderer.camera.project(finger.positions, w, h)
    assert np.all(depth > 0)
    assert pixels[..., 0].min() > 0 and pixels[..., 0].max() < w
    assert pixels[..., 1].min() > 20 and pixels[..., 1].max() < h - 20


@pytest.mark.parametrize("size", [(480, 320), (640, 360), (960, 540)])
def test_labels_and_guides_keep_apart_inside_the_frame(finger, size):  # noqa: F811
    """In frames small and large, with a colour bar, a trace panel and the whole key: no two label boxes or
    guides (axes, scale bar) overlap, all lie inside the frame, none reaches into the trace panel, and no node of
    any step lies under a guide."""
    track = dataclasses.replace(finger, pinned=np.arange(10), length_unit=" mm")
    renderer = FrameRenderer3D(track, *size, backend="numpy")
    _, labels, guides = renderer.compose(3)
    boxes = {label: label_box(label) for label in labels}
    key = [label.text for label, _, _ in renderer.key]
    assert key[0].startswith("section z = 0 mm") and key[-2:] == ["clamped face", "rest shape"] and len(guides) == 2
    bar_text = next(label.text for label in labels if label.text.endswith(" mm"))
    for (a, box_a), (b, box_b) in combinations(boxes.items(), 2):
        assert apart(box_a, box_b), (a, b)
    for guide, own in zip(guides, ({"x", "y", "z"}, {bar_text})):  # the axes' and the bar's own labels lie on them
        assert all(apart(guide, box) for label, box in boxes.items() if label.text not in own), guide
    for left, top, right, bottom in [*boxes.values(), *guides]:
        assert 0 <= left and right <= size[0] - renderer.trace_px and 0 <= top and bottom <= size[1]
    pixels, _ = renderer.camera.project(finger.positions.reshape(-1, 3), renderer.canvas.width, renderer.canvas.height)
    pixels[:, 1] += renderer.header_px
    for left, top, right, bottom in guides:  # in the corners the body leaves free
        assert not np.any(
            (pixels[:, 0] > left) & (pixels[:, 0] < right) & (pixels[:, 1] > top) & (pixels[:, 1] < bottom)
        )


def apart(a, b) -> bool:
    """Boxes (left, top, right, bottom) that do not overlap."""
    return a[2] <= b[0] or b[2] <= a[0] or a[3] <= b[1] or b[3] <= a[1]


def test_the_scale_bar_is_its_length_at_the_body_depth(finger):  # noqa: F811
    """The bar's drawn pixels span the projection of a segment of its length through the camera's target (the
    centre of the body's box) across the view, to a pixel; its label is the length with the unit."""
    renderer = FrameRenderer3D(dataclasses.replace(finger, length_unit=" mm"), 640, 360, backend="numpy")
    image, labels, _ = renderer.compose(0)
    view = image[renderer.header_px :, : renderer.canvas.width]
    w, h = renderer.canvas.width, renderer.canvas.height
    length, row = guides3d.scale_bar(w * renderer.camera.distance / renderer.camera.focal(h), " mm")[0], h - 14
    dark = np.flatnonzero(np.all(view[row] < 60, axis=1))
    right = renderer.camera.basis()[0]
    target = np.asarray(renderer.camera.target)
    ends, _ = renderer.camera.project(np.array([target - right * length / 2, target + right * length / 2]), w, h)
    assert abs((dark.max() - dark.min()) - np.ptp(ends[:, 0])) <= 1.5
    assert f"{length:g} mm" in [label.text for label in labels]


def hue_of(rgb) -> float:
    return colorsys.rgb_to_hsv(*(np.asarray(rgb, float) / 255))[0]


def test_the_clamp_an_obstacle_and_the_rest_ghost_are_drawn():
    """The clamped end (nodes at x = -2) shows in the clamp's hue; a box beside the body in the obstacle's hue at
    its projected centre; the moved body leaves the rest shape's ghost (fill and outline) where it was, and at
    rest the body hides its ghost."""
    nodes = block()[0]
    pinned = np.flatnonzero(nodes[:, 0] == LO[0])
    plate = guides3d.obstacle_triangles(Box((0.0, -1.0, 0.0), (2.0, 0.4, 0.8)), 1.0)  # -1.2 < y < -0.8
    obstacles = ((np.array([plate[0]] * 2), np.array([plate[1]] * 2)),)
    renderer = FrameRenderer3D(block_track(pinned=pinned, obstacles=obstacles), 640, 360, backend="numpy")
    frames = [renderer.compose(i)[0][renderer.header_px :, : renderer.canvas.width] for i in (0, 1)]
    hues = np.apply_along_axis(hue_of, 2, frames[1][::2, ::2].astype(float))
    assert np.count_nonzero(np.abs(hues - colorsys.rgb_to_hsv(*CLAMP)[0]) < 0.01) > 30
    pixels, _ = renderer.camera.project(np.array([[0.0, -1.0, 0.4]]), renderer.canvas.width, renderer.canvas.height)
    column, row = np.floor(pixels[0]).astype(int)
    assert abs(hue_of(frames[1][row, column]) - colorsys.rgb_to_hsv(*OBSTACLE_FILL)[0]) < 0.02
    fill = np.all(frames[1] == np.round(np.array(guides3d.GHOST_FILL) * 255), axis=2)
    edge = np.all(frames[1] == np.round(np.array(guides3d.GHOST_EDGE) * 255), axis=2)
    assert np.count_nonzero(fill) > 200 and np.count_nonzero(edge) > 100
    assert not np.any(np.all(frames[0] == np.round(np.array(guides3d.GHOST_FILL) * 255), axis=2))
    assert np.all(frames[0][0] == np.round(np.array(BACKGROUND) * 255))


def test_the_header_gives_each_value_its_unit_in_a_mm_kpa_scene():
    history = {"tip_dy": np.array([0.0, -12.3]), "tip_dz": np.array([0.0, 0.04]), "tip_rotation": np.array([0, -20.0])}
    captions = step_captions(np.array([[1.0], [1.3]]), np.array([[0.0], [120.0]]), history, UNITS["mm-kPa"])
    assert "p = 120 kPa" in captions[1][0] and "volume x1.30" in captions[1][0]
    assert captions[1][1].startswith("tip dy = -12.3 mm   dz = +0.04 mm   bend -20.0 deg")


def test_the_glyph_and_colour_map_memos_are_read_only():
    """The memos every frame shares (a label's glyph coverage, the colour map's table) refuse a write, so no caller
    can change what the next one draws; a label drawn twice is the same pixels."""
    from taichi_pneuma.render import colours, text

    label = [text.Label("12 mm", 10.0, 10.0)]
    first = text.draw_labels(np.zeros((40, 120, 3), np.uint8), label)
    with pytest.raises(ValueError, match="read-only"):
        text._coverage("12 mm", "la")[0][0, 0] = 1.0
    with pytest.raises(ValueError, match="read-only"):
        colours._colormap_table()[0] = 0.0
    assert first.any() and np.array_equal(text.draw_labels(np.zeros((40, 120, 3), np.uint8), label), first)
