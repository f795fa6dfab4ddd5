"""Calibration boards: definitions, detection, and printable images.

Board frame (mm): origin at the outer top-left corner of the square grid as
printed, x to the right along the page, y down the page, z into the paper.
Square (i, j) (column i, row j) is black when ``i + j`` is even, so the
top-left square is black; OpenCV's ChArUco boards follow the same rule.

A board is ``kind`` ``"chessboard"`` (plain squares; every inner corner must
be visible) or ``"charuco"`` (ArUco markers in the white squares; partial
views work and each corner has an identity). ``cols`` x ``rows`` count
*squares*; OpenCV's "9 x 6 chessboard" counts inner corners and is
``Board("chessboard", 10, 7, square_mm)`` here.
"""
from __future__ import annotations

import json
import re
import struct
import zlib
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import cv2
import numpy as np

from .errors import CalibrationError

#: Paper sizes (width, height) in mm, portrait.
PAPER_MM = {"a4": (210.0, 297.0), "letter": (215.9, 279.4), "a3": (297.0, 420.0)}
#: Distance from the paper's left and front edges to the grid on generated pages, mm
#: (household printers leave 3-6 mm blank).
PAGE_MARGIN_MM = 10.0
#: Room above the grid for the scale bar and caption, mm.
CAPTION_MM = 16.0

_SUBPIX_CRITERIA = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 40, 0.001)


@dataclass(frozen=True)
class Board:
    """A planar calibration target.

    Attributes
    ----------
    kind : str
        ``"chessboard"`` or ``"charuco"``.
    cols, rows : int
        Number of squares across and down.
    square_mm : float
        Side of one square, as printed (measure it!).
    marker_mm : float
        ChArUco only: side of the ArUco markers.
    dictionary : str
        ChArUco only: name of the ``cv2.aruco`` predefined dictionary.
    margin_mm : float
        White border between the paper edge and the grid in the generated image
        (used by placement ``front-left``).
    """

    kind: str = "charuco"
    cols: int = 7
    rows: int = 5
    square_mm: float = 25.0
    marker_mm: float = 18.0
    dictionary: str = "DICT_4X4_50"
    margin_mm: float = 0.0

    def __post_init__(self) -> None:
        if self.kind not in ("chessboard", "charuco"):
            raise CalibrationError(f"board: kind must be 'chessboard' or 'charuco', got {self.kind!r}")
        if int(self.cols) < 3 or int(self.rows) < 3:
            raise CalibrationError(f"board: needs at least 3 x 3 squares, got {self.cols} x {self.rows}")
        if not self.square_mm > 0:
            raise CalibrationError(f"board: square size must be positive, got {self.square_mm}")
        if self.kind == "charuco":
            if not 0 < self.marker_mm < self.square_mm:
                raise CalibrationError(
                    f"board: marker size must be between 0 and the square size, got {self.marker_mm}")
            if not hasattr(cv2.aruco, self.dictionary):
                raise CalibrationError(f"board: unknown ArUco dictionary {self.dictionary!r}")
            if self._dictionary().bytesList.shape[0] < (self.cols * self.rows) // 2:
                raise CalibrationError(f"board: dictionary {self.dictionary} has too few markers for "
                                       f"{self.cols} x {self.rows} squares")

    # ----------------------------------------------------------- geometry
    @property
    def inner_corners(self) -> tuple[int, int]:
        """(columns, rows) of inner corners, the ``patternSize`` OpenCV's chessboard finder takes."""
        return (self.cols - 1, self.rows - 1)

    @property
    def n_corners(self) -> int:
        return (self.cols - 1) * (self.rows - 1)

    @property
    def size_mm(self) -> tuple[float, float]:
        """(width, height) of the square grid in mm."""
        return (self.cols * self.square_mm, self.rows * self.square_mm)

    @property
    def symmetric(self) -> bool:
        """True when a half turn maps the pattern onto itself (orientation is then ambiguous)."""
        return self.kind == "chessboard" and (self.cols + self.rows) % 2 == 0

    def corner_points(self) -> np.ndarray:
        """(n_corners, 3) inner corners in the board frame (mm), row-major from the top-left; the
        index of a corner is its ChArUco id."""
        nx, ny = self.inner_corners
        i, j = np.meshgrid(np.arange(1, nx + 1), np.arange(1, ny + 1))
        return np.column_stack([i.ravel(), j.ravel(), np.zeros(i.size)]) * self.square_mm

    def describe(self) -> str:
        extra = f", markers {self.marker_mm:g} mm {self.dictionary}" if self.kind == "charuco" else ""
        return f"{self.kind} {self.cols} x {self.rows} squares of {self.square_mm:g} mm{extra}"

    # ------------------------------------------------------------ OpenCV
    def _dictionary(self):
        return cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, self.dictionary))

    def _charuco(self):
        return cv2.aruco.CharucoBoard((self.cols, self.rows), float(self.square_mm),
                                      float(self.marker_mm), self._dictionary())

    # ------------------------------------------------------------ storage
    def to_dict(self) -> dict:
        data = asdict(self)
        if self.kind == "chessboard":
            data.pop("marker_mm")
            data.pop("dictionary")
        return data

    @classmethod
    def from_dict(cls, data: Any, where: str = "board") -> "Board":
        if not isinstance(data, dict):
            raise CalibrationError(f"{where}: expected a board object")
        known = {k: data[k] for k in ("kind", "cols", "rows", "square_mm", "marker_mm", "dictionary",
                                      "margin_mm") if k in data}
        try:
            for key in ("cols", "rows"):
                if key in known:
                    known[key] = int(known[key])
            for key in ("square_mm", "marker_mm", "margin_mm"):
                if key in known:
                    known[key] = float(known[key])
            return cls(**known)
        except (TypeError, ValueError) as exc:
            raise CalibrationError(f"{where}: {exc}") from None

    def save(self, path: str | Path) -> None:
        Path(path).write_text(json.dumps({"format": "printwatch-board/1", **self.to_dict()}, indent=2))

    @classmethod
    def parse(cls, spec: str) -> "Board":
        """A board from a JSON file written by ``printwatch board`` or a spec
        ``KIND:COLSxROWS:SQUARE_MM[:MARKER_MM]`` (squares, not inner corners), e.g. ``charuco:7x5:25:18``."""
        path = Path(spec)
        if path.suffix.lower() == ".json" or path.is_file():
            try:
                data = json.loads(path.read_text())
            except FileNotFoundError:
                raise CalibrationError(f"{spec}: no such board file") from None
            except (OSError, ValueError) as exc:
                raise CalibrationError(f"{spec}: not a readable board JSON file ({exc})") from None
            return cls.from_dict(data, where=spec)
        match = re.fullmatch(r"(chessboard|charuco):(\d+)x(\d+):([\d.]+)(?::([\d.]+))?", spec.strip().lower())
        if not match:
            raise CalibrationError(
                f"board {spec!r}: expected a board .json file or KIND:COLSxROWS:SQUARE_MM[:MARKER_MM], "
                "e.g. charuco:7x5:25:18 or chessboard:10x7:25 (squares, not inner corners)")
        kind, cols, rows, square, marker = match.groups()
        square = float(square)
        kwargs: dict[str, Any] = {"kind": kind, "cols": int(cols), "rows": int(rows), "square_mm": square}
        if kind == "charuco":
            kwargs["marker_mm"] = float(marker) if marker else round(square * 0.72, 3)
        return cls(**kwargs)


