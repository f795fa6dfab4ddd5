"""The combined decision rule: :func:`decide` turns one check's shape results (per camera), size results (per
stereo pair) and each view's history into one verdict with its reasons, the one place a pause is decided; and
the small rules it weighs (a view's rise held, missing material kept since a rise, a standing offset, the
layer-shift evidence of the usable views)."""
from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any, Callable, Collection, Mapping, Sequence

import numpy as np

from .settings import DetectionSettings
from .layer_shift import (BandShift, LayerShift, band_reads_lowered, confirms_layer_shift, describe_layer_shift,
                          estimate_layer_shift, onto_earlier_places, with_history)
from .shape_check import ShapeResult
from .nest import (NEST_MAX_COVERAGE, PART_SLOWED_SOMEWHAT_PCT, SOLID_MIN_COVERAGE, TEXTURE_JUMP_STRONG,
                   texture_jump_for, texture_jump_for_lone_reading, textured_views)
from .tangle import TWO_VIEWS_MM2, loose_material


#: A view reading more than this share (%) of the whole part missing gives no layer-shift evidence: a shift moves the
#: newest layers only, and the layers below stay where they belong, seen. A view that misses most of the part (a face
#: in the bed's colour read as bed) reads "bed where the band should be" for any move of the band.
SHIFT_VIEW_MAX_MISSING_PCT = 50.0


#: A growth reading under this (%) is an outline that sank (a top face in the colour of what lies behind it
#: that came and went, a part knocked over), not a part that stopped: the stall rules leave it out (a stall reads
#: 0 +- a pixel step, about 15 % of a check's rise)
SANK_BELOW_PCT = -15.0


def band_shifts_of(shape: Mapping[str, ShapeResult]) -> dict[str, BandShift]:
    """{camera: BandShift}: the layer-shift evidence of the usable cameras that tested their newest band and see
    most of the part (SHIFT_VIEW_MAX_MISSING_PCT), not read against a relit background (ShapeResult.relit: lit bed
    read as the part offsets a band)."""
    return {cam: r.band_shift for cam, r in shape.items()
            if r.usable and not r.relit and r.band_shift is not None and r.missing_pct <= SHIFT_VIEW_MAX_MISSING_PCT}


def layer_shift_of(shape: Mapping[str, ShapeResult],
                   history: Sequence[tuple[bool, Mapping[str, BandShift]]] = (),
                   band_shifts: Mapping[str, BandShift] | None = None,
                   placed_at: Mapping[str, Sequence[tuple[int, int]]] | None = None) -> LayerShift | None:
    """The bed shift of the newest layers that the usable cameras confirm together (or None).

    ``history``: (had a check before it, band_shifts_of) of the previous checks, oldest first: the evidence
    for the same shift at those checks (``core.layer_shift.with_history``). ``band_shifts``: this check's
    ``band_shifts_of(shape)`` when the caller has it already. ``placed_at``: {camera: the (dx, dy) px its
    earlier passing checks laid the outline at}: a band read back onto them is the outline's walk, not the
    layers' (``LayerShift.onto_earlier_places``); None: not known.
    """
    views = band_shifts_of(shape) if band_shifts is None else band_shifts
    recent = list(history)[-4:]
    earlier = [looks for tested, looks in recent if tested and looks]
    # (the print's first check, while among them: its band is the whole part, its top the part's height)
    first = next((looks for tested, looks in recent if not tested and looks), None)
    shift = with_history(estimate_layer_shift(views, earlier=earlier, first=first), history)
    if shift is not None and placed_at is not None:
        shift.onto_earlier_places = onto_earlier_places(
            shift, {name: (view.aligned_at, placed_at.get(name, ())) for name, view in views.items()})
    return shift


def unseen_by_partner(result: ShapeResult, usable: Mapping[str, ShapeResult], pairs: Sequence[Sequence[str]],
                      extra_before: float | None) -> bool:
    """True when ``result`` fails on extra material alone (not decisive, less than a third of the threshold
    missing, no newest-band failure) that appeared at once (under a third of the threshold at the camera's
    previous check, ``extra_before``; never when it had none) while the other camera of one of its
    stereo ``pairs`` ([left, right] names) is ``usable``, passes and sees no extra material at all (every
    usable partner, where a camera belongs to several pairs)."""
    if (result.passed or result.decisive or result.missing_pct >= result.threshold / 3.0
            or (result.band_error_pct is not None and result.band_error_pct > result.band_threshold)
            or extra_before is None or extra_before >= result.threshold / 3.0):
        return False
    names = [b if a == result.camera else a for a, b in pairs if result.camera in (a, b)]
    partners = [usable[name] for name in names if name in usable]
    return bool(partners) and all(p.passed and p.extra_pct == 0.0 for p in partners)


#: A view reads the part rising as the model says at or above this share of a check's expected rise (%: the "visibly
#: grows" figure of decide)
VISIBLY_RISING_PCT = 50.0
#: ... and a decisive view's extra material at least this many times its missing material: a part or newest layers that
#: moved leave a gap where they stood (layer shifts seen by one view this way before: 1.4-2.6 times; an outline beside
#: a brim on normal prints: 3.6-6.7 times)
MOSTLY_EXTRA_RATIO = 3.0


def sees_nothing_extra(result: ShapeResult) -> bool:
    """True when a view passes with no extra material at all and measured less new material beside the part, its foot
    included, than the loose-material rule asks of each of two views (``tangle.TWO_VIEWS_MM2``): strands lying off
    the part's outline show there first (seed 24 ``030_spaghetti``'s first catch: 1.1 mm^2 beyond the bed-marks zone
    and 7.4 at the foot in the view whose outline read none)."""
    new = result.new_outside
    return (result.passed and result.extra_pct == 0.0
            and (new is None or new.with_foot_mm2 < TWO_VIEWS_MM2))


def rise_since_previous_check(result: ShapeResult) -> float | None:
    """A view's reading of the rise since its previous check (% of the expected): fine, else read to the pixel
    (``coarse_growth_pct``, a part seen small); None: neither. A reading over a span of checks is left out: it
    reaches back to checks before whatever happened since."""
    return result.growth_pct if result.growth_pct is not None else result.coarse_growth_pct


def readings_of_the_rise(usable: Mapping[str, ShapeResult]) -> list[float]:
    """The readings of the part's rise since the previous check (% of the expected) that say whether it grows: the
    fine ones where two or more views read it finely, or the only usable view does; else each view's fine reading or,
    where it has none, its reading to the pixel (:func:`rise_since_previous_check`). A view that sees the part small
    reads its rise only to the pixel, so where one view reads it finely beside it (or none does), the fine readings
    alone are one view's reading or none; the reading to the pixel is +-25 %, but a rise of 100 % read so is no
    stopped part (0 +- a pixel step)."""
    fine = [r.growth_pct for r in usable.values() if r.growth_pct is not None]
    return fine if enough_rise_readings(fine, usable) else each_views_rise(usable)


def enough_rise_readings(readings: Sequence[float], usable: Mapping[str, ShapeResult]) -> bool:
    """Whether ``readings`` of the rise make a median: two or more, or the only usable view's (a one-camera rig has no
    other view to ask)."""
    return len(readings) >= 2 or (bool(readings) and len(usable) == 1)


def median_rise(readings: Sequence[float], usable: Mapping[str, ShapeResult]) -> float | None:
    """The median of ``readings`` of the rise where they make one (:func:`enough_rise_readings`), else None."""
    return float(np.median(readings)) if enough_rise_readings(readings, usable) else None


def rise_by_view(usable: Mapping[str, ShapeResult]) -> dict[str, float]:
    """{camera: its reading of the rise since its previous check}, fine or else to the pixel
    (:func:`rise_since_previous_check`), for the usable views that have one."""
    return {cam: reading for cam, r in usable.items() if (reading := rise_since_previous_check(r)) is not None}


def each_views_rise(usable: Mapping[str, ShapeResult]) -> list[float]:
    """Each usable view's reading of the rise since its previous check, where it has one (:func:`rise_by_view`)."""
    return list(rise_by_view(usable).values())


def _steady(reading: float) -> float:
    """A reading of the rise of :data:`RISE_OVERSHOOT_PCT` or more counts as none: no part rises faster than its
    model, so its top jumped in the picture (read a check late, or a part standing up where it tipped over)."""
    return 0.0 if reading >= RISE_OVERSHOOT_PCT else reading


def _rises(readings: Sequence[float], steadily: bool = False) -> bool:
    if steadily:
        readings = [_steady(reading) for reading in readings]
    return bool(readings) and float(np.median(readings)) >= VISIBLY_RISING_PCT


def visibly_rising_finely(usable: Mapping[str, ShapeResult], steadily: bool = False) -> bool:
    """Whether the median of the usable views' fine readings of the rise is :data:`VISIBLY_RISING_PCT` or more
    (every reading counts, one that sank too: it is evidence against growth); ``steadily``: a reading of
    :data:`RISE_OVERSHOOT_PCT` or more counts as none (no part rises faster than its model: its top jumped in the
    picture, read a check late or a part standing up where it tipped over)."""
    return _rises([r.growth_pct for r in usable.values() if r.growth_pct is not None], steadily)


def visibly_rising(usable: Mapping[str, ShapeResult], steadily: bool = False) -> bool:
    """Whether the part's outline rises as the model says: :func:`visibly_rising_finely`, or the median of
    :func:`readings_of_the_rise` (readings to the pixel standing in for too few fine ones) is
    :data:`VISIBLY_RISING_PCT` or more (``steadily``: as for :func:`visibly_rising_finely`)."""
    return visibly_rising_finely(usable, steadily) or _rises(readings_of_the_rise(usable), steadily)


