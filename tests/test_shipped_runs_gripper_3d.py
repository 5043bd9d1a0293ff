"""The shipped gripper_3d runs as shipped (about 90 s, a slow case) through `pneuma-inflate --scene gripper_3d`, exits 0
and writes its pictures (shipped_runs.py). Not coarser: on a coarser mesh a fingertip's face between two nodes enters
the ball before the grip holds it (the ball is touched at the fingers' nodes only), and the ramp stops there."""

import pytest
from shipped_runs import runs_and_writes_its_pictures


@pytest.mark.slow
def test_the_shipped_3d_gripper_exits_0_and_writes_its_pictures(tmp_path, capsys):
    runs_and_writes_its_pictures("gripper_3d", [], tmp_path, capsys)
