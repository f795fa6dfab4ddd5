"""Board definitions, printable pages and detection on exact board images."""
import struct
import zlib

import cv2
import numpy as np
import pytest

from octoprint_printwatch.core.boards import (PAPER_MM, Board, board_for_bed, detect_board, printable_page,
                                              render_board_image, write_png_with_dpi)
from octoprint_printwatch.core.errors import CalibrationError


@pytest.mark.parametrize("bed", [(120.0, 120.0), (220.0, 220.0), (235.0, 235.0), (350.0, 350.0)])
@pytest.mark.parametrize("kind", ["charuco", "chessboard"])
def test_board_for_bed_fits_paper_and_bed_and_is_not_symmetric(bed, kind):
    board = board_for_bed(bed, kind=kind)
    width, depth = board.size_mm
    assert width <= 0.9 * bed[0] and depth <= 0.9 * bed[1]
    paper_w, paper_h = max(PAPER_MM["a4"]), min(PAPER_MM["a4"])
    assert width + 2 * board.margin_mm <= paper_w and depth + 2 * board.margin_mm <= paper_h
    assert board.square_mm == int(board.square_mm) and board.square_mm >= 10
    assert not board.symmetric  # orientation on the bed must be unambiguous
    # A bigger bed never gets smaller squares.
    assert board_for_bed((bed[0] * 1.5, bed[1] * 1.5), kind=kind).square_mm >= board.square_mm


def test_board_for_bed_rejects_a_square_size_that_does_not_fit():
    with pytest.raises(CalibrationError, match="does not fit"):
        board_for_bed((220, 220), square_mm=40)


@pytest.mark.parametrize("spec,expected", [
    ("chessboard:10x7:25", Board("chessboard", 10, 7, 25.0)),
    ("charuco:7x5:28:20", Board("charuco", 7, 5, 28.0, 20.0)),
])
def test_board_spec_parsing(spec, expected):
    assert Board.parse(spec) == expected


@pytest.mark.parametrize("spec", ["chess:9x6:25", "charuco:7x5", "charuco:7x5:20:25", "chessboard:2x7:25"])
def test_bad_board_spec_gives_one_line_error(spec):
    with pytest.raises(CalibrationError) as info:
        Board.parse(spec)
    assert "\n" not in str(info.value)


def test_board_json_round_trip_and_bad_file(tmp_path):
    board = board_for_bed((220, 220))
    board.save(tmp_path / "b.json")
    assert Board.parse(str(tmp_path / "b.json")) == board
    (tmp_path / "bad.json").write_text("{not json")
    with pytest.raises(CalibrationError, match="bad.json"):
        Board.parse(str(tmp_path / "bad.json"))
    with pytest.raises(CalibrationError, match="missing.json"):
        Board.parse(str(tmp_path / "missing.json"))


@pytest.mark.parametrize("kind", ["charuco", "chessboard"])
def test_corners_are_found_exactly_where_the_board_image_puts_them(kind):
    board = Board(kind, 8 if kind == "chessboard" else 7, 5, 20.0, 14.4)
    px_per_mm = 3.0
    # A camera never gives perfectly sharp edges; a slight blur is what corner finders expect.
    image = cv2.GaussianBlur(render_board_image(board, px_per_mm, margin_mm=10), (0, 0), 0.8)
    found = detect_board(image, board)
    assert found is not None and len(found) == board.n_corners
    # Board mm -> pixel-centre coordinates of the image.
    expected = (board.corner_points()[found.ids, :2] + 10) * px_per_mm - 0.5
    assert np.abs(found.pixels - expected).max() < 0.1


def test_chessboard_ids_follow_the_board_when_the_image_is_turned_half_round():
    board = Board("chessboard", 8, 5, 20.0)
    image = render_board_image(board, 3.0, margin_mm=10)
    upright = detect_board(image, board)
    turned = detect_board(cv2.rotate(image, cv2.ROTATE_180), board)
    h, w = image.shape
    # Corner k in the turned image must be the same physical corner: (x, y) -> (w-1-x, h-1-y).
    mapped = np.column_stack([w - 1 - turned.pixels[:, 0], h - 1 - turned.pixels[:, 1]])
    assert np.abs(mapped - upright.pixels).max() < 0.2


def test_printable_page_has_true_scale_and_dpi(tmp_path):
    board = board_for_bed((220, 220))
    page = printable_page(board, paper="a4", dpi=200)
    assert page.shape == (round(210 * 200 / 25.4), round(297 * 200 / 25.4))
    path = tmp_path / "board.png"
    write_png_with_dpi(path, page, 200)
    data = path.read_bytes()
    at = data.index(b"pHYs")
    ppm_x, ppm_y, unit = struct.unpack(">IIB", data[at + 4:at + 13])
    assert unit == 1 and ppm_x == ppm_y == round(200 / 0.0254)
    assert struct.unpack(">I", data[at + 13:at + 17])[0] == zlib.crc32(data[at:at + 13]) & 0xFFFFFFFF
    image = cv2.imread(str(path), cv2.IMREAD_GRAYSCALE)
    found = detect_board(image, board)
    assert found is not None and len(found) == board.n_corners
    # Grid corner (0, H) sits margin_mm from the page's left and bottom edges.
    ppmm = 200 / 25.4
    obj = board.corner_points()[found.ids]
    x_mm = (found.pixels[:, 0] + 0.5) / ppmm - obj[:, 0]
    y_from_bottom = (page.shape[0] - found.pixels[:, 1] - 0.5) / ppmm - (board.size_mm[1] - obj[:, 1])
    assert np.allclose(x_mm, board.margin_mm, atol=0.2) and np.allclose(y_from_bottom, board.margin_mm, atol=0.2)
