"""A PneuNet bending actuator from a few dimensions: a rubber block with a row of rounded-box chambers
near its top and a stiffer strain-limiting layer at its bottom.

Inflated, the chambers stretch the soft top while the layer keeps the bottom's length, so the finger
curls towards the layer (down, -y). Along x, from the left (clamped) end:

    end | chamber | gap | chamber | ... | chamber | end          length = 2 end + n chamber_length + (n - 1) gap

and from the bottom up: layer (region 'layer'), base, chamber_height, wall; across z: wall,
chamber_width, wall. With slit > 0 the middle of each gap is cut away, slit wide, from the top down to the chambers'
floor and through the whole width (a fast PneuNet's: each chamber its own walls, (gap - slit) / 2 thick on the slit's
side, so that inflated chambers bulge into the slits and press on each other; they need surface contact).

The block is centred on the origin. The chambers are named c1 .. cn from the left and sealed from each other (a real
PneuNet joins them by a thin air channel; here they are commanded together by giving them the same schedule). The
defaults extrude the 2D pneunet_finger scene: a 4 x 0.8 block, six 0.4 x 0.5 chambers with 0.1 gaps, a 0.15 layer,
here 0.76 deep.

The dataclass fields are the keys of the scene file's [body] table with shape = "pneunet".
"""

from __future__ import annotations

from dataclasses import dataclass

from ..errors import require, require_finite
from ..io.registry import key
from ..io.units import LENGTH
from .gmsh_mesher import MAX_SHAPES, Solid
from .solids import Box, Cut, RoundedBox

LAYER = "layer"


def length(default: float):
    """A length key whose default is the unitless pneunet_3d finger's (4 long): a scene with units gives every length
    it uses (io/registry.py key, scaled=False)."""
    return key(default, unit=LENGTH, scaled=False)


@dataclass(frozen=True)
class PneuNet:
    """The actuator's dimensions (see the module docstring); radius rounds the chambers' edges (0: sharp)."""

    chambers: int = 6
    name = "pneunet"
    chamber_length: float = length(0.4)
    chamber_height: float = length(0.5)
    chamber_width: float = length(0.6)
    radius: float = length(0.08)
    gap: float = length(0.1)
    wall: float = length(0.08)
    end: float = length(0.55)
    base: float = length(0.07)
    layer: float = length(0.15)
    slit: float = length(0.0)

    def __post_init__(self):
        require(
            isinstance(self.chambers, int) and not isinstance(self.chambers, bool) and 1 <= self.chambers <= MAX_SHAPES,
            f"chambers = {self.chambers!r} must be an integer from 1 to {MAX_SHAPES}",
        )
        for name in ("chamber_length", "chamber_height", "chamber_width", "gap", "wall", "end", "base"):
            value = getattr(self, name)
            require(require_finite(name, value) > 0, f"{name} = {value!r} must be > 0")
        for name in ("radius", "layer", "slit"):
            value = getattr(self, name)
            require(require_finite(name, value) >= 0, f"{name} = {value!r} must be >= 0")
        shortest = min(self.chamber_length, self.chamber_height, self.chamber_width)
        require(
            self.radius < shortest / 2,
            f"radius = {self.radius!r} must be < {shortest / 2:g} (half the chamber's shortest side)",
        )

        require(
            self.slit < self.gap,
            f"slit = {self.slit!r} must be < gap = {self.gap!r} (each chamber keeps a wall on either side of it)",
        )

    @property
    def size(self) -> tuple[float, float, float]:
        """The block's (length, height, width)."""
        n = self.chambers
        return (
            2 * self.end + n * self.chamber_length + (n - 1) * self.gap,
            self.layer + self.base + self.chamber_height + self.wall,
            self.chamber_width + 2 * self.wall,
        )

    @property
    def thinnest(self) -> float:
        """The thinnest rubber: the wall above and beside the chambers, or the gap between them (with a slit, a
        chamber's wall beside it)."""
        return min(self.wall, (self.gap - self.slit) / 2 if self.slit else self.gap)

    def solid(self) -> Solid:
        """The block, its chambers c1 .. cn and, if layer > 0, the region 'layer' (the bottom slab)."""
        length, height, width = self.size
        chamber = (self.chamber_length, self.chamber_height, self.chamber_width)
        y = -height / 2 + self.layer + self.base + self.chamber_height / 2
        chambers = []
        for i in range(self.chambers):
            x = -length / 2 + self.end + self.chamber_length / 2 + i * (self.chamber_length + self.gap)
            shape = RoundedBox((x, y, 0.0), chamber, self.radius) if self.radius > 0 else Box((x, y, 0.0), chamber)
            chambers.append((f"c{i + 1}", shape))
        regions = (
            ((LAYER, Box((0.0, (self.layer - height) / 2, 0.0), (length, self.layer, width))),) if self.layer else ()
        )
        block = Box((0.0, 0.0, 0.0), self.size)
        if not self.slit:
            return Solid(block, tuple(chambers), regions)
        floor, top = -height / 2 + self.layer + self.base, height / 2 + self.wall  # past the top: no coplanar faces
        slits = tuple(
            Box(
                (
                    -length / 2 + self.end + (i + 1) * self.chamber_length + i * self.gap + self.gap / 2,
                    (floor + top) / 2,
                    0.0,
                ),
                (self.slit, top - floor, width + 2 * self.wall),
            )
            for i in range(self.chambers - 1)
        )
        return Solid(Cut(block, slits), tuple(chambers), regions)
