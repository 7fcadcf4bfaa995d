"""What ``robocal camera calibrate`` and ``robocal handeye solve`` share: detecting a board in a
list of images with progress, the per-image rows of the JSON, pose dicts with named units and
conventions, the ROS-style transform YAML, and the report's back-projection overlays."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...io.boards import Board
from ...io.detection import BlobSettings, detect_images
from ...io.images import read_image_gray
from ...transforms import quaternion_from_matrix, rotvec_from_matrix

__all__ = ["DetectedSet", "detect_set", "pose_dict", "image_rows", "ros_transform_yaml", "overlay_figures",
           "identifiability_lines", "POSE_CONVENTION", "backprojection"]

#: how every pose in the JSON outputs is written
POSE_CONVENTION = ("T_<frame>_<object>: the object's pose in the named frame; position_mm in millimetres; "
                   "rotation_vector_deg = rotation axis times angle in degrees; quaternion_xyzw Hamilton, "
                   "scalar last (as ROS); matrix 4x4 homogeneous [mm]")


@dataclass(frozen=True, eq=False)
class DetectedSet:
    """paths (N); names (N); image_points (N, P, 2) [px] NaN where not found; image_size (w, h);
    skip_reasons (N) None for usable images; board; refined_points (N, P, 2) [px] the
    ``cornerSubPix``-refined alternative (ChArUco) or None."""

    paths: tuple
    names: tuple
    image_points: np.ndarray
    image_size: tuple
    skip_reasons: tuple
    board: Board
    refined_points: np.ndarray | None = None

    @property
    def used(self) -> np.ndarray:
        return np.array([r is None for r in self.skip_reasons])

    def require(self, n: int, what: str) -> None:
        """``HandEyeError`` naming every skipped image when fewer than ``n`` images are usable."""
        from ...handeye import HandEyeError

        used = self.used
        if used.sum() < n:
            reasons = "; ".join(f"{name}: {r}" for name, r in zip(self.names, self.skip_reasons) if r)
            raise HandEyeError(f"{what} needs at least {n} images with the board found, got {int(used.sum())} of "
                               f"{len(used)}" + (f" ({reasons})" if reasons else ""))


def detect_set(paths, board: Board, *, blob_settings: BlobSettings | None = None, homography_threshold=None,
               progress=None) -> DetectedSet:
    """Detect ``board`` in every image; ``ValueError`` when the images differ in size."""
    dets = detect_images(paths, board, blob_settings=blob_settings, homography_threshold=homography_threshold,
                         progress=progress)
    sizes = {d.image_size for d in dets}
    if len(sizes) > 1:
        first = dets[0]
        other = next(d for d in dets if d.image_size != first.image_size)
        raise ValueError(f"images differ in size: {first.name} is {first.image_size[0]}x{first.image_size[1]} px, "
                         f"{other.name} is {other.image_size[0]}x{other.image_size[1]} px (one camera, one size)")
    refined = None
    if any(d.refined_points is not None for d in dets):
        refined = np.array([d.image_points if d.refined_points is None else d.refined_points for d in dets])
    return DetectedSet(paths=tuple(paths), names=tuple(d.name for d in dets),
                       image_points=np.array([d.image_points for d in dets]), image_size=dets[0].image_size,
                       skip_reasons=tuple(d.skip_reason for d in dets), board=board, refined_points=refined)


def pose_dict(T: np.ndarray, frame: str, sigma_position_mm=None, sigma_rotation_deg=None) -> dict:
    """A pose for the JSON outputs (:data:`POSE_CONVENTION`)."""
    T = np.asarray(T, dtype=float)
    q = quaternion_from_matrix(T[:3, :3])  # (w, x, y, z)
    out = {"frame": frame, "position_mm": [float(v) for v in T[:3, 3]],
           "rotation_vector_deg": [float(v) for v in np.degrees(rotvec_from_matrix(T[:3, :3]))],
           "quaternion_xyzw": [float(q[1]), float(q[2]), float(q[3]), float(q[0])],
           "matrix": [[float(v) for v in row] for row in T]}
    if sigma_position_mm is not None:
        out["sigma_position_mm"] = [float(v) for v in sigma_position_mm]
    if sigma_rotation_deg is not None:
        out["sigma_rotation_deg"] = [float(v) for v in sigma_rotation_deg]
    return out


def backprojection(camera, T_camera_target, target_points, image_points):
    """(projected (N, P, 2), residuals detected minus projected (N, P, 2)) [px], vectorised over images."""
    N, P = image_points.shape[:2]
    pts = np.einsum("nij,pj->npi", T_camera_target[:, :3, :3], target_points) + T_camera_target[:, None, :3, 3]
    projected = camera.project(pts.reshape(-1, 3)).pixels.reshape(N, P, 2)
    return projected, image_points - projected


def _rms(r) -> float | None:
    r = np.asarray(r, dtype=float).reshape(-1, 2)
    r = r[np.isfinite(r).all(axis=1)]
    return float(np.sqrt(np.mean(np.sum(r ** 2, axis=1)))) if len(r) else None


def image_rows(detected: DetectedSet, residuals_px=None, residuals_mm=None, extra_skips=None) -> list:
    """One row per image: name, used, skip_reason, n_points, rms_px, rms_mm (per corner, norm of the
    2-vector). ``residuals_*`` (N, P, 2) for all images, NaN where not used; ``extra_skips`` {index:
    reason} from the solver."""
    rows = []
    for i, name in enumerate(detected.names):
        reason = detected.skip_reasons[i] or (extra_skips or {}).get(i)
        n = int(np.count_nonzero(np.isfinite(detected.image_points[i, :, 0])))
        rows.append({"name": name, "used": reason is None, "skip_reason": reason, "n_points": n,
                     "rms_px": None if reason or residuals_px is None else _rms(residuals_px[i]),
                     "rms_mm": None if reason or residuals_mm is None else _rms(residuals_mm[i])})
    return rows


def ros_transform_yaml(T: np.ndarray, parent: str, child: str, comment: str) -> str:
    """A ROS-style transform (metres, quaternion x, y, z, w), as ``static_transform_publisher`` and
    ROS-Industrial's calibration tools write it."""
    q = quaternion_from_matrix(np.asarray(T)[:3, :3])
    p = np.asarray(T)[:3, 3] / 1000.0
    lines = [f"# {ln}" for ln in comment.splitlines()]
    lines += [f"parent_frame: {parent}", f"child_frame: {child}", "transform:", "  translation:  # metres"]
    lines += [f"    {k}: {v:.9f}" for k, v in zip("xyz", p)]
    lines += ["  rotation:  # quaternion, Hamilton"]
    lines += [f"    {k}: {v:.9f}" for k, v in zip(("x", "y", "z", "w"), (q[1], q[2], q[3], q[0]))]
    return "\n".join(lines) + "\n"