def missed_as_much_before(result: ShapeResult, most_missing_before: Mapping[str, float] | None) -> bool:
    """Whether a view misses no more of the part, by half its threshold, than it did at one of its earlier checks
    (``most_missing_before``: the most it missed at the checks that passed since it was last unusable; None or
    absent: no such check). A face the view cannot tell from what lies behind it is missing from the view's first
    look on; a part that tipped or moved away goes missing at once (seed 30 ``053_detach``: 0 -> 20.7 % in one
    check)."""
    before = (most_missing_before or {}).get(result.camera)
    return before is not None and result.missing_pct - before < result.threshold / 2.0


#: Views that see the part whole where it belongs and nothing extra that set a first look's decisive extra material
#: aside (unseen_by_the_other_views: at a first look no view reads the rise)
FIRST_LOOK_WITNESSES = 2


def unseen_by_the_other_views(result: ShapeResult, usable: Mapping[str, ShapeResult]) -> bool:
    """True when ``result`` fails on extra material (more than half its missing material) that every other ``usable``
    view not read against a relit background (at least one) does not see at all (:func:`sees_nothing_extra`) and none
    of them reads finely as rising under ``VISIBLY_RISING_PCT`` of the model's rise (a part that stops rising while
    material spills beside it is spaghetti starting): when that extra material is not decisive and the newest band
    is within its threshold, or when it is decisive (four times the threshold, or with missing material) but
    ``MOSTLY_EXTRA_RATIO`` times the missing material, the part not found whole elsewhere, while this view, not relit,
    and another view not relit read the part rising as the model says since their previous check
    (:func:`rise_since_previous_check`: fine, or to the pixel); at this view's first look, which has no rise to read,
    while :data:`FIRST_LOOK_WITNESSES` of the other views miss under a third of their threshold (the part whole where
    it belongs).

    Material standing beside the part stands on the bed, where other cameras look too: a strand or blob shows some
    extra in a second view, and a part that detached or spills strands does not keep rising in the view that sees
    them; a part that moved leaves about as much missing where it stood as it brings extra where it went. Extra
    material no other view sees in any amount is the failing view's own error: its outline laid beside the part (a
    first look or an anchor on a brim or a 2 mm slice: the part's side beyond the outline, the brim filling the
    outline's other edge), its background frame (a parked head's shadow whose edge moved: lit bed). A displaced
    newest band beside extra material that is not decisive (a layer shift one view's band sees) still counts.
    A relit view is no witness either way: where a reflection crosses the part it reads lit bed as extra material
    (it never fails a print alone in decide), so its extra neither confirms nor refutes the failing view's.
    """
    if result.passed or result.extra_pct * 2.0 <= result.missing_pct:
        return False
    others = [r for name, r in usable.items() if name != result.camera]
    witnesses = [r for r in others if not r.relit]
    if not (witnesses and all(sees_nothing_extra(r) for r in witnesses)):
        return False
    # (nor where another view reads the part rising under half the expected rise, finely: material spilling beside
    # a part that stops rising is spaghetti starting, which the other views see as the stop, not as extra material;
    # cross-check seed 36 `026_spaghetti` check 2: s1 19.7 % extra, s0 none but a 33 % rise)
    if any(r.growth_pct is not None and r.growth_pct < VISIBLY_RISING_PCT for r in witnesses):
        return False
    if not result.decisive:
        return result.band_error_pct is None or result.band_error_pct <= result.band_threshold

    def rising(r: ShapeResult) -> bool:
        reading = rise_since_previous_check(r)
        return not r.relit and reading is not None and reading >= VISIBLY_RISING_PCT

    if result.moved_px is not None or result.extra_pct < MOSTLY_EXTRA_RATIO * result.missing_pct:
        return False
    if result.first_look:
        # (a first look has no rise to read: there, two views that see the part whole where it belongs, nothing
        # extra and under a third of their threshold missing, stand in for the rise; a part knocked off or tangled
        # before the first check misses or spills in them too)
        return sum(r.missing_pct < r.threshold / 3.0 for r in witnesses) >= FIRST_LOOK_WITNESSES
    return rising(result) and any(rising(r) for r in others)


#: A coarse growth reading counts in decide only from a view that read the part rising this much (%) at its
#: previous check (fine or coarse reading)
COARSE_ROSE_BEFORE_PCT = 50.0


#: Views that read a stop after a held rise that stall a print with nothing missing yet (decide): one view's reading
#: jumps by a pixel step, two at the same check do not (every usable view where fewer are usable: stopped_views_needed)
STOPPED_VIEWS = 2
#: ... where one of them misses this much of the part (%), or twice as much of its newest band
STOPPED_MIN_MISSING_PCT = 1.0


#: At the print's first reading of the rise (no view held one before), the trace of the part (%) one view that reads
#: none must miss more than at its previous check: with no rise held before, a stop is told from a top the camera
#: cannot resolve by its missing layers alone (before any onset on the development sets no such view missed over
#: 0.74 %; a stop under way since before the first check missed 3.5-7 % more)
FIRST_STOP_MIN_MISSING_PCT = 2.0 * STOPPED_MIN_MISSING_PCT


def stopped_views_needed(usable: int) -> int:
    """How many views that held a rise and read none now stall a print with a trace missing (decide): STOPPED_VIEWS,
    or every usable view where fewer are usable. A second view outvotes one view's pixel step; a one-camera rig has
    none, and there, as on two views, the trace of the newest layers missing tells a stop from a top the camera
    cannot resolve (that reads 0 with nothing missing)."""
    return max(1, min(STOPPED_VIEWS, usable))


def _rise_readings(result: ShapeResult) -> list[float]:
    """A view's readings of the rise at this check (% of the expected), finest first: fine, over the span, coarse."""
    return [x for x in (result.growth_pct, result.span_growth_pct, result.coarse_growth_pct) if x is not None]


def finest_reading(result: ShapeResult) -> float | None:
    """A view's finest reading of the rise (% of the expected): fine, else over the span, else coarse; None: none."""
    return next(iter(_rise_readings(result)), None)


def finest_readings(usable: Mapping[str, ShapeResult]) -> dict[str, float]:
    """Each view's finest reading of the rise (:func:`finest_reading`), where it has one and its outline did not sink
    (:data:`SANK_BELOW_PCT`)."""
    return {cam: reading for cam, r in usable.items()
            if (reading := finest_reading(r)) is not None and reading >= SANK_BELOW_PCT}


def held_a_rise(held_rise_before: Mapping[str, float] | None, camera: str) -> bool:
    """Whether ``camera``'s readings before this check held a rise of :data:`COARSE_ROSE_BEFORE_PCT` or more
    (``held_rise_before``: :func:`held_rise` per view): a stop in that view is a change."""
    return ((held_rise_before or {}).get(camera) or 0.0) >= COARSE_ROSE_BEFORE_PCT


#: A view's reading of a rise at its previous check corroborates a stop (decide's ``held_rise_before``) only
#: when its last this many readings of the rise read one: where the camera cannot resolve the top, its readings
#: jump by a pixel step from one check to the next (0-200 %), so one reading of a rise before a 0 is no history
#: of rising.
RISE_HELD_READINGS = 2

#: A reading of the rise at this share of the expected or more is itself a pixel step, not a rise held: no part
#: rises faster than its model, so a view reading half again the expected rise read its top late (a 0 at one check
#: and 200 % at the next), and the reading before it belongs to the same measurement (held_rise).
RISE_OVERSHOOT_PCT = 150.0


#: A view reading at least this share of the expected rise (fine, over its span or coarse) saw the part rise as the
#: model says: a stop that no view shows as missing material does not stand against it (decide).
FULL_RISE_PCT = 100.0


def a_view_reads_the_full_rise(usable: Mapping[str, ShapeResult]) -> bool:
    """Whether any usable view reads the rise the model expects (:data:`FULL_RISE_PCT`, :func:`rise_read`)."""
    return any(rise_read(r) >= FULL_RISE_PCT for r in usable.values())


def rise_read(r: ShapeResult) -> float:
    """A view's highest reading of the rise at this check (% of the expected): fine, over its span or coarse;
    0 (none)."""
    return float(max(_rise_readings(r), default=0.0))


def held_rise(readings: Sequence[float], read_at_previous: bool,
              min_growth_pct: float = DetectionSettings.min_growth_pct) -> float | None:
    """The rise (% of the expected) a view read at its previous check where its readings before held it: the lowest
    of its last :data:`RISE_HELD_READINGS` readings (``readings``: its finest, fine, else over the span, else coarse,
    at its checks that gave one since it was last unusable, oldest first), or None where the previous check gave no
    reading (``read_at_previous`` False) or too few readings were given.

    A stop late in the interval before the previous check leaves that check reading part of the rise
    (``min_growth_pct`` to :data:`COARSE_ROSE_BEFORE_PCT`: the layers printed before the stop), the checks after it
    none; where the :data:`RISE_HELD_READINGS` readings before that partial one held a rise, the view held that rise
    up to the stop (as ``missing_since_rise`` keeps its missing material through such a reading).

    A reading of :data:`RISE_OVERSHOOT_PCT` or more among the last ones is a top read late, so the reading before them
    joins the history (and a history too short for that holds nothing): a view whose readings run 0, 67, 200 % read
    no steady rise before a 17 % (cross-check seed 43 ``013_normal``, a black L on glass whose stereo partner could
    not tell it from the bed), while a stop after a steady rise is still one after a late reading (86, 100, 200 %,
    then 14 %: seed 41 ``045_detach``)."""
    if not read_at_previous or len(readings) < RISE_HELD_READINGS:
        return None
    before_stop = readings[-RISE_HELD_READINGS - 1:-1]
    if (min_growth_pct <= readings[-1] < COARSE_ROSE_BEFORE_PCT and len(before_stop) == RISE_HELD_READINGS
            and min(before_stop) >= COARSE_ROSE_BEFORE_PCT):
        return float(min(before_stop))
    held = readings[-RISE_HELD_READINGS:]
    if max(held) >= RISE_OVERSHOOT_PCT:
        if len(readings) <= RISE_HELD_READINGS:
            return None
        held = readings[-RISE_HELD_READINGS - 1:]
    return float(min(held))


