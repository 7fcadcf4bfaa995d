"""Calibration boards (targets for cameras): definitions, the ``--board`` spec string, object
points in a fixed order, and the printed design as an image (issue 14; docs/handeye.md, "Boards").

Spec strings (lengths need their unit, ``mm`` or ``m``; ``COLSxROWS`` is width x height, as
OpenCV's pattern sizes and image sizes are written)::

    checkerboard:9x6:25mm                         inner corners 9 across, 6 down; square 25 mm
    charuco:5x7:36.195mm:18.256mm:DICT_6X6_250    squares 5 across, 7 down; square, marker, dictionary
    charuco:5x7:36.195mm:18.256mm:DICT_6X6_250:legacy   OpenCV's pre-4.6 pattern (boards with an
                                                  even number of rows printed by old OpenCV)
    circles:10x10:25.4mm                          symmetric dot grid, 10 x 10 dots, 25.4 mm apart
    circles:10x10:25.4mm:modified                 the ROS-Industrial grid: one larger dot marks the origin

Object points [mm, z = 0 on the board], index order = the order of detections:

* ``checkerboard``: inner corner (c, r) at (c s, r s), index r * COLS + c; corner 0 is the one
  whose outer diagonal square is black (the board's top-left square is black). A board with
  COLS + ROWS even looks the same turned by 180 degrees: its order is then only defined up to that
  turn (use COLS + ROWS odd, e.g. 9x6, or ChArUco, for hand-eye).
* ``charuco``: chessboard corner id k (OpenCV's ids) at OpenCV's ``getChessboardCorners()[k]``:
  ((k mod (COLS-1)) + 1) s, (k div (COLS-1) + 1) s), origin at the board's outer top-left corner.
* ``circles``: dot (c, r) at (c s, r s), index r * COLS + c (OpenCV's ``findCirclesGrid`` order;
  a plain symmetric grid has the checkerboard's ambiguity).
* ``circles ... modified`` (ROS-Industrial ``ModifiedCircleGridTarget``): index r * COLS + c at
  (c s, (ROWS - 1 - r) s): the large dot is the origin, index (ROWS - 1) * COLS (start of the last
  row), +x runs along the last row, +y up to the first row, +z out of the printed face.

This module imports no cv2 except to draw ChArUco markers (:func:`board_image`).
"""

from __future__ import annotations
from ..errors import InputError

import re
from dataclasses import dataclass

import numpy as np

__all__ = ["Board", "BoardSpecError", "parse_board", "board_image", "ARUCO_DICTIONARIES"]

#: ArUco dictionaries by OpenCV name -> OpenCV's numeric id (as ROS-Industrial's ``dictionary:``).
ARUCO_DICTIONARIES = {
    f"DICT_{bits}X{bits}_{n}": 4 * (bits - 4) + i
    for bits in (4, 5, 6, 7) for i, n in enumerate((50, 100, 250, 1000))
}
KINDS = ("checkerboard", "charuco", "circles")
_LENGTH = re.compile(r"^\s*([0-9]*\.?[0-9]+(?:[eE][-+]?[0-9]+)?)\s*(mm|m)\s*$")
_SIZE = re.compile(r"^\s*(\d+)\s*[xX]\s*(\d+)\s*$")


class BoardSpecError(InputError):
    """A ``--board`` spec string (or board settings of a file) is not a valid board."""


