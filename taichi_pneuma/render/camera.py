"""A perspective camera orbiting a target, shared by the 3D renderers (NumPy rasteriser and GGUI).

World axes: y up. The eye sits at `distance` from the target, at `azimuth` degrees about the y axis
(0: on the +z side, looking down -z; positive turns towards +x) and `elevation` degrees above the
x-z plane:

    eye = target + distance (cos el sin az, sin el, cos el cos az).

The view basis is forward f = (target - eye) / |target - eye|, right r = f x y / |f x y|, up u = r x f;
a point p has camera coordinates (x, y, z) = ((p - eye) . r, (p - eye) . u, (p - eye) . f), z its depth,
and pixel coordinates (column, row from the top)

    (W / 2 + F x / z, H / 2 - F y / z),    F = (H / 2) / tan(fov / 2),

fov the vertical field of view (GGUI's convention): the same picture on both renderers.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ..errors import require, require_finite

MAX_ELEVATION = 89.0  # the orbit stops short of the poles, where the up vector is undefined


@dataclass(frozen=True)
class Camera:
    target: tuple[float, float, float] = (0.0, 0.0, 0.0)
    distance: float = 5.0
    azimuth: float = 30.0
    elevation: float = 25.0
    fov: float = 35.0

    def __post_init__(self):
        for name in ("distance", "azimuth", "elevation", "fov"):
            require_finite(name, getattr(self, name))
        require(self.distance > 0, f"distance = {self.distance!r} must be > 0")
        require(
            abs(self.elevation) <= MAX_ELEVATION,
            f"elevation = {self.elevation!r} must lie in [-{MAX_ELEVATION:g}, {MAX_ELEVATION:g}] degrees",
        )
        require(0 < self.fov < 170, f"fov = {self.fov!r} must lie in (0, 170) degrees")

    @property
    def eye(self) -> np.ndarray:
        az, el = np.radians(self.azimuth), np.radians(self.elevation)
        return np.asarray(self.target, float) + self.distance * np.array(
            [np.cos(el) * np.sin(az), np.sin(el), np.cos(el) * np.cos(az)]
        )

    def basis(self) -> np.ndarray:
        """Rows: right r, up u, forward f (orthonormal, right-handed as r x u = -f)."""
        f = np.asarray(self.target, float) - self.eye
        f /= np.linalg.norm(f)
        r = np.cross(f, [0.0, 1.0, 0.0])
        r /= np.linalg.norm(r)
        return np.array([r, np.cross(r, f), f])

    def focal(self, height: int) -> float:
        return height / 2 / np.tan(np.radians(self.fov) / 2)

    def to_camera(self, points: np.ndarray) -> np.ndarray:
        """Camera coordinates (..., 3): right, up, depth."""
        return (np.asarray(points, float) - self.eye) @ self.basis().T

    def project(self, points: np.ndarray, width: int, height: int) -> tuple[np.ndarray, np.ndarray]:
        """(pixels (..., 2) as (column, row from the top), depth (...)) of world points."""
        c = self.to_camera(points)
        focal = self.focal(height)
        return np.stack(
            [width / 2 + focal * c[..., 0] / c[..., 2], height / 2 - focal * c[..., 1] / c[..., 2]], axis=-1
        ), c[..., 2]

    def orbit(self, d_azimuth: float, d_elevation: float) -> Camera:
        """This camera turned about the target; the elevation is held within +-MAX_ELEVATION."""
        elevation = float(np.clip(self.elevation + d_elevation, -MAX_ELEVATION, MAX_ELEVATION))
        return replace(self, azimuth=(self.azimuth + d_azimuth) % 360.0, elevation=elevation)

    def fitted(self, points: np.ndarray, width: int, height: int, margin: float | tuple[float, float] = 0.06) -> Camera:
        """This camera's direction, aimed at the centre of the points' bounding box and moved just far enough
        that every corner of the box projects inside the frame, `margin` of it left free at each side (one
        fraction, or (left and right, top and bottom))."""
        lo, hi = np.min(points.reshape(-1, 3), axis=0), np.max(points.reshape(-1, 3), axis=0)
        target = (lo + hi) / 2
        aimed = replace(self, target=tuple(target), distance=1.0)
        corners = np.array(np.meshgrid(*zip(lo, hi), indexing="ij")).reshape(3, -1).T - target
        c = corners @ aimed.basis().T  # relative to the target: depth at distance d is c_z + d
        focal = self.focal(height)
        half = np.array([width, height]) / 2 * (1 - 2 * np.asarray(margin, float))
        needed = np.max(np.abs(c[:, :2]) * focal / half - c[:, 2:3])
        nearest = np.max(-c[:, 2]) + 1e-3 * np.ptp(corners)  # every corner in front of the eye
        return replace(aimed, distance=float(max(needed, nearest)))