#: A view keeps its missing material from its last rising check (missing_since_rise) for at most this many
#: checks since at which nothing went missing (under a quarter of its threshold more than at the rise): a stop
#: late in an interval may show nothing at the first check after it, never at the second (a whole interval's
#: layers are then gone); a view that reads "no rise" while nothing goes missing cannot see the part rise.
RISE_QUIET_CHECKS = 2


def missing_since_rise(kept: float | None, rise: float | None, missing: float,
                       min_growth_pct: float, quiet: int = 0,
                       threshold: float | None = None,
                       rise_before: float | None = None) -> tuple[float | None, int]:
    """A view's ``CameraState.rise_missing`` and ``rise_quiet`` after a check: its missing material
    (``missing``, %) when it read the part rising there (``rise``: fine or else coarse growth, % of the expected
    rise, at least :data:`COARSE_ROSE_BEFORE_PCT`); the value ``kept`` from an earlier such check while it
    reads a stall (-15 % to ``min_growth_pct``: 0 +- a pixel step) or no reading at all (the model's outline
    does not rise in this view there, e.g. a tier printed inside the silhouette of the one below: no evidence
    either way), counting the checks since (``quiet``) at which it misses under a quarter of ``threshold``
    more than ``kept`` (None: none counted), and forgotten at the :data:`RISE_QUIET_CHECKS`-th; None after any
    other reading, except a part of the rise (``min_growth_pct`` to :data:`COARSE_ROSE_BEFORE_PCT`) read right
    after the rising check itself (``rise_before``: the view's reading at its previous check): the check after a
    stop reads the layers printed before it in that interval, the checks after it none."""
    if rise is not None and rise >= COARSE_ROSE_BEFORE_PCT:
        return missing, 0
    stop_within_interval = (rise is not None and min_growth_pct <= rise
                            and (rise_before or 0.0) >= COARSE_ROSE_BEFORE_PCT)
    if kept is None or (rise is not None and not SANK_BELOW_PCT <= rise < min_growth_pct and not stop_within_interval):
        return None, 0
    if threshold is not None and missing - kept < threshold / 4.0:
        quiet += 1
        if quiet >= RISE_QUIET_CHECKS:
            return None, 0
    return kept, quiet


#: A view's newest band counts as gone since it read the part rising (standing_offset) once this many points more
#: of it are missing than then (the stall rule's share of the band gone).
BAND_GONE_SINCE_RISE_PCT = 25.0


def lowest_missing_while_rising(kept: tuple[float, float | None] | None, rise: float | None, missing: float,
                                band_missing: float | None) -> tuple[float, float | None] | None:
    """A view's ``CameraState.missing_while_rising`` after a check: the lowest of its missing material (``missing``,
    %) and of its newest band's (``band_missing``; None: no band figures) at the checks where it read the part
    rising (``rise``: fine or else coarse growth, at least :data:`COARSE_ROSE_BEFORE_PCT`), ``kept`` from the
    earlier ones (None: none yet)."""
    if rise is None or rise < COARSE_ROSE_BEFORE_PCT:
        return kept
    if kept is None:
        return missing, band_missing
    return min(kept[0], missing), min((x for x in (kept[1], band_missing) if x is not None), default=None)


def standing_offset(result: ShapeResult, while_rising: tuple[float, float | None] | None) -> bool:
    """Whether a view's missing material (``result``) is no more than it read at a check where it saw the part
    rise (``while_rising``: its lowest missing material, overall and of the newest band, at such checks;
    :func:`lowest_missing_while_rising`): under half its threshold more overall, or no more than the share of the
    newest band it missed at its rising checks, and under :data:`BAND_GONE_SINCE_RISE_PCT` more of the newest band.
    Material missing while the part rose is a face the camera cannot tell from what lies behind it (decide's
    "visibly grows" rule); the same share missing later is that face still, while a stop leaves the newest layers
    missing on top of it. (A view that missed a share of every newest band while the part rose misses that share
    of each layer as it piles up: the whole part's share climbs toward it, check by check, with nothing stopped.)"""
    if while_rising is None:
        return False
    missing, band = while_rising
    within_part = (result.missing_pct - missing < result.threshold / 2.0
                   or (band is not None and result.missing_pct <= band))
    if not within_part:
        return False
    return band is None or result.band_missing_pct is None or \
        result.band_missing_pct - band < BAND_GONE_SINCE_RISE_PCT


def rise_for_loose_material(usable: Mapping[str, ShapeResult], growth: Sequence[float]) -> float | None:
    """The part's rise since the previous check (% of the expected) that :func:`core.tangle.loose_material` weighs
    (``rise_pct``), or None: the median of ``growth`` (the fine readings, ``ShapeResult.growth_pct``, of -15 % or
    more) when two or more views measured it, or the only usable camera did (there is no other view to ask);
    else, where views read the rise coarsely (``coarse_growth_pct``: a part seen small, a rise of 4-6 px per
    check), the median over the views of each one's fine reading or else its coarse one, under the same
    condition. A coarse reading is +-25 %, and a view that cannot see the top rise reads 0 at every check, so
    alone it proves nothing (a normal print reads under 50 % at a few checks); here it is only the second
    witness of material new beyond the outline, which such a check of a normal print does not show: a part
    knocked off or stopped under a pile of strands does both."""
    fine = median_rise(growth, usable)
    return fine if fine is not None else median_rise([g for g in each_views_rise(usable) if g >= SANK_BELOW_PCT],
                                                     usable)


def lone_rise_reading(usable: Mapping[str, ShapeResult],
                      rise_before: Mapping[str, float | None] | None) -> float | None:
    """The rise since the previous check (% of the expected, -15 % or more: :func:`rise_since_previous_check`) of the
    only one of two or more usable views that reads it, where that view read the part rising (50 %) at its previous
    check (``rise_before``: a view that never sees the top rise reads 0 at every check), or None. No median of
    readings exists there to weigh (:func:`enough_rise_readings`)."""
    readings = {cam: reading for cam, reading in rise_by_view(usable).items() if reading >= SANK_BELOW_PCT}
    if len(readings) != 1 or len(usable) < 2:
        return None
    ((camera, reading),) = readings.items()
    return reading if ((rise_before or {}).get(camera) or 0.0) >= COARSE_ROSE_BEFORE_PCT else None


def rose_in_a_view_read_to_the_pixel(usable: Mapping[str, ShapeResult]) -> bool:
    """Whether no usable view reads the rise finely and one reads the full rise to the pixel (``coarse_growth_pct`` of
    FULL_RISE_PCT, under RISE_OVERSHOOT_PCT: :func:`_steady`). Where the texture rule weighs a rise of 50-79 % (its
    TEXTURE_JUMP_STRONG band), such a rise is then the median of readings of +-25 % each: one view's 50 % and another's
    100 % say no more than "rose three quarters, give or take a pixel", while the view reading 100 % saw the whole rise,
    and a part stopped under a nest of strands reads 0 +- a pixel step in every view. Cross-check seed 39
    ``006_normal``, a yellow cone on black PEI seen small by two cameras: s0 50 %, s1 100 %, and s0's newest band, near
    its texture floor at the two checks before, 2.9 times as textured at the cone's shoulder."""
    if any(r.growth_pct is not None for r in usable.values()):
        return False
    return any(_steady(reading) >= FULL_RISE_PCT for reading in each_views_rise(usable))


def rise_over_spans(usable: Mapping[str, ShapeResult]) -> float | None:
    """The part's rise (% of the expected) over the views' spans of checks (``ShapeResult.span_growth_pct``) where
    no view reads it at one check, finely or to the pixel: the median of the span readings (-15 % or more) of two or
    more views, or the only usable view's; else None. A span reaches back to checks before whatever slowed the part,
    so it reads more of the rise than the last check saw: under a limit, the last check's rise is under it too."""
    if any(rise_since_previous_check(r) is not None for r in usable.values()):
        return None
    return median_rise([r.span_growth_pct for r in usable.values()
                        if r.span_growth_pct is not None and r.span_growth_pct >= SANK_BELOW_PCT], usable)


def rise_or_over_spans(usable: Mapping[str, ShapeResult], rise_pct: float | None) -> tuple[float | None, str]:
    """(rise %, how it was read): ``rise_pct`` (:func:`rise_for_loose_material`), else the views' readings over their
    spans where no view reads the rise at one check (:func:`rise_over_spans`, " over the last checks"), else None."""
    if rise_pct is not None:
        return rise_pct, ""
    rise = rise_over_spans(usable)
    return rise, "" if rise is None else " over the last checks"


def rise_for_texture(usable: Mapping[str, ShapeResult], rise_pct: float | None,
                     rise_before: Mapping[str, float | None] | None) -> tuple[float | None, float | None, str]:
    """(rise %, jump, how it was read) for decide's textured-band rule: the rise it weighs, how many times as textured
    as before a band must look there (None: no test) and the words the reason adds. The rise is the first that
    exists of ``rise_pct`` (:func:`rise_for_loose_material`), the views' readings over their spans where no view
    reads it at one check (:func:`rise_over_spans`), and the reading of the only one of several views that reads it
    (:func:`lone_rise_reading`, with its stricter :func:`core.nest.texture_jump_for_lone_reading`); no rise, no test."""
    rise, over = rise_or_over_spans(usable, rise_pct)
    if rise is None:
        lone = lone_rise_reading(usable, rise_before)
        return (None, None, "") if lone is None else (lone, texture_jump_for_lone_reading(lone), " (read by one view)")
    jump = texture_jump_for(rise)
    if jump == TEXTURE_JUMP_STRONG and rose_in_a_view_read_to_the_pixel(usable):
        jump = None   # a part that slowed somewhat by readings to the pixel, one of which read the full rise
    return rise, jump, over