@dataclass(frozen=True)
class Board:
    """A calibration board.

    kind: ``"checkerboard"`` | ``"charuco"`` | ``"circles"``; cols, rows: inner corners
    (checkerboard), squares (charuco) or dots (circles), across x down; pitch_mm: square side or
    dot spacing [mm]; marker_mm: ArUco marker side [mm] (charuco); dictionary: OpenCV name
    (charuco); modified: circles with one large origin dot; legacy: OpenCV's pre-4.6 ChArUco pattern.
    """

    kind: str
    cols: int
    rows: int
    pitch_mm: float
    marker_mm: float | None = None
    dictionary: str | None = None
    modified: bool = False
    legacy: bool = False

    def __post_init__(self):
        if self.kind not in KINDS:
            raise BoardSpecError(f"unknown board kind {self.kind!r}; expected one of {', '.join(KINDS)}")
        least = 2 if self.kind != "checkerboard" else 2
        if self.cols < least or self.rows < least:
            raise BoardSpecError(f"{self.kind} needs at least {least}x{least}, got {self.cols}x{self.rows}")
        if self.kind == "charuco" and (self.cols < 3 or self.rows < 3):
            raise BoardSpecError(f"charuco needs at least 3x3 squares, got {self.cols}x{self.rows}")
        if not (self.pitch_mm > 0 and np.isfinite(self.pitch_mm)):
            raise BoardSpecError(f"square/spacing must be a positive length, got {self.pitch_mm} mm")
        if self.kind == "charuco":
            if self.dictionary not in ARUCO_DICTIONARIES:
                raise BoardSpecError(f"unknown ArUco dictionary {self.dictionary!r}; expected one of "
                                     f"{', '.join(ARUCO_DICTIONARIES)}")
            if not (self.marker_mm and 0 < self.marker_mm < self.pitch_mm):
                raise BoardSpecError(f"charuco marker side must be positive and smaller than the square "
                                     f"({self.pitch_mm} mm), got {self.marker_mm} mm")
        if self.modified and self.kind != "circles":
            raise BoardSpecError("'modified' applies to circles boards only")

    # -- geometry -----------------------------------------------------------------------------

    @property
    def n_points(self) -> int:
        """Number of object points P."""
        if self.kind == "charuco":
            return (self.cols - 1) * (self.rows - 1)
        return self.cols * self.rows

    @property
    def grid(self) -> tuple[int, int]:
        """(columns, rows) of the object-point grid."""
        if self.kind == "charuco":
            return self.cols - 1, self.rows - 1
        return self.cols, self.rows

    def object_points(self) -> np.ndarray:
        """(P, 3) [mm] in the fixed order described in the module docstring."""
        gc, gr = self.grid
        c, r = np.meshgrid(np.arange(gc, dtype=float), np.arange(gr, dtype=float))
        c, r = c.ravel(), r.ravel()
        if self.kind == "charuco":
            x, y = (c + 1.0) * self.pitch_mm, (r + 1.0) * self.pitch_mm
        elif self.modified:
            x, y = c * self.pitch_mm, (gr - 1 - r) * self.pitch_mm
        else:
            x, y = c * self.pitch_mm, r * self.pitch_mm
        return np.stack([x, y, np.zeros_like(x)], axis=1)

    @property
    def front_z(self) -> int:
        """+1 if the board's z axis points out of the printed face (toward a camera that sees the
        pattern), -1 if into it (x right and y down on the print, as OpenCV's boards)."""
        return 1 if self.modified else -1

    @property
    def min_points(self) -> int:
        """Fewest detected points for an image to be used (a pose needs >= 4 non-collinear
        points; ChArUco corners are found in pieces, other boards all or nothing)."""
        return 6 if self.kind == "charuco" else self.n_points

    @property
    def spec(self) -> str:
        """The spec string this board parses from."""
        pitch = f"{self.pitch_mm:g}mm"
        if self.kind == "charuco":
            s = f"charuco:{self.cols}x{self.rows}:{pitch}:{self.marker_mm:g}mm:{self.dictionary}"
            return s + (":legacy" if self.legacy else "")
        s = f"{self.kind}:{self.cols}x{self.rows}:{pitch}"
        return s + (":modified" if self.modified else "")

    def to_dict(self) -> dict:
        return {"spec": self.spec, "kind": self.kind, "cols": self.cols, "rows": self.rows,
                "pitch_mm": self.pitch_mm, "marker_mm": self.marker_mm, "dictionary": self.dictionary,
                "modified": self.modified, "legacy": self.legacy, "n_points": self.n_points}


def _length_mm(text: str, what: str, spec: str) -> float:
    m = _LENGTH.match(text)
    if not m:
        raise BoardSpecError(f"board {spec!r}: {what} {text!r} is not a length with its unit (e.g. 25mm or 0.025m)")
    return float(m.group(1)) * (1000.0 if m.group(2) == "m" else 1.0)


def parse_board(spec: str) -> Board:
    """A :class:`Board` from a spec string (module docstring); :class:`BoardSpecError` naming
    the part that is wrong."""
    parts = [p.strip() for p in str(spec).split(":")]
    kind = parts[0].lower()
    usage = {"checkerboard": "checkerboard:COLSxROWS:SQUARE (inner corners), e.g. checkerboard:9x6:25mm",
             "charuco": "charuco:COLSxROWS:SQUARE:MARKER:DICT[:legacy] (squares), "
                        "e.g. charuco:5x7:36.195mm:18.256mm:DICT_6X6_250",
             "circles": "circles:COLSxROWS:SPACING[:modified] (dots), e.g. circles:10x10:25.4mm:modified"}
    if kind not in usage:
        raise BoardSpecError(f"board {spec!r}: unknown kind {parts[0]!r}; expected one of: " + "; ".join(usage.values()))
    n_fixed = {"checkerboard": 3, "charuco": 5, "circles": 3}[kind]
    flags = [p.lower() for p in parts[n_fixed:]]
    allowed = {"checkerboard": set(), "charuco": {"legacy"}, "circles": {"modified"}}[kind]
    if len(parts) < n_fixed or not set(flags) <= allowed:
        raise BoardSpecError(f"board {spec!r}: expected {usage[kind]}")
    size = _SIZE.match(parts[1])
    if not size:
        raise BoardSpecError(f"board {spec!r}: size {parts[1]!r} is not COLSxROWS (e.g. 9x6)")
    cols, rows = int(size.group(1)), int(size.group(2))
    pitch = _length_mm(parts[2], "square/spacing", spec)
    if kind == "charuco":
        marker = _length_mm(parts[3], "marker side", spec)
        dictionary = parts[4].upper()
        if dictionary.isdigit():
            by_id = {v: k for k, v in ARUCO_DICTIONARIES.items()}
            dictionary = by_id.get(int(dictionary), dictionary)
        return Board("charuco", cols, rows, pitch, marker, dictionary, legacy="legacy" in flags)
    return Board(kind, cols, rows, pitch, modified="modified" in flags)


