"""``printwatch board``: a printable calibration board sized for your bed."""
from __future__ import annotations

import argparse
from pathlib import Path

from ..core.boards import PAPER_MM, board_for_bed, printable_page, write_png_with_dpi
from ..core.errors import CalibrationError


def parse_pair(text: str, what: str) -> tuple[float, float]:
    """``"220,220"`` or ``"220x220"`` -> (220.0, 220.0); CalibrationError naming ``what`` otherwise."""
    parts = text.replace("x", ",").replace("X", ",").split(",")
    try:
        values = tuple(float(p) for p in parts)
    except ValueError:
        values = ()
    if len(values) != 2 or not all(v > 0 for v in values):
        raise CalibrationError(f"{what} {text!r}: expected two positive numbers like 220,220")
    return values  # type: ignore[return-value]


def parse_grid(text: str) -> tuple[int, int]:
    try:
        cols, rows = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise CalibrationError(f"--squares {text!r}: expected COLSxROWS, e.g. 7x5") from None
    return cols, rows


def add_parser(subparsers):
    parser = subparsers.add_parser(
        "board", help="write a printable calibration board for your bed",
        description="Write a printable calibration board (PNG at the given DPI) and its description "
                    "(JSON, given to 'printwatch calibrate --board'). Squares are as large as the paper and "
                    "the bed allow.")
    parser.add_argument("--out", "-o", required=True, help="PNG file to write; the board JSON goes beside it")
    parser.add_argument("--bed", required=True, metavar="W,D", help="bed width and depth in mm, e.g. 220,220")
    parser.add_argument("--type", dest="kind", choices=("charuco", "chessboard"), default="charuco",
                        help="charuco (default: partial views allowed) or chessboard (most precise bed pose)")
    parser.add_argument("--paper", choices=sorted(PAPER_MM), default="a4")
    parser.add_argument("--squares", metavar="COLSxROWS", help="squares across and down (default 7x5; "
                        "8x5 for a chessboard)")
    parser.add_argument("--square-mm", type=float, help="square size in mm (default: largest that fits)")
    parser.add_argument("--dpi", type=int, default=300)
    return parser


def run(args: argparse.Namespace) -> int:
    bed = parse_pair(args.bed, "--bed")
    cols, rows = parse_grid(args.squares) if args.squares else (None, None)
    if not 72 <= args.dpi <= 1200:
        raise CalibrationError(f"--dpi {args.dpi}: expected 72 to 1200")
    board = board_for_bed(bed, kind=args.kind, paper=args.paper, cols=cols, rows=rows, square_mm=args.square_mm)
    page = printable_page(board, paper=args.paper, dpi=args.dpi)
    out = Path(args.out)
    if out.suffix.lower() != ".png":
        raise CalibrationError(f"{out}: the board image must be a .png file")
    write_png_with_dpi(out, page, args.dpi)
    board_json = out.with_suffix(".json")
    board.save(board_json)
    print(f"wrote {out} ({args.paper.upper()} landscape, {args.dpi} dpi) and {board_json}")
    print(f"board: {board.describe()}; grid {board.size_mm[0]:g} x {board.size_mm[1]:g} mm, "
          f"{board.margin_mm:g} mm from the page's left and bottom edges")
    print("print at 100 % (not 'fit to page'), check the scale bar, and glue or tape the page flat")
    return 0