def stopped_and_textured(usable: Mapping[str, ShapeResult], settings: DetectionSettings, *,
                         held_rise_before: Mapping[str, float] | None,
                         band_texture_before: Mapping[str, float] | None) -> dict[str, float]:
    """The views that stopped (a rise held at their previous readings, ``held_rise_before``, and none read now: their
    finest reading under ``min_growth_pct``) while their newest band turned :data:`TEXTURE_JUMP_STRONG` times as
    textured as at their checks before (``band_texture_before``), with that ratio; none where the median of every
    view's finest reading is :data:`PART_SLOWED_SOMEWHAT_PCT` or more. Strands piled over a part that stopped read
    in that view as both a stop and a changed band, where no median of one-check readings exists to slow (views
    seen small read the rise only over a span or to the pixel; a span reaching back before the stop still reads
    part of the rise). A view that never saw the part rise, or one reading some rise, is no such witness."""
    readings = finest_readings(usable)
    if not readings or float(np.median(list(readings.values()))) >= PART_SLOWED_SOMEWHAT_PCT:
        return {}
    stopped = {cam for cam, reading in readings.items()
               if reading < settings.min_growth_pct and held_a_rise(held_rise_before, cam)}
    return textured_views({cam: usable[cam].band_texture for cam in stopped}, band_texture_before or {},
                          TEXTURE_JUMP_STRONG)


#: A view whose outline sank by at least this share of a check's expected rise (its finest reading, % : -50 is half a
#: check's layers gone from its top) saw the part go down, not stop: material does not vanish (knocked_over)
SUNK_PCT = -50.0
#: ... where one of two such views misses this many times its threshold of the part (as the decisive extra material)
KNOCKED_MISSING_THRESHOLDS = 4.0


def knocked_over(usable: Mapping[str, ShapeResult]) -> str | None:
    """The reason to pause for a part knocked over or off its place, or None: two views (not relit) whose outline
    sank (finest reading :data:`SUNK_PCT` or lower) at the same check, one of them missing
    :data:`KNOCKED_MISSING_THRESHOLDS` times its threshold of the part. A part that moved away misses where it stood,
    and where it lies in a view the outline's search does not reach, or another view cannot tell it from the bed,
    nothing reads extra beside the gap (the decisive signature needs both). One view's outline sinks where a top
    face in the colour of what lies behind it comes and goes (the stall rules leave such readings out), and a view
    can miss most of a part it cannot see, but two sunk outlines at once with most of the part gone are a fall."""
    sunk = {cam: r for cam, r in usable.items()
            if not r.relit and (reading := finest_reading(r)) is not None and reading <= SUNK_PCT}
    gone = [r for r in sunk.values() if r.missing_pct >= KNOCKED_MISSING_THRESHOLDS * r.threshold]
    if len(sunk) < 2 or not gone:
        return None
    worst = max(gone, key=lambda r: r.missing_pct)
    return (f"the part's outline sank in {', '.join(sorted(sunk))} since the previous check while {worst.camera} "
            f"misses {worst.missing_pct:.0f}% of the part: the part knocked over or off its place?")


@dataclass(frozen=True)
class Stall:
    """Whether the part stopped growing at a check (:func:`part_stalled`)."""
    stalled: bool
    #: the rise readings (% of the expected) the stall was read on, or this check's fine readings where none fired
    #: (decide quotes their median, and the loose-material rule weighs them: :func:`rise_for_loose_material`)
    growth: list[float]
    #: over what the rise was read: "since the previous check" or "over the last checks"
    since: str
    #: views whose newest band is bare where it read solid before (a nest of strands over a stopped part)
    bare_band: list[ShapeResult]
    #: the limit (% of the expected rise) the readings were held to: fine_stall_limit for fine readings, else the
    #: settings' ``min_growth_pct``
    limit: float | None = None


#: A fine reading of the rise (``growth_pct``, ``span_growth_pct``: growth.profile_growth reads one only where the model's
#: top rises a median of 1.5 x 4 px) reads a stall up to this (% of the expected rise), just above one pixel of the
#: smallest such rise (1/6, 16.7 %, in float32): a stalled part reads 0 +- a pixel, and under the 15 % of
#: ``min_growth_pct`` alone its one-pixel reading of a 6-px rise read as a part rising (cross-check seed 33
#: ``034_spaghetti``, seed 28 ``024_runout``: every view 16.7 % with the newest layers missing). Before any onset on the
#: development seeds 20, 24 and 27-33, fine or span readings fell in 15-17 % at 4 checks (one of a normal print, beside a
#: view reading 75 %). A reading to the pixel (``coarse_growth_pct``, a rise of 4-6 px: a pixel is 17-25 %) keeps
#: ``min_growth_pct``: such readings of 16.7-25 % stood before an onset at 11 checks (normal prints among them), and
#: with 17 % for them too one view in the bed's colour paused seed 28 ``023_layer_shift`` before its onset.
FINE_STALL_PCT = 17.0


def _rounded_under(value: float, limit: float) -> str:
    """``value`` (%) to the unit, or to a tenth where the unit would read it at or over ``limit`` (16.7 % under 17)."""
    return f"{value:.0f}" if round(value) < limit else f"{value:.1f}"


def fine_stall_limit(settings: DetectionSettings) -> float:
    """The limit a fine reading of the rise (one check's, or over its span) reads a stall under (FINE_STALL_PCT)."""
    return max(settings.min_growth_pct, FINE_STALL_PCT)


def rising_over_spans(usable: Mapping[str, ShapeResult]) -> bool:
    """Whether :data:`STOPPED_VIEWS` or more views that see the part as its model says (their shape check passed) read
    the rise over a span of checks only (``ShapeResult.span_growth_pct``) and every one of them reads more than a part
    stopped since the previous check rose: over n checks at most (n - 1) / n of the expected, read above that by more
    than a pixel step (:data:`FINE_STALL_PCT`), an overshoot counting as none (:func:`_steady`). Against one view's
    fine reading of no rise: a top whose newest band that view read as background at one check (cross-check seed 47
    ``004_normal`` s1, a dark red tower reading 43 %, 0 %, 157 % at three checks running, while s0L and s0R read 100 %
    and 86 % over three checks). A view that sees material where the model has none (a
    part knocked off, strands piling up) reads their top, not the part's."""
    spans = [(r.span_growth_pct, r.growth_span or 1) for r in usable.values()
             if r.passed and r.growth_pct is None and r.span_growth_pct is not None]
    return len(spans) >= STOPPED_VIEWS and all(
        _steady(reading) > 100.0 * (span - 1) / span + FINE_STALL_PCT for reading, span in spans)