# --------------------------------------------------------------- detection
@dataclass
class Detection:
    """Board corners found in one image.

    Attributes
    ----------
    ids : (n,) int
        Corner indices into :meth:`Board.corner_points`.
    pixels : (n, 2) float
        Sub-pixel image positions of those corners.
    image_size : (width, height)
    """

    ids: np.ndarray
    pixels: np.ndarray
    image_size: tuple[int, int]

    def __len__(self) -> int:
        return len(self.ids)

    def object_points(self, board: Board) -> np.ndarray:
        """(n, 3) board-frame coordinates (mm) of the detected corners."""
        return board.corner_points()[self.ids]


def to_gray(image: np.ndarray) -> np.ndarray:
    """(H, W) uint8 grey copy of a grey, BGR or BGRA frame."""
    image = np.asarray(image)
    if image.ndim == 3 and image.shape[2] == 4:
        image = cv2.cvtColor(image, cv2.COLOR_BGRA2GRAY)
    elif image.ndim == 3 and image.shape[2] == 3:
        image = cv2.cvtColor(image, cv2.COLOR_BGR2GRAY)
    elif image.ndim == 3 and image.shape[2] == 1:
        image = image[:, :, 0]
    if image.dtype != np.uint8:
        image = cv2.normalize(image, None, 0, 255, cv2.NORM_MINMAX).astype(np.uint8)
    return image


