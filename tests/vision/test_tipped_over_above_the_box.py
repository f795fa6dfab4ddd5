"""A part tipped over with its top above the search box is the print's, not an object reaching in from above
(masks.tipped_over: where bed shows in the part's place in a view, an object of the part's colour, new since the
previous check and meeting the part's outline along half its extent, is the part itself).

What a user would notice: a detached part left printing. Cross-check seed 45 ``021_detach`` (a grey frame 59 mm wide and
11 mm tall on a dark bed, four 640x480 cameras, two kept here): the part tipped 38 degrees before the first check, its
far side standing above the box in every view. Found foreign like the parked hotend, it counted in no figure: both views
read only missing material (15 and 17 %), which a first look forgives, and the print went on to its end.

Synthetic cases (tests/vision/synthetic.py: the part rows 80-170, columns 110-210) for each condition of the rule.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from octoprint_printwatch.core import masks
from octoprint_printwatch.core.masks import outline_zone, tipped_over

from .check_runs import run_checks
from .synthetic import PART, Box

RECORDING = Path(__file__).resolve().parents[1] / "data" / "recordings" / "frame_tipped_first_look"


def test_a_part_tipped_over_above_the_box_pauses_the_print_at_the_first_check():
    results = run_checks(RECORDING)
    assert [r.verdict for r in results] == ["fail", "fail"]
    first = results[0]
    assert any("unexpected material" in reason or "part displaced" in reason for reason in first.reasons)
    for view in first.shape.values():
        assert view.extra_pct > view.threshold           # the tipped part counts as material where none belongs
        foreign = 0 if view.foreign_mask is None else np.count_nonzero(view.foreign_mask)
        assert foreign < 0.1 * view.expected_pixels


def test_read_as_an_object_from_above_the_tipped_part_passes(monkeypatch):
    """The catch rests on the rule: with no contact long enough, the tipped part is foreign again and both checks
    pass."""
    monkeypatch.setattr(masks, "TIPPED_MIN_CONTACT_SHARE", float("inf"))
    assert [r.verdict for r in run_checks(RECORDING)] == ["ok", "ok"]


def _tipped(hanging: np.ndarray, before: np.ndarray | None = None, other_colour: bool = False) -> float:
    """The share of ``hanging`` (a blob found reaching in from above) that tipped_over takes for the part."""
    outline = outline_zone(PART.mask(), 2.0, 2.0)
    def colour(material: np.ndarray) -> np.ndarray:
        return material.copy() if other_colour else np.zeros_like(material)
    out = tipped_over(hanging, hanging, outline, before, colour)
    return out[hanging].mean()


# the top of the part tipped over in place, rising from its outline above the box along its whole width
RESTING = Box(PART.x0, 20, PART.x1, PART.y0 - 3).mask()
# the hotend's block beside the part, meeting the outline at its corner only
AT_A_CORNER = Box(40, 20, PART.x0 - 1, PART.y0 - 3).mask()


def test_an_object_of_the_parts_colour_resting_on_the_outline_is_the_part():
    assert _tipped(RESTING) == 1.0


def test_an_object_meeting_the_outline_at_a_corner_is_not():
    assert _tipped(AT_A_CORNER) == 0.0


def test_an_object_of_another_colour_is_not():
    assert _tipped(RESTING, other_colour=True) == 0.0


def test_an_object_where_one_hung_at_the_previous_check_is_not():
    """The hotend followed from the previous check (its image rises with the part's top) stays foreign."""
    assert _tipped(RESTING, before=Box(PART.x0, 25, PART.x1, PART.y0 - 8).mask()) == 0.0
    # ... while one that was not there is the part
    assert _tipped(RESTING, before=Box(250, 20, 290, 40).mask()) == 1.0