def part_stalled(usable: Mapping[str, ShapeResult], settings: DetectionSettings, *, top_closing: bool,
                 band_coverage_before: Mapping[str, float] | None, rise_before: Mapping[str, float | None] | None,
                 missing_before: Mapping[str, float] | None, missing_at_rise: Mapping[str, float] | None,
                 held_rise_before: Mapping[str, float] | None, first_rise_reading: bool = False) -> Stall:
    """The stall rules of :func:`decide` (its docstring lists them) over the usable views' rise readings.
    ``first_rise_reading``: no earlier check of the print gave any view a reading of the rise
    (stopped_at_the_first_reading)."""
    # A part that stopped growing stopped in every view: the growth test is decided on the median over
    # the cameras that could measure it, so one camera fooled by a top face the colour of the
    # background cannot pause a print on its own.
    # An outline that sank is not a part that stopped (material does not vanish; a stalled part reads
    # 0 +- one pixel step, about 15 % of a check's rise): that camera was fooled at this check or the
    # previous one (a top face the colour of what lies behind it); readings below -15 % are left out.
    band_coverage_before = band_coverage_before or {}
    # (fine readings, one check's or over a span, read a stall within a pixel of none: FINE_STALL_PCT)
    fine_limit = fine_stall_limit(settings)

    def stall_rules(read: Mapping[str, float], stopped: Collection[str] = ()) -> tuple[bool, list]:
        """Whether the part stalled by the rules below on the growth readings ``read`` (camera -> %, each of -15 %
        or more), and the views whose newest band is bare (for the reasons). ``stopped``: views whose low reading
        needs no missing material to corroborate it (a rise they read at their previous check)."""
        measured = {cam: usable[cam] for cam in read}
        growth = list(read.values())
        # ... and where the part stopped, its newest layers are missing in a view that sees no rise; without
        # that, a flat rise is a top skin closing in a colour the camera cannot tell from the bed
        # (where a top surface closes in the newest layers, ``top_closing``, its smooth skin may read missing
        # as a whole, like the bed: then only the newest band itself gone counts)
        # (a view whose rise only reads to the pixel, ``coarse_growth_pct``, and that reads none, is such a view too:
        # the stall is decided on the fine readings; the missing layers show where they show)
        still = ({cam for cam, reading in read.items() if reading < fine_limit}
                 | {cam for cam, r in usable.items()
                    if cam not in read and r.growth_pct is None and r.coarse_growth_pct is not None
                    and r.coarse_growth_pct < settings.min_growth_pct})
        band_gone = any((usable[cam].band_missing_pct or 0.0) >= 25.0
                        or (not top_closing and (usable[cam].missing_pct >= usable[cam].threshold / 2.0
                                                 or cam in stopped))
                        for cam in still)
        stalled = bool(growth) and float(np.median(growth)) < fine_limit and band_gone
        # A part rising at under half the expected rate while two views that see it slow each miss part of its
        # newest band has slowed, not been misread: strands piling on a stopped part lift the outline a little
        # but fill no band; a face the colour of the bed reads missing but its outline rises fully.
        # (a view misses part of the newest band, or, where the part stopped before the previous check and the
        # gap reaches below the band, half the threshold of the whole part, as for band_gone above)
        slowed_views = [r for cam, r in measured.items()
                        if read[cam] < 50.0 and ((r.band_missing_pct or 0.0) >= 15.0
                                                 or r.missing_pct >= r.threshold / 2.0 or cam in stopped)]
        stalled = stalled or (not top_closing and len(growth) >= 2 and float(np.median(growth)) < 50.0
                              and len(slowed_views) >= 2)
        # A part that stopped under a nest of strands (spaghetti) reads no missing material: the pile fills its
        # outline. But its newest band, in the part's colours, is then a mesh of strands over the bed or the bed
        # itself: less than half covered by the part's material, in a view whose band read solid before (a face
        # in the bed's colour reads bare at every check) and that saw no rise or could not measure one. Not where
        # a top surface closes (a smooth top skin may look like the bed).
        bare_band = [r for r in usable.values()
                     if (r.growth_pct is None or r.growth_pct < fine_limit)
                     and r.band_part_coverage is not None and r.band_part_coverage < NEST_MAX_COVERAGE
                     and band_coverage_before.get(r.camera, 0.0) >= SOLID_MIN_COVERAGE]
        stalled = stalled or (not top_closing and bool(growth)
                              and float(np.median(growth)) < fine_limit and bool(bare_band))
        return stalled, bare_band

    measured = {cam: r for cam, r in usable.items() if r.growth_pct is not None and r.growth_pct >= SANK_BELOW_PCT}
    growth = [r.growth_pct for r in measured.values()]
    # A stop is a change: a view whose own readings at its previous checks read the part rising (``held_rise_before``,
    # held_rise) needs no missing material to corroborate a one-check reading of no rise either. Strands piled on a
    # stopped part fill its outline (nothing reads missing), while a top the camera cannot tell from what lies behind
    # it never reads a rise at two checks running. Not while a view reads the part rising as expected (fine, over its
    # span or coarse): a stop shows in every view, and with nothing missing nothing else stands against that view (a top
    # misread at one check reads 0 in one view and twice the rise in another, then rises again).
    # Nor while a view's one-check reading still reads some rise: only where every one reads a stall (a view reading
    # -8 % beside one reading 29 % over a face it misses all along is a resized frame's pixel step, not a stop).
    unanimous = all(r.growth_pct < fine_limit for r in measured.values())
    rose_before = set() if not unanimous or a_view_reads_the_full_rise(usable) else {
        cam for cam in measured if held_a_rise(held_rise_before, cam)}
    # Where fewer views are usable than a stop with nothing missing needs (a one-camera rig: stopped_views_needed),
    # no second view outvotes one reading's pixel step, so the stopped view shows the stop itself (stop_witnessed: a
    # trace missing, or its band's top read lowered), as views_read_a_stop asks below (seed 30 ``007_normal`` and seed
    # 34 ``003_normal``: one camera, 0 % after readings of 100 %, nothing missing, then 200 %: the top read one check
    # late)
    if len(usable) < STOPPED_VIEWS:
        rose_before = {cam for cam in rose_before if stop_witnessed(usable[cam], usable)}
    stalled, bare_band = stall_rules({cam: r.growth_pct for cam, r in measured.items()}, rose_before)
    # One view's fine reading of no rise is no median where the other views read the rise to the pixel (a part seen
    # small) and with them the part visibly rises, or read over their spans more rise than a stop leaves: that view's
    # top is a face it cannot tell from what lies behind it
    if stalled and len(measured) < 2 and (visibly_rising(usable) or rising_over_spans(usable)):
        stalled, bare_band = False, []
    growth_since = "since the previous check"
    # Where one check's rise is too small for any reading in a view (2-3 px: a part seen small, checks a few
    # layers apart), its reading over more checks (``ShapeResult.span_growth_pct``, as fine, but from an older
    # look) stands in for the same rules: a stall persists, so it is read, once the span lies after the stop.
    # (in addition to the one-check readings, never instead: a span reaching back before a stop reads part of
    # the rise, where a one-check reading already reads none)
    spanned = {cam: r.span_growth_pct for cam, r in usable.items()
               if r.growth_pct is None and r.span_growth_pct is not None and r.span_growth_pct >= SANK_BELOW_PCT}
    if spanned and not stalled:
        with_span = {**{cam: r.growth_pct for cam, r in measured.items()}, **spanned}
        # A gap a few pixels deep hides in the outline's tolerance, so a view whose span reading is the first
        # to see the part slow misses nothing yet; its own readings at its previous checks (``held_rise_before``:
        # fine, else over the span, else coarse, held by the reading before it: held_rise) corroborate it instead
        # when they read the part rising: a stop is a change, while a top the camera cannot tell from what lies
        # behind it never reads a rise, or reads one at one check and none at the next (pixel-step noise).
        stopped = {cam for cam in spanned if held_a_rise(held_rise_before, cam)}
        stalled, bare_band = stall_rules(with_span, stopped)
        if stalled:
            growth = list(with_span.values())
            growth_since = "over the last checks"
    # Where no camera resolves the rise (4-6 px per check: a part seen small, checks a few layers apart) the
    # coarse readings (``ShapeResult.coarse_growth_pct``, to the pixel, +-25 %) stand in, each from a view that
    # read the part rising (50 %) at its previous check (``rise_before``: a view that never sees the top rise, a
    # face in the bed's colour, reads 0 at every check), and corroborated by material gone missing since that
    # check in a view reading no rise (``missing_before``: a face the colour of the bed misses the same at every
    # check). A stop is a change: the part rose, now it does not, and its newest layers are missing.
    # A stop falls between two checks: at the first check after it the newest layers may be too thin to miss
    # (a stop late in the interval), and at the next one the view's previous reading is the stop itself. So a
    # view that read the part rising at an earlier check and no rise (or no reading: the model's outline did
    # not rise in it) at every check since (``missing_at_rise``: its missing material at that check,
    # CameraState.rise_missing, missing_since_rise) counts as well, its missing material measured against that
    # check: the part rose, then stopped, and its newest layers went missing since.
    limit = fine_limit if stalled else settings.min_growth_pct
    rise_before, missing_before = rise_before or {}, missing_before or {}
    missing_at_rise = missing_at_rise or {}
    rose = {cam: (missing_at_rise[cam] if cam in missing_at_rise else missing_before.get(cam))
            for cam in usable
            if cam in missing_at_rise or (rise_before.get(cam) or 0.0) >= COARSE_ROSE_BEFORE_PCT}
    coarse = {cam: usable[cam].coarse_growth_pct for cam in rose
              if usable[cam].coarse_growth_pct is not None and usable[cam].coarse_growth_pct >= SANK_BELOW_PCT}
    coarse_stalled = (not growth and not top_closing and bool(coarse)
                      and float(np.median(list(coarse.values()))) < settings.min_growth_pct
                      and any(coarse[cam] < settings.min_growth_pct and rose[cam] is not None
                              and usable[cam].missing_pct - rose[cam] >= usable[cam].threshold / 2.0
                              for cam in coarse))
    if coarse_stalled:
        growth, limit = list(coarse.values()), settings.min_growth_pct
    stalled = stalled or coarse_stalled
    # Views that each held a rise over their last readings (``held_rise_before``) and read none now, STOPPED_VIEWS of
    # them, stalled with little missing yet (a stop late in the interval leaves the newest layers too thin to miss
    # half the threshold): a stop is a change, and views that see it at the same check are no pixel step of one view
    # (a top a view cannot resolve reads 0-200 % by turns). Each view's reading is its finest (fine, else over the
    # span, else coarse), and their median must read no rise too; a trace of the newest layers must be missing in
    # one of them (STOPPED_MIN_MISSING_PCT): two views misread a black top on a black bed under JPEG's blocks as
    # still, with nothing missing (the default set's layer_shift_05 at quality 35). Where one view is usable (a
    # one-camera rig) it is every view: nothing outvotes it, and the trace stands against its pixel step. A band whose
    # top reads lowered (bed where it should stand) stands in for the trace while no view reads the full rise
    # (stop_witnessed).
    readings = finest_readings(usable)
    stopped_views = [usable[cam] for cam, reading in readings.items()
                     if reading < settings.min_growth_pct and held_a_rise(held_rise_before, cam)]
    if not stalled and not top_closing and views_read_a_stop(usable, readings, stopped_views, settings,
                                                             lambda r: stop_witnessed(r, usable)):
        stalled, growth = True, list(readings.values())
    if not stalled and not top_closing and first_rise_reading and stopped_at_the_first_reading(
            usable, readings, settings, missing_before=missing_before):
        stalled, growth = True, list(readings.values())
    return Stall(stalled, growth, growth_since, bare_band, limit)