def detect_board(image: np.ndarray, board: Board, *, min_corners: int = 6) -> Detection | None:
    """Find the board's inner corners in a frame; None when the board is not found.

    Chessboard corners are put in a canonical order (see :func:`_canonical_chessboard_order`)
    so the same physical corner has the same id in every view, which stereo
    calibration and the bed pose need.
    """
    gray = to_gray(image)
    size = (gray.shape[1], gray.shape[0])
    if board.kind == "charuco":
        corners, ids, markers, _ = _charuco_detector(board, 4).detectBoard(gray)
        if ids is None or len(ids) < board.n_corners:
            # Small, far markers: their bits are read more reliably on an enlarged frame.
            big = cv2.resize(gray, None, fx=2, fy=2, interpolation=cv2.INTER_CUBIC)
            corners2, ids2, markers2, _ = _charuco_detector(board, 8).detectBoard(big)
            if ids2 is not None and (ids is None or len(ids2) > len(ids)):
                corners, ids = (corners2 + 0.5) / 2.0 - 0.5, ids2
                markers = [(m + 0.5) / 2.0 - 0.5 for m in markers2]
        if ids is None or len(ids) < min_corners:
            return None
        pixels = _refine_charuco_corners(gray, corners.reshape(-1, 2), markers)
        return Detection(ids.ravel().astype(int), pixels, size)
    corners = _find_chessboard(gray, board.inner_corners)
    if corners is None:
        return None
    pixels = _canonical_chessboard_order(gray, corners, board)
    return Detection(np.arange(board.n_corners), pixels, size)


def _refine_charuco_corners(gray: np.ndarray, corners: np.ndarray, markers) -> np.ndarray:
    """(n, 2) corners refined by ``cornerSubPix`` with the largest window that stays clear of
    the markers (whose edges would pull the corner); corners too cramped keep OpenCV's estimate.

    detectBoard's own refinement leaves errors of 0.2-0.3 px even on sharp images.
    """
    corners = corners.astype(np.float64).copy()
    if not markers:
        return corners
    marker_pts = np.concatenate([np.asarray(m, dtype=np.float64).reshape(-1, 2) for m in markers])
    # Chebyshev distance from each corner to the nearest marker corner, less the blur of its edge.
    gap = np.abs(corners[:, None, :] - marker_pts[None]).max(axis=2).min(axis=1)
    half = np.floor(gap - 2.5).astype(int)
    for w in np.unique(np.clip(half, 0, 10)):
        if w < 2:
            continue
        pick = np.clip(half, 0, 10) == w
        refined = cv2.cornerSubPix(gray, corners[pick].astype(np.float32).reshape(-1, 1, 2), (int(w), int(w)),
                                   (-1, -1), _SUBPIX_CRITERIA).reshape(-1, 2)
        # Keep a refinement only when it stayed near the start (it can jump to a marker corner).
        moved = np.linalg.norm(refined - corners[pick], axis=1)
        corners[pick] = np.where((moved < 1.5)[:, None], refined, corners[pick])
    return corners


def _charuco_detector(board: Board, pixels_per_cell: int):
    params = cv2.aruco.DetectorParameters()
    # A board uses few of the dictionary's markers and ids off the board are ignored, so
    # accepting more bit errors costs little and reads small, blurred markers far away.
    params.errorCorrectionRate = 1.0
    params.perspectiveRemovePixelPerCell = pixels_per_cell
    return cv2.aruco.CharucoDetector(board._charuco(), cv2.aruco.CharucoParameters(), params)


def _find_chessboard(gray: np.ndarray, pattern: tuple[int, int]) -> np.ndarray | None:
    """(n, 2) corners in OpenCV's order, or None. Tries the classic finder (fast, precise with
    cornerSubPix) first, then the sector-based one, which copes better with blur and noise."""
    flags = cv2.CALIB_CB_ADAPTIVE_THRESH + cv2.CALIB_CB_NORMALIZE_IMAGE + cv2.CALIB_CB_FAST_CHECK
    found, corners = cv2.findChessboardCorners(gray, pattern, flags=flags)
    if found:
        win = _chessboard_subpix_window(corners.reshape(-1, 2), pattern)
        corners = cv2.cornerSubPix(gray, corners, (win, win), (-1, -1), _SUBPIX_CRITERIA)
        return corners.reshape(-1, 2).astype(np.float64)
    found, corners = cv2.findChessboardCornersSB(gray, pattern, flags=cv2.CALIB_CB_EXHAUSTIVE
                                                 + cv2.CALIB_CB_ACCURACY)
    if found:
        return corners.reshape(-1, 2).astype(np.float64)
    return None


