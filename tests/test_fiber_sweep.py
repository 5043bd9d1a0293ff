"""A sweep over the winding angle of a braided tube (pneuma-sweep varying fibers[0].path.angle): below the magic
angle arctan(sqrt 2) = 54.74 degrees from the axis a pressurised braid shortens, above it it lengthens.

Why (the McKibben muscle's kinematics, derived here): an inextensible strand at angle a from the axis of a cylinder
of radius r and length L has length s with L = s cos a and 2 pi r n = s sin a (n its turns); the volume it encloses,
V = pi r^2 L = s^3 sin^2 a cos a / (4 pi n^2), is largest at tan^2 a = 2. Pressure does work p dV > 0 on the
chamber, so the braid moves towards the largest volume: a < 54.74 degrees opens (a grows: L = s cos a shrinks), a
greater one closes (L grows). The rubber tube's own stiffness weakens this near the magic angle, not far from it.
"""

import csv

from taichi_pneuma.apps.sweep import main

TUBE = """name = "braided_tube"
[body]
shape = "cylinder"
center = [0.0, 0.0, 0.0]
radius = 0.3
length = 2.0
axis = "x"
[mesh]
size = 0.12
[material]
E = 1e4
nu = 0.45
[clamp]
side = "left"
[[chambers]]
name = "c"
shape = "cylinder"
center = [0.0, 0.0, 0.0]
radius = 0.15
length = 1.7
axis = "x"
control = "pressure"
keyframes = [[2, 1500.0]]
[[fibers]]
name = "braid"
E = 1e9
diameter = 0.03
[fibers.path]
layout = "crossed"
center = [-0.95, 0.0, 0.0]
axis = "x"
radius = 0.23
angle = 30.0
extent = 1.9
strands = 6
[schedule]
increments = 2
"""


def test_a_braided_tube_shortens_below_the_magic_angle_and_lengthens_above_it(tmp_path):
    scene = tmp_path / "tube.toml"
    scene.write_text(TUBE)
    out = tmp_path / "study"
    argv = ["--scene", str(scene), "--vary", "fibers[0].path.angle=30,50,60,80", "--workers", "1"]
    assert main([*argv, "--out", str(out), "--quiet"]) == 0
    with open(out / "sweep.csv", newline="") as f:
        rows = {float(row["fibers[0].path.angle"]): row for row in csv.DictReader(f)}
    extension = {angle: float(row["tip_dx"]) for angle, row in rows.items()}
    assert all(row["converged"] == "true" for row in rows.values())
    assert extension[30.0] < extension[50.0] < 0 < extension[60.0] < extension[80.0]
    assert "tip_twist" in rows[30.0]  # a 3D study's table has the twist