def stopped_at_the_first_reading(usable: Mapping[str, ShapeResult], readings: Mapping[str, float],
                                 settings: DetectionSettings, *, missing_before: Mapping[str, float]) -> bool:
    """Whether a stop under way since before the print's first reading of the rise shows at that reading (part_stalled,
    ``first_rise_reading``): STOPPED_VIEWS views (every usable view where fewer are usable: stopped_views_needed), not
    relit, read no rise (their finest readings, ``readings``: finest_readings), the median of every view's reading is
    none either, no view reads the full rise (FULL_RISE_PCT), and one of the stopped views misses
    FIRST_STOP_MIN_MISSING_PCT more of the part than at its previous check (``missing_before``: a view not usable
    there shows nothing gone since) or reads its band's top lowered (layer_shift.band_reads_lowered: bed where the
    newest layers' top should stand, as stop_witnessed).

    A part that stopped before the first check (a runout, a tangle from the first layers) was already short there, and
    the first check cannot tell that from the calibration error: its outline is placed on the short part, and from
    then on no view ever reads a rise, so none holds one (held_a_rise) for the stall rules above. The model says the
    part rose by a whole interval since; two views reading none at once, with the newest layers' absence showing as
    material missing in one of them, is that stop. A top the camera cannot tell from the bed reads no rise too, but
    misses nothing there, or only in one view at a time; and an outline anchored off the part (a top view over a
    black part's shadow and brim) misses as much or more at every check from the first on: the stop's layers go
    missing since the previous check."""
    stopped = [r for cam, r in usable.items()
               if cam in readings and readings[cam] < settings.min_growth_pct and not r.relit]

    def witnessed(r: ShapeResult) -> bool:   # (missing_before: a view not usable there shows nothing gone since)
        gone = r.camera in missing_before and r.missing_pct - missing_before[r.camera] >= FIRST_STOP_MIN_MISSING_PCT
        return gone or band_reads_lowered(r.band_shift)

    return not a_view_reads_the_full_rise(usable) and views_read_a_stop(usable, readings, stopped, settings, witnessed)


def views_read_a_stop(usable: Mapping[str, ShapeResult], readings: Mapping[str, float], stopped: Sequence[ShapeResult],
                      settings: DetectionSettings, witnessed: Callable[[ShapeResult], bool]) -> bool:
    """Whether the views reading no rise (``stopped``) are as many as a stop needs (stopped_views_needed), the median
    of every view's finest reading (``readings``) reads none too, and one of them shows the stop (``witnessed``): the
    part_stalled rules for views that held a rise (stop_witnessed) and at the print's first reading
    (stopped_at_the_first_reading)."""
    return (bool(readings) and len(stopped) >= stopped_views_needed(len(usable))
            and float(np.median(list(readings.values()))) < settings.min_growth_pct
            and any(witnessed(r) for r in stopped))


def stop_witnessed(result: ShapeResult, usable: Mapping[str, ShapeResult]) -> bool:
    """Whether a view that held a rise and reads none now shows the stop itself (part_stalled's stopped views): a trace
    of the part or of its newest band missing (STOPPED_MIN_MISSING_PCT), or its band's top read lowered
    (layer_shift.band_reads_lowered; not on a relit view) while no usable view reads the part rising as expected
    (FULL_RISE_PCT). The newest layers of a stop late in the interval, or of a filament in the bed's colour, are too
    thin or too camouflaged to read missing, but the band's top shows bed where it should stand; a top the camera
    cannot resolve reads no such move. A view reading the full rise stands against a top read lower, not against
    material gone (a black tower on a black bed, sharpened: one view read its top 17 px low, another 200 %)."""
    return (result.missing_pct >= STOPPED_MIN_MISSING_PCT
            or (result.band_missing_pct or 0.0) >= 2.0 * STOPPED_MIN_MISSING_PCT
            or (not result.relit and band_reads_lowered(result.band_shift)
                and not a_view_reads_the_full_rise(usable)))


#: decide's ``layer_shift`` when the caller read none: read it from the views (an explicit None is "no shift read")
READ_FROM_THE_VIEWS: Any = object()