def _chessboard_subpix_window(pixels: np.ndarray, pattern: tuple[int, int]) -> int:
    grid = pixels.reshape(pattern[1], pattern[0], 2)
    spacing = min(np.linalg.norm(np.diff(grid, axis=1), axis=2).min(),
                  np.linalg.norm(np.diff(grid, axis=0), axis=2).min())
    # Half-window must stay inside one square, or the refinement drifts to the next corner.
    return int(np.clip(spacing * 0.4, 2, 11))


def _canonical_chessboard_order(gray: np.ndarray, corners: np.ndarray, board: Board) -> np.ndarray:
    """Re-order (n, 2) chessboard corners so that id 0 is the corner next to the black outer square
    and the grid is seen from its printed side (board x to y turns clockwise in the image).

    OpenCV may return the grid from either end; a half turn is told apart by the colour of the
    outer corner square (possible when cols + rows is odd), a mirror by the image handedness.
    """
    nx, ny = board.inner_corners
    grid = corners.reshape(ny, nx, 2)
    if _handedness(grid) < 0:  # mirrored: x and y turn anticlockwise; flip the rows' direction
        grid = grid[:, ::-1]
        if nx == ny:
            grid = grid.transpose(1, 0, 2)[:, ::-1]
    if not board.symmetric and not _outer_square_is_dark(gray, grid):
        grid = grid[::-1, ::-1]
    return grid.reshape(-1, 2)


def _handedness(grid: np.ndarray) -> float:
    ex = grid[0, -1] - grid[0, 0]
    ey = grid[-1, 0] - grid[0, 0]
    return float(ex[0] * ey[1] - ex[1] * ey[0])


def _outer_square_is_dark(gray: np.ndarray, grid: np.ndarray) -> bool:
    """Is the square diagonally outside corner (0, 0) darker than its neighbour outside (0, 1)?"""
    c00, c01, c10 = grid[0, 0], grid[0, 1], grid[1, 0]
    step_x, step_y = c01 - c00, c10 - c00
    outer = c00 - 0.5 * step_x - 0.5 * step_y  # centre of the outer corner square
    beside = c00 + 0.5 * step_x - 0.5 * step_y  # centre of the square to its right (other colour)
    return _sample(gray, outer) < _sample(gray, beside)


def _sample(gray: np.ndarray, point: np.ndarray, radius: int = 2) -> float:
    x = int(np.clip(round(point[0]), radius, gray.shape[1] - radius - 1))
    y = int(np.clip(round(point[1]), radius, gray.shape[0] - radius - 1))
    return float(gray[y - radius:y + radius + 1, x - radius:x + radius + 1].mean())


# ------------------------------------------------------- printable images
def render_board_image(board: Board, px_per_mm: float, *, margin_mm: float = 0.0) -> np.ndarray:
    """(H, W) uint8 image of the board pattern at ``px_per_mm``, with a white margin.

    The grid's outer top-left corner is at pixel ``margin_mm * px_per_mm`` (pixel-edge
    coordinates), so board-frame mm map to pixel edges by ``(x + margin) * px_per_mm``.
    """
    grid_w = int(round(board.cols * board.square_mm * px_per_mm))
    grid_h = int(round(board.rows * board.square_mm * px_per_mm))
    if board.kind == "charuco":
        grid = board._charuco().generateImage((grid_w, grid_h), marginSize=0, borderBits=1)
    else:
        xs = np.floor(np.arange(grid_w) / grid_w * board.cols).astype(int)
        ys = np.floor(np.arange(grid_h) / grid_h * board.rows).astype(int)
        grid = np.where((xs[None, :] + ys[:, None]) % 2 == 0, 0, 255).astype(np.uint8)
    margin = int(round(margin_mm * px_per_mm))
    return cv2.copyMakeBorder(grid, margin, margin, margin, margin, cv2.BORDER_CONSTANT, value=255)


