"""A z-buffer rasteriser of coloured triangles in NumPy: 3D frames with no GPU and no Vulkan.

Each triangle, given by its corners' pixel positions, depths and colours, covers the pixels whose centres
(column + 1/2, row + 1/2) lie inside it (edge functions: the barycentric weights b_k all >= 0). A covered
pixel gets the perspective-correct interpolation of the corners' depth and colour,

    1 / z = sum_k b_k / z_k,    c = z sum_k b_k c_k / z_k,

and the nearest triangle wins (a buffer of the largest 1 / z, filled by np.maximum.at; the colour is
interpolated for the winners only). The covered pixels are found row by row: on a pixel row each weight
b_k is linear in x, so b_k >= 0 bounds the row's columns from one side, and all triangles' rows and then
their pixels are enumerated at once (ragged arrays, no loop over triangles). Cost: proportional to the
covered pixels, times the overdraw.

Shading (shade_faces) is flat, two-sided, under a key light fixed to the camera (beside the eye, a little right
of and above it, so the faces towards the eye, the top and the sides of a box differ clearly) plus a small
highlight: with n the face's unit normal turned towards the eye, l the direction to the light and h the unit
half-way vector of l and the direction to the eye v,

    colour = base (AMBIENT + DIFFUSE max(n . l, 0)) + SPECULAR max(n . h, 0)^SHININESS   (white highlight)

and a face seen from its back (its normal pointing away from the eye: the inside of the body through a section)
has its shade scaled by BACK_FACE. The GGUI renderer draws the same shaded colours.
"""

from __future__ import annotations

import numpy as np

from .camera import Camera

AMBIENT, DIFFUSE = 0.38, 0.62  # shade = AMBIENT + DIFFUSE max(n . l, 0): in [AMBIENT, 1]
SPECULAR, SHININESS = 0.18, 24.0  # the highlight, added white
BACK_FACE = 0.75
LIGHT = (0.35, 0.15, -1.0)  # the direction to the key light in camera (right, up, forward) units: by the eye


def shade_faces(corners: np.ndarray, camera: Camera) -> tuple[np.ndarray, np.ndarray]:
    """(shade (f,), highlight (f,)) of world triangles (f, 3, 3) for `camera` (module docstring): a face's colour
    is base * shade + highlight."""
    normal = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    normal /= np.maximum(np.linalg.norm(normal, axis=1, keepdims=True), 1e-300)
    view = camera.eye - corners.mean(axis=1)
    view /= np.maximum(np.linalg.norm(view, axis=1, keepdims=True), 1e-300)
    facing = np.sum(normal * view, axis=1) >= 0
    normal = np.where(facing[:, None], normal, -normal)
    light = np.asarray(LIGHT) @ camera.basis()
    light /= np.linalg.norm(light)
    half = light + view
    half /= np.maximum(np.linalg.norm(half, axis=1, keepdims=True), 1e-300)
    shade = (AMBIENT + DIFFUSE * np.maximum(normal @ light, 0.0)) * np.where(facing, 1.0, BACK_FACE)
    highlight = np.where(facing, SPECULAR * np.maximum(np.sum(normal * half, axis=1), 0.0) ** SHININESS, 0.0)
    return shade, highlight


def rasterise(
    pixels: np.ndarray, depth: np.ndarray, colors: np.ndarray, width: int, height: int, background=(1.0, 1.0, 1.0)
) -> np.ndarray:
    """The (height, width, 3) float image of triangles: corner pixels (f, 3, 2) as (column, row from the top),
    corner depths (f, 3) (> 0: in front of the eye; triangles with a corner behind are skipped) and corner
    colours (f, 3, 3) or one colour per triangle (f, 3)."""
    colors = np.asarray(colors, float)
    image = np.empty((height * width, 3), dtype=np.float32)
    image[:] = background
    edges = _edge_functions(pixels)
    pixel, face = _covered(pixels, depth, edges, width, height)
    if len(pixel):
        column, row = pixel % width + 0.5, pixel // width + 0.5
        plane = np.einsum("fkc,fk->fc", edges, 1 / depth)  # 1 / z = sum_k b_k / z_k, linear in (x, y)
        inverse = plane[face, 0] * column + plane[face, 1] * row + plane[face, 2]
        nearest = np.zeros(height * width)
        np.maximum.at(nearest, pixel, inverse)
        won = inverse >= nearest[pixel]
        pixel, face, column, row, inverse = pixel[won], face[won], column[won], row[won], inverse[won]
        if colors.ndim == 3:
            weights = edges[face, :, 0] * column[:, None] + edges[face, :, 1] * row[:, None] + edges[face, :, 2]
            image[pixel] = np.einsum("ik,ikc->ic", weights / depth[face] / inverse[:, None], colors[face])
        else:
            image[pixel] = colors[face]
    return image.reshape(height, width, 3)


