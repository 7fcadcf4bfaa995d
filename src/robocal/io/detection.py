"""Board detection on real pixels through OpenCV (issue 14; docs/handeye.md, "Detection").

:func:`detect_board` finds a :class:`~robocal.io.boards.Board` in one grey image and returns a
:class:`Detection`: image points (P, 2) [px, OpenCV's pixel-centre convention] in the board's
object-point order with NaN rows for points not found, the image size, and a skip reason when
too few points were found (the image is then not used). :func:`detect_images` does this for a
list of files, reporting progress.

Sub-pixel refinement: checkerboard corners by ``cornerSubPix`` (11 x 11 window; on rendered images
with known truth 0.045 px RMS against 0.087-0.090 px for ``findChessboardCornersSB`` (docs/handeye.md), which is
used when the classic detector finds no board); ChArUco corners are refined by OpenCV's
``CharucoDetector`` itself and, as an alternative set (``refined_points``), again by
``cornerSubPix`` with a window kept clear of the markers; circle centres are blob centroids
(sub-pixel by construction). A checkerboard that is not found is looked for with one inner corner
fewer or more per side, and the message names the count found ("did you give squares?").

ChArUco markers: after the first ArUco pass, the markers the board layout predicts but the pass
missed are searched for again (OpenCV's ``refineDetectedMarkers``, ``CharucoParameters.
tryRefineMarkers``; each one is still decoded against the dictionary). On the ROS-Industrial
ChArUco set this takes the corners found from 290 to 382 in 16 images (4 -> 24 in ``2.png``,
8 -> 24 in ``15.png``), all fitting a per-image PnP to 0.24-1.05 px RMS (docs/datasets.md).

Orientation: the checkerboard's first corner is the one whose outer diagonal square is black
(boards with COLS + ROWS odd; see :mod:`.boards`); the modified circle grid is ordered from its
large dot, measured here from the blob sizes (OpenCV's ``findCirclesGrid`` does not know it).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .boards import ARUCO_DICTIONARIES, Board
from .images import ImageFileError, read_image_gray

__all__ = ["Detection", "detect_board", "detect_images", "homography_error_px", "read_image_gray", "BlobSettings", "ImageFileError"]


@dataclass(frozen=True)
class BlobSettings:
    """Dot detector settings for circle grids (OpenCV ``SimpleBlobDetector`` names; the
    ROS-Industrial ``circle_detector_params`` map onto them). Areas in px^2."""

    min_threshold: float = 20.0
    max_threshold: float = 220.0
    n_thresholds: int = 20
    min_repeatability: int = 3
    min_dist_between_blobs: float = 5.0
    min_area: float = 25.0
    max_area: float = 5000.0
    min_convexity: float | None = 0.95
    min_circularity: float | None = None
    min_inertia_ratio: float | None = None
    dark_dots: bool = True


@dataclass(frozen=True)
class Detection:
    """One image's detection.

    name: the image's file name (or a label); image_points: (P, 2) [px], NaN where a point was not
    found; image_size: (width, height) [px]; skip_reason: None when the image is usable, else why not;
    refined_points: (P, 2) [px] the same points refined again by ``cornerSubPix`` (ChArUco only,
    else None): ``camera calibrate`` keeps the set the model fits better.
    """

    name: str
    image_points: np.ndarray
    image_size: tuple
    skip_reason: str | None = None
    refined_points: np.ndarray | None = None

    @property
    def n_found(self) -> int:
        return int(np.count_nonzero(np.isfinite(self.image_points[:, 0])))

    @property
    def used(self) -> bool:
        return self.skip_reason is None


def _empty(board: Board) -> np.ndarray:
    return np.full((board.n_points, 2), np.nan)


# -- checkerboard ---------------------------------------------------------------------------------


def _sample(gray: np.ndarray, xy: np.ndarray) -> float:
    x, y = int(round(xy[0])), int(round(xy[1]))
    h, w = gray.shape
    if not (0 <= x < w and 0 <= y < h):
        return np.nan
    return float(np.mean(gray[max(y - 1, 0):y + 2, max(x - 1, 0):x + 2]))


def _checkerboard(gray, board: Board):
    import cv2

    size = (board.cols, board.rows)
    flags = cv2.CALIB_CB_ADAPTIVE_THRESH | cv2.CALIB_CB_NORMALIZE_IMAGE
    found, corners = cv2.findChessboardCorners(gray, size, flags=flags)
    if found:
        corners = cv2.cornerSubPix(gray, corners.astype(np.float32), (5, 5), (-1, -1),
                                   (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 50, 1e-3))
    else:  # the sector-based detector finds boards the classic one misses (blur, low contrast)
        found, corners = cv2.findChessboardCornersSB(gray, size, flags=cv2.CALIB_CB_NORMALIZE_IMAGE
                                                     | cv2.CALIB_CB_ACCURACY)
    if not found:
        return _empty(board), _checkerboard_miss(gray, board)
    pts = corners.reshape(board.rows, board.cols, 2).astype(float)
    if (board.cols + board.rows) % 2 == 1:
        # the two squares diagonal to corner 0 are black by convention (the last corner's are white);
        # the two squares beside it have the other colour. Diagonal brighter than beside: turn by
        # 180 degrees. (Diagonal squares of a checkerboard share their colour: comparing the outer
        # with the inner diagonal square tells nothing.)
        p0 = pts[0, 0]
        ex, ey = 0.5 * (pts[0, 1] - p0), 0.5 * (pts[1, 0] - p0)
        diagonal = [_sample(gray, p0 - ex - ey), _sample(gray, p0 + ex + ey)]
        beside = [_sample(gray, p0 + ex - ey), _sample(gray, p0 - ex + ey)]
        if np.all(np.isfinite(diagonal + beside)) and np.mean(diagonal) > np.mean(beside):
            pts = pts[::-1, ::-1]
    return pts.reshape(-1, 2), None


def _checkerboard_miss(gray, board: Board) -> str:
    """Why a checkerboard was not found: with another count of inner corners in the image (one
    fewer or one more on both sides: squares given for inner corners, or the other way) the message
    says so; else that every inner corner must be visible."""
    import cv2

    expected = f"{board.cols} x {board.rows}"
    for dc, dr in ((-1, -1), (1, 1)):  # the sector-based detector: ~0.15 s per size on a 1280 x 1024 miss
        size = (board.cols + dc, board.rows + dr)
        if min(size) < 2:
            continue
        found, _ = cv2.findChessboardCornersSB(gray, size, flags=cv2.CALIB_CB_NORMALIZE_IMAGE)
        if found:
            hint = "did you give squares?" if dc < 0 or dr < 0 else "did you give inner corners minus one?"
            return (f"checkerboard not found: inner corners: {size[0]} x {size[1]} found / {expected} expected, "
                    f"{hint} (the spec counts inner corners: a board of 10 x 7 squares is checkerboard:9x6)")
    return f"checkerboard not found ({expected} inner corners expected, all must be visible)"


# -- ChArUco --------------------------------------------------------------------------------------


def _charuco(gray, board: Board):
    import cv2

    dictionary = cv2.aruco.getPredefinedDictionary(ARUCO_DICTIONARIES[board.dictionary])
    b = cv2.aruco.CharucoBoard((board.cols, board.rows), board.pitch_mm, board.marker_mm, dictionary)
    if board.legacy:
        b.setLegacyPattern(True)
    charuco_params = cv2.aruco.CharucoParameters()
    charuco_params.tryRefineMarkers = True  # look again for the markers the layout predicts
    detector = cv2.aruco.CharucoDetector(b, charuco_params, cv2.aruco.DetectorParameters())
    corners, ids, _marker_corners, marker_ids = detector.detectBoard(gray)
    pts = _empty(board)
    n_markers = 0 if marker_ids is None else len(marker_ids)
    if ids is None or len(ids) == 0:
        return pts, f"no ChArUco corners found ({n_markers} ArUco markers of {board.dictionary})"
    ids = np.asarray(ids).ravel()
    pts[ids] = np.asarray(corners, dtype=float).reshape(-1, 2)
    return pts, None


def _charuco_subpix(gray, board: Board, pts: np.ndarray) -> np.ndarray | None:
    """The ChArUco corners refined again by ``cornerSubPix`` on the image (half-window a fifth of the
    square's size in pixels, 2 to 5 px, so that it stays clear of the markers), or None with fewer
    than 2 corners. On rendered images (known truth) this takes the corner error from 0.060 to
    0.037 px RMS (docs/handeye.md, "Detection")."""
    import cv2

    ok = np.flatnonzero(np.isfinite(pts[:, 0]))
    if len(ok) < 2:
        return None
    X = board.object_points()[ok, :2]
    d_img = np.linalg.norm(pts[ok][:, None] - pts[ok][None], axis=2)
    d_obj = np.linalg.norm(X[:, None] - X[None], axis=2)
    near = np.isclose(d_obj, board.pitch_mm)
    if not near.any():
        return None
    square_px = float(np.median(d_img[near]))
    half = int(np.clip(round(0.2 * square_px), 2, 5))
    refined = cv2.cornerSubPix(gray, pts[ok].astype(np.float32).reshape(-1, 1, 2), (half, half), (-1, -1),
                               (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 50, 1e-4)).reshape(-1, 2)
    out = np.array(pts, dtype=float, copy=True)
    out[ok] = refined
    return out


# -- circle grids ---------------------------------------------------------------------------------


def _blob_detector(settings: BlobSettings):
    import cv2

    p = cv2.SimpleBlobDetector_Params()
    p.minThreshold = settings.min_threshold
    p.maxThreshold = settings.max_threshold
    p.thresholdStep = max((settings.max_threshold - settings.min_threshold) / max(settings.n_thresholds, 1), 1.0)
    p.minRepeatability = settings.min_repeatability
    p.minDistBetweenBlobs = settings.min_dist_between_blobs
    p.filterByColor = True
    p.blobColor = 0 if settings.dark_dots else 255
    p.filterByArea = True
    p.minArea, p.maxArea = settings.min_area, settings.max_area
    p.filterByConvexity = settings.min_convexity is not None
    if settings.min_convexity is not None:
        p.minConvexity = settings.min_convexity
    p.filterByCircularity = settings.min_circularity is not None
    if settings.min_circularity is not None:
        p.minCircularity = settings.min_circularity
    p.filterByInertia = settings.min_inertia_ratio is not None
    if settings.min_inertia_ratio is not None:
        p.minInertiaRatio = settings.min_inertia_ratio
    return cv2.SimpleBlobDetector_create(p)


def _grid_symmetries(grid: np.ndarray):
    """The 8 turns and mirrors of a (R, C, ...) array of points."""
    for g in (grid, np.swapaxes(grid, 0, 1)):
        for k in range(4):
            yield np.rot90(g, k, axes=(0, 1))


def _order_modified(centers: np.ndarray, sizes: np.ndarray, board: Board):
    """Reorder a detected (R, C) grid so that the large dot is at (ROWS-1, 0), +x runs along the
    last row and +y up the first column with the printed face toward the camera (module
    docstring of :mod:`.boards`). Returns (points (P, 2), None) or (None, reason)."""
    grid = np.concatenate([centers, sizes[..., None]], axis=-1)
    corner_sizes = [grid[0, 0, 2], grid[0, -1, 2], grid[-1, 0, 2], grid[-1, -1, 2]]
    median = float(np.median(sizes))
    ranked = np.sort(corner_sizes)
    if not (ranked[-1] > 1.3 * median and ranked[-1] > 1.2 * ranked[-2]):
        return None, (f"no larger orientation dot at a grid corner (corner dot sizes "
                      f"{', '.join(f'{s:.1f}' for s in corner_sizes)} px, median {median:.1f} px)")
    gc, gr = board.grid
    for g in _grid_symmetries(grid):
        if g.shape[:2] != (gr, gc) or g[-1, 0, 2] != ranked[-1]:
            continue
        origin = g[-1, 0, :2]
        along_x = g[-1, 1, :2] - origin
        along_y = g[-2, 0, :2] - origin
        # printed face toward the camera: x right and y up as seen, i.e. negative cross product in
        # image coordinates (whose y runs down)
        if along_x[0] * along_y[1] - along_x[1] * along_y[0] < 0:
            return g[..., :2].reshape(-1, 2), None
    return None, "modified circle grid: no ordering puts the large dot at the origin with the face toward the camera"


def _circles(gray, board: Board, settings: BlobSettings):
    import cv2

    detector = _blob_detector(settings)
    gc, gr = board.grid
    flags = cv2.CALIB_CB_SYMMETRIC_GRID | cv2.CALIB_CB_CLUSTERING
    found, centers = cv2.findCirclesGrid(gray, (gc, gr), flags=flags, blobDetector=detector)
    shape = (gr, gc)
    if not found and gc != gr:
        found, centers = cv2.findCirclesGrid(gray, (gr, gc), flags=flags, blobDetector=detector)
        shape = (gc, gr)
    if not found:
        return _empty(board), f"circle grid {gc}x{gr} not found (all dots must be visible)"
    centers = np.asarray(centers, dtype=float).reshape(*shape, 2)
    if shape != (gr, gc):
        centers = np.swapaxes(centers, 0, 1)
    if not board.modified:
        return centers.reshape(-1, 2), None
    keypoints = detector.detect(gray)
    if len(keypoints) == 0:
        return _empty(board), "no blobs for the dot sizes"
    kp = np.array([k.pt for k in keypoints])
    ks = np.array([k.size for k in keypoints])
    flat = centers.reshape(-1, 2)
    dist = np.linalg.norm(flat[:, None, :] - kp[None, :, :], axis=-1)
    nearest = dist.argmin(axis=1)
    if np.max(dist[np.arange(len(flat)), nearest]) > 1.0:
        return _empty(board), "dot sizes could not be matched to the grid's centres"
    sizes = ks[nearest].reshape(centers.shape[:2])
    pts, reason = _order_modified(centers, sizes, board)
    return (pts, None) if pts is not None else (_empty(board), reason)


# -- public ---------------------------------------------------------------------------------------


def detect_board(image, board: Board, *, name: str = "image", min_points: int | None = None,
                 blob_settings: BlobSettings | None = None) -> Detection:
    """Find ``board`` in ``image`` (grey (H, W) uint8 array, or a colour (H, W, 3) BGR array).

    ``min_points``: fewest points for the image to be used (default ``board.min_points``).
    """
    img = np.asarray(image)
    if img.ndim == 3:
        img = img.mean(axis=2)
    if img.dtype != np.uint8:
        img = np.clip(np.rint(img), 0, 255).astype(np.uint8)
    h, w = img.shape
    refined = None
    if board.kind == "checkerboard":
        pts, reason = _checkerboard(img, board)
    elif board.kind == "charuco":
        pts, reason = _charuco(img, board)
        refined = _charuco_subpix(img, board, pts) if reason is None else None
    else:
        pts, reason = _circles(img, board, blob_settings or BlobSettings())
    need = board.min_points if min_points is None else int(min_points)
    found = int(np.count_nonzero(np.isfinite(pts[:, 0])))
    if reason is None and found < need:
        reason = f"too few points: {found} of {board.n_points} found, need {need}"
    return Detection(name=name, image_points=np.ascontiguousarray(pts, dtype=float), image_size=(w, h),
                     skip_reason=reason, refined_points=refined)


def homography_error_px(image_points: np.ndarray, object_points: np.ndarray) -> float:
    """How well one plane-to-image homography explains a detection (as ROS-Industrial's
    ``homography_threshold`` check): the homography is fitted to every third detected point and
    the mean distance [px] of the other points from their mapped positions is returned (NaN with
    fewer than 6 points). A wrong correspondence or strong lens distortion makes it large."""
    import cv2

    ok = np.isfinite(image_points[:, 0])
    uv, xy = image_points[ok], object_points[ok, :2]
    if len(uv) < 6:
        return float("nan")
    fit = np.zeros(len(uv), bool)
    fit[::3] = True
    if fit.sum() < 4:
        fit[:4] = True
    H, _ = cv2.findHomography(xy[fit].astype(np.float64), uv[fit].astype(np.float64), 0)
    if H is None:
        return float("inf")
    mapped = cv2.perspectiveTransform(xy[~fit].reshape(-1, 1, 2).astype(np.float64), H).reshape(-1, 2)
    return float(np.mean(np.linalg.norm(mapped - uv[~fit], axis=1)))


def detect_images(paths, board: Board, *, min_points: int | None = None, blob_settings: BlobSettings | None = None,
                  homography_threshold: float | None = None, progress=None) -> list[Detection]:
    """:func:`detect_board` on every file of ``paths``; ``progress(i, n, text)`` after each image.
    With ``homography_threshold`` [px], an image whose :func:`homography_error_px` exceeds it is
    skipped with that reason."""
    paths = [Path(p) for p in paths]
    out = []
    X = board.object_points()
    for i, p in enumerate(paths, 1):
        det = detect_board(read_image_gray(p), board, name=p.name, min_points=min_points, blob_settings=blob_settings)
        if det.used and homography_threshold is not None:
            err = homography_error_px(det.image_points, X)
            if err > homography_threshold:
                det = Detection(det.name, det.image_points, det.image_size,
                                skip_reason=f"homography error {err:.2f} px above the threshold {homography_threshold:g} px "
                                "(a wrong detection or strong lens distortion)")
        out.append(det)
        if progress is not None:
            status = f"{det.n_found} points" if det.used else f"skipped: {det.skip_reason}"
            progress(i, len(paths), f"{p.name}: {status}")
    return out
