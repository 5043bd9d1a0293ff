"""The scene file's [[obstacles]] tables (terms/obstacles.py Obstacle), declared with fileformat.py's entries:

[[obstacles]]
name = "post"
shape = "sphere"               # one of OBSTACLE_SHAPES (plane, box, sphere, ...); the shape's keys follow
center = [3.0, -0.6]
radius = 0.3
dhat = 0.01                    # the barrier's threshold and stiffness, as [effects.ground]'s
stiffness = 1e3
keyframes = [[10, [0.0, 0.2, 0.0]]]   # its translation by step (none: static)
friction = 0.5                 # Coulomb coefficient (0, the default: frictionless)
friction_slip = 0.001          # the slip over which static friction reaches mu N (none: dhat / 10)
weight = 2.0                   # from step `release` on, free to move along y under this load along -y
release = 12
"""

from ..io.units import FORCE, LENGTH, NODAL_STIFFNESS
from ..terms.obstacle_shapes import OBSTACLE_SHAPES
from ..terms.obstacles import Obstacle
from .fileformat import Key, Table, Variant

SHAPE = Variant(OBSTACLE_SHAPES, choose=lambda shape: shape.name, doc="the obstacle's shape")
OBSTACLE = Table(
    {
        "name": Key(
            str,
            doc="distinct, not a chamber's; a plain name (letters, digits, _ + - .) not starting with = + - @ (it "
            "heads the history's <name>.fx, ... columns, and with friction <name>.friction.fx, ...)",
        ),
        "shape": SHAPE,
        "dhat": Key(float, None, "the contact barrier's threshold distance", unit=LENGTH, scaled=False, si=0.01),
        "stiffness": Key(float, None, "the barrier's stiffness", unit=NODAL_STIFFNESS, scaled=False, si=1e3),
        "keyframes": Key(
            tuple,
            None,
            "[[step, [dx, dy, dz]], ...]: its translation, linear between steps (2D: [dx, dy]), each component "
            "within 10 times the body's size; swept in sub-steps of at most half its dhat",
        ),
        "friction": Key(float, 0.0, "the Coulomb friction coefficient mu between it and the body (0: frictionless)"),
        "friction_slip": Key(
            float,
            None,
            "the tangential slip over which static friction rises to mu times the normal force (none: dhat / 10)",
            unit=LENGTH,
        ),
        "weight": Key(
            float,
            None,
            "a load W along -y (its weight): from step `release` on the obstacle is free to move along y, held by its "
            "contact and friction with the body alone (none: it stays where it is placed)",
            unit=FORCE,
        ),
        "release": Key(int, 0, "the step from which an obstacle with a weight is free"),
    },
    make=lambda v: Obstacle(**{**v, "keyframes": v["keyframes"] or ()}),
    parts=lambda o: {
        "name": o.name,
        "shape": o.shape,
        "dhat": o.dhat,
        "stiffness": o.stiffness,
        "keyframes": o.keyframes or None,
        "friction": o.friction or None,
        "friction_slip": o.friction_slip,
        "weight": o.weight,
        "release": o.release or None,
    },
    cls=Obstacle,
)