def overlay_figures(detected: DetectedSet, projected: np.ndarray, order, k: int = 4) -> list:
    """Back-projection overlays of up to ``k`` used images: the worst, the best and ones between
    (``order``: per-image RMS, NaN for unused)."""
    from ...report.camera_report import plot_backprojection

    rms = np.asarray(order, dtype=float)
    idx = np.flatnonzero(np.isfinite(rms))
    if len(idx) == 0:
        return []
    ranked = idx[np.argsort(rms[idx])[::-1]]
    pick = sorted(set(ranked[np.linspace(0, len(ranked) - 1, min(k, len(ranked))).round().astype(int)].tolist()))
    out = []
    for i in pick:
        gray = read_image_gray(detected.paths[i])
        out.append(plot_backprojection(gray, detected.image_points[i], projected[i],
                                       f"{detected.names[i]}: RMS {rms[i]:.2f} px"))
    return out


def identifiability_lines(report) -> list:
    """Human-readable findings of a calib identifiability report (what cannot be determined)."""
    if report is None:
        return []
    dropped = getattr(report, "dropped", None)
    if dropped is None:
        return [str(report)]
    if not dropped:
        return ["every estimated parameter is identifiable from these images"]
    lines = []
    for d in dropped:
        lines.append(f"{d['name']}: {d.get('why', 'not identifiable')}; held at its start value")
    return lines