def board_for_bed(bed_mm: tuple[float, float], *, kind: str = "charuco", paper: str = "a4",
                  cols: int | None = None, rows: int | None = None,
                  square_mm: float | None = None) -> Board:
    """The largest board of whole-millimetre squares that fits on the paper and on the bed.

    Bigger squares are seen with more pixels by a camera looking across the bed,
    which is what makes the bed pose precise; the board must still lie flat on
    the bed with room to spare.
    """
    bed_w, bed_d = (float(v) for v in bed_mm)
    if not (bed_w > 0 and bed_d > 0):
        raise CalibrationError(f"bed size must be positive, got {bed_w:g} x {bed_d:g} mm")
    # 7 x 5 for ChArUco; 8 x 5 for a chessboard, whose odd + even count fixes its orientation.
    cols = cols or (7 if kind == "charuco" else 8)
    rows = rows or 5
    if paper.lower() not in PAPER_MM:
        raise CalibrationError(f"paper {paper!r}: expected one of {', '.join(PAPER_MM)}")
    pw, ph = _landscape(paper)
    usable_w = min(pw - 2 * PAGE_MARGIN_MM, bed_w * 0.9)
    usable_h = min(ph - 2 * PAGE_MARGIN_MM - CAPTION_MM, bed_d * 0.9)
    fit = min(usable_w / cols, usable_h / rows)
    if square_mm is None:
        square_mm = float(np.floor(fit))
        if square_mm < 4:
            raise CalibrationError(f"bed {bed_w:g} x {bed_d:g} mm is too small for a {cols} x {rows} board")
    elif square_mm > fit + 1e-9:
        raise CalibrationError(f"a {cols} x {rows} board of {square_mm:g} mm squares does not fit on "
                               f"{paper} paper and a {bed_w:g} x {bed_d:g} mm bed (max {fit:.1f} mm)")
    marker = round(square_mm * 0.72, 1) if kind == "charuco" else 18.0
    return Board(kind=kind, cols=cols, rows=rows, square_mm=float(square_mm), marker_mm=marker,
                 margin_mm=PAGE_MARGIN_MM)


def _landscape(paper: str) -> tuple[float, float]:
    pw, ph = PAPER_MM[paper.lower()]
    return max(pw, ph), min(pw, ph)


def printable_page(board: Board, *, paper: str = "a4", dpi: int = 300) -> np.ndarray:
    """(H, W) uint8 landscape page: the grid ``board.margin_mm`` from the left and bottom
    edges (so the page can be pushed into the bed's front-left corner), a 100 mm scale
    bar and a caption above it."""
    pw, ph = _landscape(paper)
    px_per_mm = dpi / 25.4
    gw_mm, gh_mm = board.size_mm
    margin = board.margin_mm
    if gw_mm + margin > pw or gh_mm + margin > ph:
        raise CalibrationError(f"board {gw_mm:g} x {gh_mm:g} mm does not fit on {paper} paper")
    page = np.full((int(round(ph * px_per_mm)), int(round(pw * px_per_mm))), 255, np.uint8)
    grid = render_board_image(board, px_per_mm)
    x0 = int(round(margin * px_per_mm))
    y0 = int(round((ph - margin - gh_mm) * px_per_mm))
    page[y0:y0 + grid.shape[0], x0:x0 + grid.shape[1]] = grid[: page.shape[0] - y0, : page.shape[1] - x0]
    # A bar to check the printer did not scale the page ("fit to page" is the usual culprit).
    bar_len = min(100.0, gw_mm)
    bar_bottom = y0 - int(round(3 * px_per_mm))
    bar_top = bar_bottom - int(round(1.5 * px_per_mm))
    if bar_top > int(6 * px_per_mm):
        cv2.rectangle(page, (x0, bar_top), (x0 + int(round(bar_len * px_per_mm)) - 1, bar_bottom), 0, -1)
        lines = [f"PrintWatch {board.describe()}. This edge goes to the back of the bed.",
                 f"Bar = {bar_len:g} mm: print at 100 %; if bar or squares measure otherwise, give the real "
                 "square size."]
        scale = px_per_mm * 0.085
        for k, text in enumerate(lines):
            y = bar_top - int(round((2 + 4.5 * (len(lines) - 1 - k)) * px_per_mm))
            cv2.putText(page, text, (x0, y), cv2.FONT_HERSHEY_SIMPLEX, scale, 0,
                        max(1, int(px_per_mm * 0.1)), cv2.LINE_AA)
    return page


def write_png_with_dpi(path: str | Path, image: np.ndarray, dpi: int) -> None:
    """Write a PNG whose pHYs chunk carries ``dpi`` so print dialogs default to the true size."""
    ok, data = cv2.imencode(".png", image)
    if not ok:
        raise CalibrationError(f"{path}: could not encode the board image")
    data = data.tobytes()
    ppm = int(round(dpi / 0.0254))
    payload = b"pHYs" + struct.pack(">IIB", ppm, ppm, 1)
    chunk = struct.pack(">I", 9) + payload + struct.pack(">I", zlib.crc32(payload) & 0xFFFFFFFF)
    ihdr_end = 8 + 8 + 13 + 4  # signature, IHDR length+type, IHDR data, CRC
    try:
        Path(path).write_bytes(data[:ihdr_end] + chunk + data[ihdr_end:])
    except OSError as exc:
        raise CalibrationError(f"{path}: cannot write ({exc.strerror})") from None
