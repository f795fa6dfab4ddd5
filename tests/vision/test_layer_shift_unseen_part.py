"""A view that reads most of the part missing gives no layer-shift evidence (eighteenth session, helper b18): a shift
moves the newest layers only, the layers below stay in place and are seen. A face in the bed's colour read as bed reads
"bed where the band should be" for any move of the band (cross-check seed 14 `042`: 61 % of the part missing in the
one view that "confirmed" an 8.8-mm shift, 448 confirming px, none of them material)."""
from octoprint_printwatch.core.layer_shift import band_shift
from octoprint_printwatch.core.verdict import SHIFT_VIEW_MAX_MISSING_PCT, band_shifts_of, decide
from octoprint_printwatch.core.settings import DetectionSettings
from octoprint_printwatch.core.shape_check import ShapeResult

from .synthetic import Box
from .test_layer_shift import J_ONE

TIER, BAND = Box(110, 110, 210, 170), Box(110, 100, 210, 110)
SHIFTED = TIER.mask() | BAND.moved(10, 0).mask()


def view(missing):
    """A passing, usable view whose band evidence alone confirms a 2-mm shift, reading ``missing`` % of the part
    missing."""
    found = band_shift(SHIFTED, ~SHIFTED, TIER.mask(), BAND.mask(), 24, 12, 5, 2.0, bed_to_image=J_ONE)
    return ShapeResult("cam", missing, missing, missing, 0.0, None, None, 500, 5000, 100.0, (0, 0), 7.0, 50.0,
                       passed=True, usable=True, reasons=[], band_shift=found)


def test_a_view_seeing_the_part_confirms_the_shift():
    verdict, reasons = decide({"cam": view(missing=5.0)}, {}, DetectionSettings())
    assert verdict == "fail" and any("layer shift?" in r for r in reasons)


def test_a_view_missing_most_of_the_part_gives_no_shift_evidence():
    unseen = view(missing=SHIFT_VIEW_MAX_MISSING_PCT + 11.0)
    assert band_shifts_of({"cam": unseen}) == {}
    verdict, reasons = decide({"cam": unseen}, {}, DetectionSettings())
    assert not any("layer shift?" in r for r in reasons)