def decide(shape: Mapping[str, ShapeResult], size: Mapping[str, dict], settings: DetectionSettings,
           unreadable: Mapping[str, str] | Sequence[str] = (), *,
           layer_shift: LayerShift | None = READ_FROM_THE_VIEWS, top_closing: bool = False,
           pairs: Sequence[Sequence[str]] = (),
           extra_before: Mapping[str, float] | None = None,
           band_coverage_before: Mapping[str, float] | None = None,
           rise_before: Mapping[str, float | None] | None = None,
           missing_before: Mapping[str, float] | None = None,
           missing_at_rise: Mapping[str, float] | None = None,
           band_texture_before: Mapping[str, float] | None = None,
           held_rise_before: Mapping[str, float] | None = None,
           missing_while_rising: Mapping[str, tuple[float, float | None]] | None = None,
           first_rise_reading: bool = False,
           most_missing_before: Mapping[str, float] | None = None) -> tuple[str, list[str]]:
    """The combined decision rule -> (verdict, reasons).

    * A camera counts only when it gave a frame and its background still matches the bed
      (``usable``); dead or disturbed cameras are reported, never a cause for a pause.
    * fail when at least half of the usable cameras (and at least ``min_failing_cameras``) fail
      their shape check (Eq. 4.1 with tolerance over its threshold, or the newest band over the
      band threshold), or when one camera fails decisively (missing AND extra material, or the whole
      part found elsewhere: the part moved; extra material four times the threshold); extra material
      alone that appeared at once (``extra_before``: each camera's extra at its previous check) in one
      camera of a stereo pair (``pairs``) whose partner passes and sees none does not count
      (:func:`unseen_by_partner`), nor does extra material that every other usable view not relit passes without seeing
      any of (not decisive with the newest band within its threshold, or decisive with three times as much extra as
      missing material while this view and another read the part rising since their previous check, fine or to the
      pixel: :func:`unseen_by_the_other_views`);
      views read against a relit background (``ShapeResult.relit``) count only
      alongside a failing view that was not (in no share of views, nor for loose material or a layer shift),
    * while the part visibly grows (median growth >= 50 %, a reading of ``RISE_OVERSHOOT_PCT`` or more counting as
      none: no part rises faster than its model, its top jumped in the picture), a camera failing on missing material
      alone does not count (a face the colour of what lies behind it looks missing); where fewer than two views
      read the rise finely, the readings to the pixel stand in (:func:`readings_of_the_rise`), for missing material
      the view already missed at a check that passed (``most_missing_before``: :func:`missed_as_much_before`); nor
      does missing material alone from no more than half of the usable cameras not relit unless the part stalled,
      nor from a camera's first look at the part (``ShapeResult.first_look``: the growth test needs a second one), nor
      where, as a group, it is not the background (``ShapeResult.background_missing_pct``: a face of nearly
      the bed's colour), nor from a view that missed as much while it saw the part rise (``missing_while_rising``:
      :func:`standing_offset`);
    * or when the part stopped growing (corroborated by missing material in at least one view:
      25 % of the newest band, or half the threshold overall, in a view that saw no rise, finely or, where it
      reads the rise only to the pixel, coarsely): the median over
      cameras of the observed rise of the part's upper outline since the previous check (readings below
      -15 %, a sunk outline, left out) is below ``min_growth_pct`` of the expected rise (not where one view
      reads it finely and, with the other views' readings to the pixel, the part visibly rises); or, unless a
      top surface closes, when two or more cameras measured growth, its median is under 50 % and two views
      that saw under 50 % each miss 15 % of the newest band or half the threshold overall (strands piling on
      a stopped part lift the outline a little but fill no band; a part that stopped before the previous check
      misses more below its band); or, unless a top surface closes, when the median is under
      ``min_growth_pct`` and a view that saw no rise (or could not measure one) shows its newest band less
      than half covered by the part's colours where its band read solid (80 %) at an earlier check
      (``ShapeResult.band_part_coverage``; ``band_coverage_before``: each camera's highest reading at its
      earlier checks; core/nest.py: a nest of strands over a stopped part); or, where no camera measured
      growth and no top surface closes, when the median of the coarse readings (``coarse_growth_pct``) of the
      views that read a rise of 50 % at their previous check (``rise_before``) is under ``min_growth_pct`` and a
      view reading under it misses half the threshold more of the part than at its previous check
      (``missing_before``); a view that read such a rise at an earlier check and no rise (or no reading) at
      every check since (``missing_at_rise``: its missing material at that check; :func:`missing_since_rise`)
      counts too, measured against that check; where a view gives no one-check reading, its reading over the last
      checks (``ShapeResult.span_growth_pct``) stands in for the fine rules, and a view whose own readings before
      (``held_rise_before``: fine, else over the span, else coarse, at its previous check; CheckRunner passes it
      only where the view's reading before that read a rise too, the lower of the two: :func:`held_rise`) were a
      rise of ``COARSE_ROSE_BEFORE_PCT`` needs no missing material to corroborate it (nor does a view's one-check
      reading, while every one-check reading reads a stall and no view the full rise: a stop is a change, while
      strands piled on a stopped part fill its outline); nor do ``STOPPED_VIEWS`` such views that read no rise now
      (every usable view where fewer are usable: :func:`stopped_views_needed`; each its finest reading: fine, else
      over the span, else coarse), where the median of every view's finest
      reading reads none either, need more than a trace (``STOPPED_MIN_MISSING_PCT`` of the part, or twice that of
      the newest band, in one of them, or its band's top read lowered while no view reads the full rise:
      :func:`stop_witnessed`); nor, at the print's first reading of the rise (``first_rise_reading``: no earlier
      check gave any view one, so none held a rise), do as many views that read none, where the median reads none,
      no view the full rise, and one of them misses ``FIRST_STOP_MIN_MISSING_PCT`` more of the part than at its
      previous check or reads its band's top lowered (:func:`stopped_at_the_first_reading`: a stop before the first
      check), not where a top surface closes,
      or when a pair's size check reports an error over ``size_threshold_pct`` (a pair that
      abstains reports no ``error_pct`` and never fails);
    * or when two views (not relit) read their outline sunk by half a check's rise or more and one of them misses four
      times its threshold of the part (:func:`knocked_over`: a part knocked over or off its place, lying where no
      view reads it as extra material);
    * or when the cameras together confirm that the newest layers sit sideways on the older ones
      (``layer_shift``: :func:`layer_shift_of`, computed here when not given; see
      :func:`core.layer_shift.confirms_layer_shift`);
    * or when loose material (spaghetti) appeared around the part since the previous check: material new
      since then, where the model has none, attached to the part and over 2 mm beyond its outline
      (``ShapeResult.new_outside``), at least 6 mm^2 in two usable views, or 30 mm^2 when only one camera
      is usable, or 6 mm^2 counting blobs in the bed-marks zone in cameras on two different sides, or
      in one view while the part's outline rose under half the expected height (median of two or more views,
      or the only usable camera's own reading, where too few views read it finely each view's coarse reading
      standing in: :func:`rise_for_loose_material`; not where a top surface closes)
      (:func:`core.tangle.loose_material`);
    * or when, with the part's outline rising under half the expected height (the same figure, or where no view
      reads the rise at one check their readings over a span of checks, :func:`rise_over_spans`; not where a top
      surface closes), a view's newest band looks 1.5 times as textured as at its checks before
      (``ShapeResult.band_texture``; ``band_texture_before``: the smoothest of each camera's readings at its last
      ``TEXTURE_MEMORY_CHECKS`` checks, not a first look; :func:`core.nest.textured_views`), or twice as textured
      (TEXTURE_JUMP_STRONG) with the part rising under 80 % (PART_SLOWED_SOMEWHAT_PCT): strands piled over a part
      that slowed, or the bed where it should be; where only one of several views reads the rise (and read it rise
      at its previous check), twice as textured with that view's reading under half (:func:`lone_rise_reading`,
      :func:`core.nest.texture_jump_for_lone_reading`);
      or, not where a top surface closes, when a view that held a rise (``held_rise_before``) and reads none now (its
      finest reading) shows its band twice as textured, while the median of every view's finest reading is under
      80 % (:func:`stopped_and_textured`: its own stop is the second witness where no median of one-check readings
      exists);
    * unknown when no camera and no pair gave usable evidence; ok otherwise.
    """
    if layer_shift is READ_FROM_THE_VIEWS:
        # (only where the caller gave none: a re-decision that set some views' readings aside may have read none, and
        # reading them again here would bring those back)
        layer_shift = layer_shift_of(shape)
    if not isinstance(unreadable, Mapping):
        unreadable = {cam: "no frame (camera unavailable)" for cam in unreadable}
    reasons: list[str] = [f"{cam}: {why}: no verdict from this camera" for cam, why in unreadable.items()]
    usable = {cam: r for cam, r in shape.items() if r.usable}
    for cam, r in shape.items():
        if not r.usable:
            reasons.extend(r.reasons)
    failing = [r for r in usable.values() if not r.passed]
    stall = part_stalled(usable, settings, top_closing=top_closing, band_coverage_before=band_coverage_before,
                         rise_before=rise_before, missing_before=missing_before, missing_at_rise=missing_at_rise,
                         held_rise_before=held_rise_before, first_rise_reading=first_rise_reading)
    stalled, growth, growth_since, bare_band = stall.stalled, stall.growth, stall.since, stall.bare_band
    stall_limit = stall.limit if stall.limit is not None else settings.min_growth_pct
    size_fail, size_usable = [], 0
    for key, entry in size.items():
        error = entry.get("error_pct") if isinstance(entry, Mapping) else None
        if error is None or entry.get("abstained"):
            continue
        size_usable += 1
        limit = float(entry.get("threshold_pct", settings.size_threshold_pct))
        if error > limit:
            size_fail.append(f"{key}: size differs from the model by {error:.1f}% (limit {limit:g}%)")
    if not usable and not size_usable:
        return "unknown", reasons or ["no usable camera at this check"]
    # One camera seeing "material missing" or "extra material" may be fooled (a face the colour of
    # the background, a reflection); a failure of the part is seen from most sides. So plain shape
    # failures must come from at least half of the usable cameras (and ``min_failing_cameras``);
    # a decisive signature (the part displaced, the newest layers offset) suffices from one camera.
    # (a view read against a relit background only corroborates: no share of views counts it, here or below)
    plain_views = sum(not r.relit for r in usable.values())
    needed = max(settings.min_failing_cameras, math.ceil(plain_views / 2))
    decisive = [r for r in failing if r.decisive]
    missing_only = [r for r in failing
                    if not r.decisive and 0 < r.missing_pct and r.extra_pct * 2.0 <= r.missing_pct]
    # A camera's first look cannot tell a face the colour of what lies behind it from a part that printed
    # less than the model says: one frame shows both as missing material. The next check can (the growth
    # test), so there missing material alone waits for it.
    waiting = {r.camera for r in missing_only if r.first_look}
    # Nor does missing material that, as a group, is not the background: a face of nearly its colour (filament
    # in the bed's colour) passes for it pixel by pixel, but not as a group (``background_missing_pct``)
    waiting |= {r.camera for r in missing_only if r.background_missing_pct is not None
                and r.background_missing_pct + r.extra_pct <= r.threshold
                and (r.band_error_pct is None or r.background_band_missing_pct is None
                     or r.background_band_missing_pct + (r.band_error_pct - (r.band_missing_pct or 0.0))
                     <= r.band_threshold)}
    # Nor does missing material a view already read at a check where it saw the part rise (a standing offset: a
    # face it cannot tell from what lies behind it, as the "visibly grows" rule below says), when no more of the
    # part and of its newest band is missing now: a stop leaves the newest layers missing on top of it
    waiting |= {r.camera for r in missing_only if standing_offset(r, (missing_while_rising or {}).get(r.camera))}
    failing = [r for r in failing if r.camera not in waiting]
    missing_only = [r for r in missing_only if r.camera not in waiting]
    if missing_only and not stalled and 2 * len(missing_only) <= plain_views:
        # "Missing" alone, from no more than half of the cameras, while the part has not stopped growing:
        # faces the colour of what lies behind them (dark on dark, grey on grey) look exactly like this,
        # a runout does not (it stalls the growth, and the part's top is gone from most views).
        failing = [r for r in failing if r not in missing_only]
    # (here every reading counts: a sinking outline is evidence against growth, e.g. a part knocked over; and a reading
    # over the model's rise is none: a part standing up where it tipped over jumps in the picture, cross-check seed 43
    # ``033_detach``. The stall rule's own "visibly rising" keeps such readings: a top read a check late after a 0,
    # counted as none there, stalled seed 38 ``005_normal``, a normal print)
    if visibly_rising_finely(usable, steadily=True):
        # The part's outline rises as the model says: "material missing" without any extra material
        # is then a face the camera cannot tell from what lies behind it, not a runout.
        failing = [r for r in failing if r.decisive or r.extra_pct * 2.0 > r.missing_pct]
    elif visibly_rising(usable, steadily=True):
        # ... so it does where fewer than two views read the rise finely and the readings to the pixel of a part seen
        # small stand in (readings_of_the_rise: +-25 %), for missing material the view already read at an earlier
        # check (a face it cannot tell from what lies behind it, there since its first look; a part that tipped over
        # goes missing at once while its outline's top may still read a rise)
        failing = [r for r in failing if r.decisive or r.extra_pct * 2.0 > r.missing_pct
                   or not missed_as_much_before(r, most_missing_before)]
    # Extra material alone that appeared at once in one camera of a stereo pair whose partner, looking from
    # nearly the same side, sees none at all (and passes) is not standing there: a hair of stringing (18 %
    # "extra" in one view of a pair, 0 in the other; docs/detection-shadows.md). Material new since the
    # previous check is the tangle rule's to judge (two views). Extra material that built up check by check
    # (a layer shift along the pair's line of sight) still counts; so does a decisive view (a detached part
    # is sometimes seen by one camera of a pair only), and a pair with one usable camera is a single view.
    extra_before = extra_before or {}
    failing = [r for r in failing if not unseen_by_partner(r, usable, pairs, extra_before.get(r.camera))]
    # ... nor does extra material that no other view sees in any amount while they all pass (not decisive, its newest
    # band fitting; or decisive, mostly extra, while it and another view read the part rising): material on the bed
    # shows in a second view; the failing view's own outline or background frame does not
    unseen = {r.camera for r in failing if unseen_by_the_other_views(r, usable)}
    failing = [r for r in failing if r.camera not in unseen]
    decisive = [r for r in decisive if r.camera not in unseen]
    # A view read against a relit background (``ShapeResult.relit``: a reflection swept across a glossy bed) guesses
    # the light under the part from the bed around it; where the reflection crosses the part it reads lit bed as
    # material (extra where there is none, or a missing top as there). It corroborates a view that was not
    # relit, never fails a print alone.
    if all(r.relit for r in [*failing, *decisive]):
        failing, decisive = [], []
    shape_fail = bool(decisive) or len(failing) >= needed
    fail_reasons = [reason for r in (failing if shape_fail else []) for reason in r.reasons]
    if stalled:
        fail_reasons.append(f"the part has not grown as expected {growth_since}: "
                            f"{_rounded_under(float(np.median(growth)), stall_limit)}% of the expected rise seen "
                            f"(median of {len(growth)} camera(s), limit {stall_limit:g}%): "
                            f"runout, clog or a stopped print?")
        if not top_closing:
            fail_reasons.extend(f"{r.camera}: the newest layers show the part's colours over "
                                f"{100.0 * r.band_part_coverage:.0f}% of their area "
                                f"({100.0 * band_coverage_before[r.camera]:.0f}% at an earlier check): "
                                f"strands or bare bed where the part should be" for r in bare_band)
    if layer_shift is not None and confirms_layer_shift(layer_shift, settings.layer_shift_mm):
        fail_reasons.append(describe_layer_shift(layer_shift))
        shape_fail = True
    fallen = None if shape_fail or stalled else knocked_over(usable)
    if fallen is not None:
        fail_reasons.append(fallen)
        shape_fail = True
    # The rise the loose-material rule weighs: the median of the fine readings (two or more views, or a one-camera
    # rig's own); where they are too few (a part seen small: a rise of 4-6 px per check), each view's fine reading
    # or else its coarse one (``coarse_growth_pct``, +-25 %) stands in (rise_for_loose_material)
    rise_pct = None if top_closing else rise_for_loose_material(usable, growth)
    # ... and where no view reads one check's rise at all, their readings over a span of checks (rise_over_spans: a
    # span reaching back before a stop reads more of the rise than the last check saw)
    loose_rise, loose_over = (None, "") if top_closing else rise_or_over_spans(usable, rise_pct)
    # (a relit view's material beside the part may be lit bed: no loose material from it)
    seen_loose = {cam: r for cam, r in usable.items() if not r.relit}
    tangle = loose_material({cam: None if r.new_outside is None else r.new_outside.area_mm2
                             for cam, r in seen_loose.items()},
                            with_foot={cam: r.new_outside.with_foot_mm2 for cam, r in seen_loose.items()
                                       if r.new_outside is not None},
                            directions={cam: r.new_outside.direction for cam, r in seen_loose.items()
                                        if r.new_outside is not None},
                            # (not where a top surface closes: a ridge's or apex's last layers are too thin
                            # for the outline to show them rise, so a normal part reads 0 % there)
                            rise_pct=loose_rise, rise_over=loose_over,
                            surrounding={cam for cam, r in seen_loose.items()
                                         if r.new_outside is not None and r.new_outside.surrounds_part},
                            spreading={cam for cam, r in seen_loose.items()
                                       if r.new_outside is not None and r.new_outside.spreads_around},
                            pairs=[pair for pair in pairs if all(cam in seen_loose for cam in pair)])
    if tangle is not None:
        fail_reasons.append(tangle)
        shape_fail = True
    # A part that slowed while a view's newest band turned textured (``band_texture_before``: each camera's
    # band texture at its previous check): strands piled over it fill its outline and lift it a little, but each
    # strand brings its own highlight and shadow where the printed face was smooth (the bed seen where the part
    # should be is textured too); the slow rise is the second witness, as for one view of loose material
    # (a rise of 50-79 % only with a band changed markedly: a coarse rise reading is +-25 %)
    # (where no view reads the rise at one check, their readings over a span of checks stand in, or the one view's
    # that does: rise_for_texture)
    texture_rise, jump, over = (None, None, "") if top_closing else rise_for_texture(usable, rise_pct, rise_before)
    textured = ({} if jump is None else
                textured_views({cam: r.band_texture for cam, r in usable.items()}, band_texture_before or {}, jump))
    if textured:
        fail_reasons.extend(f"{cam}: the newest layers look {ratio:.1f} times as textured as at the checks before "
                            f"while the part rose {texture_rise:.0f}% of the expected height{over}: strands piled "
                            f"over the part, or the bed where it should be?" for cam, ratio in sorted(textured.items()))
        shape_fail = True
    # ... and a view that read the part rise at its checks before and none now whose band turned so textured: its own
    # stop is the second witness where too few views read the rise since the previous check (stopped_and_textured)
    stopped_textured = ({} if textured or top_closing else
                        stopped_and_textured(usable, settings, held_rise_before=held_rise_before,
                                             band_texture_before=band_texture_before))
    if stopped_textured:
        fail_reasons.extend(f"{cam}: the newest layers look {ratio:.1f} times as textured as at the checks before "
                            f"where the part stopped rising in this view: strands piled over the part, or the bed "
                            f"where it should be?" for cam, ratio in sorted(stopped_textured.items()))
        shape_fail = True
    if shape_fail or size_fail or stalled:
        return "fail", fail_reasons + size_fail + reasons
    return "ok", reasons