def _edge_functions(pixels: np.ndarray) -> np.ndarray:
    """(f, 3, 3): per triangle and corner k the coefficients (a, b, c) of its barycentric weight
    b_k(x, y) = a x + b y + c, zero on the edge opposite corner k and one at corner k (inf for a
    degenerate triangle)."""
    x0, x1, x2 = pixels[:, 0], pixels[:, 1], pixels[:, 2]
    area = _cross(x1 - x0, x2 - x0)
    edge = np.stack([x2 - x1, x0 - x2, x1 - x0], axis=1)  # the edge opposite corner k, from corner k + 1
    start = np.stack([x1, x2, x0], axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        return (
            np.stack(
                [-edge[..., 1], edge[..., 0], edge[..., 1] * start[..., 0] - edge[..., 0] * start[..., 1]], axis=-1
            )
            / area[:, None, None]
        )


def _covered(pixels: np.ndarray, depth: np.ndarray, edges: np.ndarray, width: int, height: int):
    """(pixel index, triangle) for every pixel whose centre lies inside a triangle, row by row: on the row
    y = r + 1/2 each b_k(x) = a_k x + (b_k y + c_k) >= 0 bounds x from one side, and the covered columns
    run from the largest lower bound to the smallest upper bound."""
    top = np.maximum(np.ceil(pixels[:, :, 1].min(axis=1) - 0.5), 0).astype(np.int64)
    bottom = np.minimum(np.floor(pixels[:, :, 1].max(axis=1) - 0.5), height - 1).astype(np.int64)
    rows_of = np.where(np.all(np.isfinite(edges), axis=(1, 2)) & np.all(depth > 0, axis=1), bottom - top + 1, 0)
    rows_of = np.maximum(rows_of, 0)
    face = np.repeat(np.arange(len(pixels)), rows_of)
    row = top[face] + np.arange(len(face)) - np.repeat(np.cumsum(rows_of) - rows_of, rows_of)
    a, b, c = edges[face, :, 0], edges[face, :, 1], edges[face, :, 2]
    offset = b * (row[:, None] + 0.5) + c  # b_k on the row = a_k x + offset_k
    with np.errstate(divide="ignore", invalid="ignore"):
        bound = -offset / a
    left = np.max(np.where(a > 0, bound, -np.inf), axis=1)
    right = np.min(np.where(a < 0, bound, np.inf), axis=1)
    empty = np.any((a == 0) & (offset < 0), axis=1)
    first = np.maximum(np.ceil(np.maximum(left, -1.0) - 0.5), 0).astype(np.int64)
    last = np.minimum(np.floor(np.minimum(right, width + 1.0) - 0.5), width - 1).astype(np.int64)
    count = np.where(empty, 0, np.maximum(last - first + 1, 0))
    pixel_face = np.repeat(face, count)
    column = np.repeat(first, count) + np.arange(len(pixel_face)) - np.repeat(np.cumsum(count) - count, count)
    return np.repeat(row, count) * width + column, pixel_face


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


class NumpyView:
    """The rasteriser as a 3D view of (width, height) pixels, interchangeable with ggui3d.GGUIView."""

    name = "NumPy z-buffer rasteriser"

    def __init__(self, width: int, height: int):
        self.width, self.height = width, height

    def render(self, corners: np.ndarray, colors: np.ndarray, camera: Camera, background) -> np.ndarray:
        """The (height, width, 3) float image of world triangles (f, 3, 3) with corner colours (f, 3, 3)."""
        pixels, depth = camera.project(corners, self.width, self.height)
        return rasterise(pixels, depth, colors, self.width, self.height, background)

    def close(self) -> None:
        """Nothing to release (the interface of ggui3d.GGUIView)."""
