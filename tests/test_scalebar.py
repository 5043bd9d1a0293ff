"""The scale bar's length is the largest round length within a fifth of the view, labelled with the unit."""

import pytest

from taichi_pneuma.render.scalebar import scale_bar


@pytest.mark.parametrize(
    "width, unit, expected",
    [(2.0, "", (0.2, "0.2")), (100.0, " mm", (20.0, "20 mm")), (30.0, " mm", (5.0, "5 mm")), (0.9, "", (0.1, "0.1"))],
)
def test_the_bar_is_one_two_or_five_times_a_power_of_ten_within_a_fifth_of_the_view(width, unit, expected):
    length, label = scale_bar(width, unit)
    assert length == pytest.approx(expected[0]) and label == expected[1]
    assert length <= 0.2 * width < 2.5 * length  # the next round length (x2 or x2.5) would be too long


def test_a_view_without_width_is_refused():
    with pytest.raises(ValueError, match="view_width"):
        scale_bar(0.0)