#: A view that never saw more than this share of the part at a passing look (ShapeResult.outline_coverage: the
#: expected part its material covered where the outline was laid) reads no layer shift, and fails only with views that
#: saw the part whole (:func:`without_views_never_seen_whole`). Measured (helper al, cross-check seeds 30 and 31,
#: 8d1777c): of 18 anchors left by looks covering under 0.6 of the part, 7 lay over 8 px off it and 22 % of the later
#: checks before an onset failed in that view; of 243 left by looks covering 0.8 or more, 6 and 0.5 %; none between 0.6
#: and 0.8.
SEEN_WHOLE_SHARE = 2.0 / 3.0


def without_views_never_seen_whole(decision: Mapping[str, Any],
                                   seen_share: Mapping[str, float | None],
                                   history: Sequence[tuple[bool, Mapping[str, BandShift]]] = (),
                                   placed_at: Mapping[str, Sequence[tuple[int, int]]] | None = None,
                                   anchor_share: Mapping[str, float | None] | None = None
                                   ) -> tuple[str, list[str]] | None:
    """A failing check (``decision``: the arguments :func:`decide` failed it with) decided again with the evidence of
    the views that never saw the part whole set aside: ``("ok", reasons)`` when the check then passes, else None (the
    verdict stands).

    ``seen_share``: {camera: the most of the part its passing looks' material covered (0-1), None: no passing look}.
    A view never saw the part whole where that is under SEEN_WHOLE_SHARE and this is not its first look (that has no
    history: the first check of a part that detached at once). Set aside: such a view's layer-shift reading always
    (the newest band is read against the outline the view laid), and its shape failure where a witness passes: a usable
    view, not relit, that saw the part whole. What a stop or spaghetti is read from stays: its readings of the part's
    rise, of its band's top lowered (a stop's witness), of missing and loose material. ``history``, ``placed_at``:
    :func:`layer_shift_of`'s, for the readings kept.

    ``anchor_share``: {camera: the share of the part the passing look that laid its anchor covered, None: no anchor}.
    A view whose anchor a look covering under SEEN_WHOLE_SHARE laid reads no layer shift either, however much of the
    part its later looks saw, where the shift shows to no camera but such views: a held anchor moves a pixel at a
    time, so the outline stays where that look put it, and the newest band is read against that outline
    (SEEN_WHOLE_SHARE's measurement, al's, is of exactly those anchors). A camera whose outline a whole look laid,
    agreeing on the same bed move, reads it against an outline of its own (cross-check seed 30 `031_layer_shift`: s0,
    s1 and s3 confirm 2.2 mm together at check 4, s3 anchored by a look covering 0.48 at check 0 and 0.95-0.99 later).

    A view whose faces are the colour of the bed or the backdrop separates only some of them, and the overlap lays
    the outline where it takes those in: on the part's dark side or its cast shadow, 5-26 px off the part
    (cross-check seeds 30-33, ``benchmarks/outline_residual.py``). Held there, the view reads the part beside its
    outline as missing or extra material, a displaced band or a layer shift, alone, for the rest of the print. A
    view that saw the part whole laid its outline where the part is, and a failure of the part shows there too."""
    shape: Mapping[str, ShapeResult] = decision["shape"]

    def saw_whole(name: str) -> bool:
        return (seen_share.get(name) or 0.0) >= SEEN_WHOLE_SHARE

    def anchored_by_a_partial_look(name: str) -> bool:
        share = (anchor_share or {}).get(name)
        return share is not None and share < SEEN_WHOLE_SHARE

    partial = [name for name, r in shape.items() if r.usable and not r.first_look and not saw_whole(name)]
    witnesses = [name for name, r in shape.items() if r.usable and r.passed and not r.relit and saw_whole(name)]
    # (a layer-shift reading is the newest band against the outline the view laid: a partial view's never counts, nor
    # that of a view whose outline a partial look anchored; a partial view's shape failure waits for a view that saw
    # the part whole and passes)
    failing = [name for name in partial if not shape[name].passed] if witnesses else []
    shifts = band_shifts_of(shape)
    partly_anchored = [name for name, r in shape.items()
                       if r.usable and not r.first_look and name not in partial and anchored_by_a_partial_look(name)]
    # (... where the shift rests on such views alone: cameras agreeing on one rigid move each read it against an
    # outline of their own, whose errors are their own)
    shown_to = set(getattr(decision.get("layer_shift"), "cameras", None) or ())
    if not shown_to or not shown_to <= {*partial, *partly_anchored}:
        partly_anchored = []
    reading_shift = [name for name in [*partial, *partly_anchored] if name in shifts]
    if not failing and not reading_shift:
        return None
    # (what a stop or spaghetti is read from stays: the view's rise, its band's top lowered, its missing and loose
    # material; a part a view sees partly still stops)
    kept = {name: replace(r, passed=True, decisive=False, moved_px=None, reasons=[]) if name in failing else r
            for name, r in shape.items()}
    layer_shift = layer_shift_of(kept, history, {name: s for name, s in shifts.items() if name not in reading_shift},
                                 placed_at=placed_at)
    again, again_reasons = decide(**{**decision, "shape": kept, "layer_shift": layer_shift})
    if again != "ok":
        return None
    never = f"never saw the part whole (under {SEEN_WHOLE_SHARE:.0%} of it at any passing look)"
    notes = [f"{', '.join(failing)}: {never}: failing while {', '.join(witnesses)} did and "
             f"pass{'es' if len(witnesses) == 1 else ''}"] if failing else []
    shift_only = [name for name in reading_shift if name not in failing and name in partial]
    if shift_only and decision.get("layer_shift") is not None:
        notes.append(f"{', '.join(shift_only)}: {never}: no layer-shift reading")
    anchored_only = [name for name in reading_shift if name in partly_anchored]
    # (said only where their reading failed the check: the shift shows to them alone, so it was theirs)
    if anchored_only and decision.get("layer_shift") is not None \
            and confirms_layer_shift(decision["layer_shift"], decision["settings"].layer_shift_mm):
        notes.append(f"{', '.join(anchored_only)}: its outline was anchored by a look that saw under "
                     f"{SEEN_WHOLE_SHARE:.0%} of the part: no layer-shift reading")
    return "ok", [*again_reasons, *notes]