# -- the printed design ---------------------------------------------------------------------------


def _aruco_board(board: Board):
    import cv2

    dictionary = cv2.aruco.getPredefinedDictionary(ARUCO_DICTIONARIES[board.dictionary])
    b = cv2.aruco.CharucoBoard((board.cols, board.rows), board.pitch_mm, board.marker_mm, dictionary)
    if board.legacy:
        b.setLegacyPattern(True)
    return b


def board_image(board: Board, mm_per_texel: float, margin_mm: float | None = None):
    """The printed board as a grey image (white 255, black 0) and its placement.

    Returns ``(image (H, W) uint8, affine (2, 3))`` where ``affine @ (x, y, 1)`` maps a board point
    [mm] (the object-point frame) to texel coordinates (column, row), texel centres at integers.
    ``mm_per_texel`` should divide the square/spacing (and the ChArUco marker offset) so that edges
    fall on texel boundaries. ``margin_mm``: white border around the pattern (default one pitch).
    """
    s = board.pitch_mm
    margin = s if margin_mm is None else float(margin_mm)
    t = float(mm_per_texel)
    if board.kind == "charuco":
        pattern_w, pattern_h = board.cols * s, board.rows * s
        x0, y0 = -margin, -margin  # pattern origin = outer top-left corner
    elif board.kind == "checkerboard":
        pattern_w, pattern_h = (board.cols + 1) * s, (board.rows + 1) * s
        x0, y0 = -s - margin, -s - margin
    else:
        pattern_w, pattern_h = (board.cols - 1) * s, (board.rows - 1) * s
        x0, y0 = -margin, -margin
    W = int(round((pattern_w + 2 * margin) / t))
    H = int(round((pattern_h + 2 * margin) / t))
    # board coordinates of texel centres (y of the object frame grows with the row, except modified)
    xs = x0 + (np.arange(W) + 0.5) * t
    ys = y0 + (np.arange(H) + 0.5) * t
    if board.kind == "checkerboard":
        i = np.floor((xs + s) / s).astype(int)
        j = np.floor((ys + s) / s).astype(int)
        inside_x = (i >= 0) & (i <= board.cols)
        inside_y = (j >= 0) & (j <= board.rows)
        black = ((i[None, :] + j[:, None]) % 2 == 0) & inside_x[None, :] & inside_y[:, None]
        img = np.where(black, 0, 255).astype(np.uint8)
    elif board.kind == "circles":
        gc, gr = board.grid
        ci = np.clip(np.rint(xs / s), 0, gc - 1)
        rj = np.clip(np.rint(ys / s), 0, gr - 1)
        dx = xs - ci * s
        dy = ys - rj * s
        d2 = dx[None, :] ** 2 + dy[:, None] ** 2
        radius = np.full((H, W), 0.25 * s)
        if board.modified:
            # the large dot at object (0, 0) = image row ROWS-1 (y grows downward in the picture
            # frame used here; the object frame's y = (ROWS-1) s - picture y)
            big = (ci[None, :] == 0) & (rj[:, None] == gr - 1)
            radius = np.where(big, 0.4 * s, radius)
        img = np.where(d2 <= radius ** 2, 0, 255).astype(np.uint8)
    else:
        px_per_square = s / t
        if abs(px_per_square - round(px_per_square)) > 1e-6:
            raise BoardSpecError(f"mm_per_texel {t} must divide the ChArUco square {s} mm")
        inner = _aruco_board(board).generateImage((board.cols * int(round(px_per_square)),
                                                   board.rows * int(round(px_per_square))), marginSize=0,
                                                  borderBits=1)
        m = int(round(margin / t))
        img = np.full((H, W), 255, np.uint8)
        img[m:m + inner.shape[0], m:m + inner.shape[1]] = inner
    # affine: board (x, y) -> texel (col, row); texel centre k at coordinate x0 + (k + 0.5) t
    if board.modified:
        # picture rows run down while the object y runs up: y_obj = (ROWS-1) s - y_picture
        top = (board.grid[1] - 1) * s
        affine = np.array([[1 / t, 0.0, -x0 / t - 0.5], [0.0, -1 / t, (top - y0) / t - 0.5]])
    else:
        affine = np.array([[1 / t, 0.0, -x0 / t - 0.5], [0.0, 1 / t, -y0 / t - 0.5]])
    return img, affine
