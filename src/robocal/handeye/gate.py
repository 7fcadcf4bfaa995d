"""Sanity gates of a hand-eye solution, in the form of :mod:`robocal.calib.sanity` (a
:class:`~robocal.calib.sanity.Verdict` with ``status``/``reasons``/``checks``).

A refinement always returns a transform with a small formal sigma, even for data that cannot
describe one camera on one robot (images paired with the wrong poses, inverted poses, a wrong
orientation convention or set-up, wrong intrinsics). The gates compare

* **reprojection**: the back-projection RMS through the reported flange poses against the corner
  noise seen by per-image PnP (``HANDEYE_NOISE_FACTOR`` x) and an absolute floor
  ``HANDEYE_RMS_FLOOR_PX`` (a real robot's pose error alone gives pixels: 2.3-2.6 px on the
  ROS-Industrial sets);
* **motion consistency**: the screw invariants of every pair of images (:mod:`.consistency`): the
  median angle mismatch against ``MOTION_ANGLE_LIMIT_DEG``; images whose own median exceeds
  ``IMAGE_ANGLE_LIMIT_DEG`` (and 3 x the overall median) are named;
* **agreement with the linear start**: the refined camera pose against the linear solution it
  started from (``LINEAR_POSITION_LIMIT_MM``, ``LINEAR_ROTATION_LIMIT_DEG``).

Likely causes (:func:`cause_reasons`) are named from hypotheses the caller evaluated (shifted
pairing, another convention, the other set-up or inverted poses, intrinsics calibrated on the same
images). Every bound is a module constant, listed in docs/reliability.md. Math only.
"""

from __future__ import annotations

import math

import numpy as np

from ..calib.sanity import Verdict, _check
from .consistency import MotionMismatch

__all__ = ["HANDEYE_NOISE_FACTOR", "HANDEYE_RMS_FLOOR_PX", "MOTION_ANGLE_LIMIT_DEG", "IMAGE_ANGLE_LIMIT_DEG",
           "LINEAR_POSITION_LIMIT_MM", "LINEAR_ROTATION_LIMIT_DEG", "HYPOTHESIS_RMS_FACTOR", "IMAGE_RMS_FACTOR", "handeye_verdict", "disagreeing_images",
           "Hypothesis", "cause_reasons", "self_calibration_verdict", "SELF_CALIBRATION_VARIANCE_LIMIT",
           "JOINT_OFFSET_LIMIT_DEG", "JOINT_NOISE_LIMIT_DEG", "CAMERA_RMS_LIMIT_PX", "camera_verdict"]

#: Back-projection RMS above this multiple of the per-image PnP RMS (the corner noise as this camera
#: model sees it) fails, unless below ``HANDEYE_RMS_FLOOR_PX``.
HANDEYE_NOISE_FACTOR = 10.0
#: Back-projection RMS [px] that always passes (robot pose errors of a real arm give a few pixels).
HANDEYE_RMS_FLOOR_PX = 5.0
#: A hypothesis for the cause fits when its linear solution back-projects within this multiple of the
#: gate's RMS limit.
HYPOTHESIS_RMS_FACTOR = 4.0
#: Median over all pairs of |angle(flange motion) - angle(camera motion)| [deg] above this fails
#: (ROS-Industrial sets: 0.45 and 1.95 deg; one pose row shifted: 12.7-19.9 deg).
MOTION_ANGLE_LIMIT_DEG = 5.0
#: An image whose own median angle mismatch exceeds this [deg] (and 3 x the overall median) is named.
IMAGE_ANGLE_LIMIT_DEG = 8.0
#: An image back-projecting worse than this multiple of the RMS limit (and 3 x the median image) is
#: named (ROS-Industrial 10x10: its worst image, 2.png, 7.3 px against the 5 px limit).
IMAGE_RMS_FACTOR = 2.0
#: The refined camera pose farther than this from its linear start [mm] / [deg] fails (ROS-Industrial
#: sets: 7.3 mm / 0.58 deg and 37.6 mm / 2.5 deg).
LINEAR_POSITION_LIMIT_MM = 100.0
LINEAR_ROTATION_LIMIT_DEG = 10.0


def disagreeing_images(mismatch: MotionMismatch) -> np.ndarray:
    """Indices of the images whose pairs disagree (median angle mismatch above
    ``IMAGE_ANGLE_LIMIT_DEG`` and above 3 x the median over all pairs)."""
    per = mismatch.per_image_angle_deg
    limit = max(IMAGE_ANGLE_LIMIT_DEG, 3.0 * (mismatch.angle_deg_median if math.isfinite(mismatch.angle_deg_median)
                                              else 0.0))
    return np.flatnonzero(np.isfinite(per) & (per > limit))


def _times(ratio: float) -> str:
    return "over 1000 x" if ratio > 1000 else f"{ratio:.0f} x"


def _names(indices, labels, images, k: int = 8) -> str:
    items = [f"{images[i]} (pose {labels[i]})" if str(labels[i]) not in str(images[i]) else str(images[i])
             for i in indices]
    return ", ".join(items[:k]) + (f" and {len(items) - k} more" if len(items) > k else "")


def handeye_verdict(*, backprojection_rms_px: float, pnp_rms_px: float, mismatch: MotionMismatch,
                    linear_difference: tuple, image_names, pose_labels,
                    per_image_backprojection_px=None) -> Verdict:
    """The gates of a hand-eye solution (module docstring).

    backprojection_rms_px: RMS [px] of the target projected through the reported flange poses and
    the solution; pnp_rms_px: the RMS [px] of per-image PnP with the same camera; mismatch: the
    screw-invariant mismatch of the data (:func:`~robocal.handeye.consistency.motion_mismatch`);
    linear_difference: ``(mm, deg)`` between the refined camera pose and its linear start;
    image_names, pose_labels (N): to name the images that disagree; per_image_backprojection_px (N):
    each image's back-projection RMS [px] (images far above the others are named).
    """
    checks: dict = {}
    reasons = []
    noise = max(float(pnp_rms_px), 1e-3) if math.isfinite(pnp_rms_px) else float("nan")
    limit = max(HANDEYE_RMS_FLOOR_PX, HANDEYE_NOISE_FACTOR * noise) if math.isfinite(noise) else HANDEYE_RMS_FLOOR_PX
    if not _check(checks, "reprojection_vs_corner_noise", backprojection_rms_px, limit, "px"):
        reasons.append(f"back-projection RMS {backprojection_rms_px:.4g} px through the reported flange poses is "
                       f"{_times(backprojection_rms_px / noise)} the corner noise (per-image PnP RMS {noise:.3g} px; "
                       f"limit max({HANDEYE_RMS_FLOOR_PX:g} px, {HANDEYE_NOISE_FACTOR:g} x)): the flange poses and "
                       "the images do not describe one camera on one robot")
    if not _check(checks, "motion_angle_consistency", mismatch.angle_deg_median, MOTION_ANGLE_LIMIT_DEG, "deg"):
        reasons.append(f"the flange and camera motions between image pairs rotate by different angles (median "
                       f"mismatch {mismatch.angle_deg_median:.3g} deg, limit {MOTION_ANGLE_LIMIT_DEG:g} deg): most "
                       "images are paired with the wrong flange pose, or the poses' orientation convention or the "
                       "camera's intrinsics are wrong")
    bad = disagreeing_images(mismatch)
    checks["images_disagreeing"] = {"value": int(len(bad)), "limit": 0, "unit": "images", "passed": not len(bad),
                                    "images": [str(image_names[i]) for i in bad]}
    if len(bad) and math.isfinite(mismatch.angle_deg_median) and mismatch.angle_deg_median <= MOTION_ANGLE_LIMIT_DEG:
        reasons.append(f"{len(bad)} image(s) disagree with the others' motions (median angle mismatch above "
                       f"{IMAGE_ANGLE_LIMIT_DEG:g} deg): {_names(bad, pose_labels, image_names)}: likely swapped or "
                       "mislabelled pose rows, an image duplicated over another, or a pose taken at another moment")
    per = np.asarray(per_image_backprojection_px if per_image_backprojection_px is not None else [], dtype=float)
    if per.size and np.isfinite(per).any():
        off_limit = max(IMAGE_RMS_FACTOR * limit, 3.0 * float(np.nanmedian(per)))
        off = np.flatnonzero(np.isfinite(per) & (per > off_limit))
        off = np.setdiff1d(off, bad)
        checks["images_off_the_chain"] = {"value": int(len(off)), "limit": 0, "unit": "images", "passed": not len(off),
                                          "images": [str(image_names[i]) for i in off]}
        if len(off) and len(off) <= len(per) // 2:
            worst = ", ".join(f"{image_names[i]} {per[i]:.3g} px" for i in off[np.argsort(-per[off])][:8])
            reasons.append(f"{len(off)} image(s) back-project far worse than the others through their flange poses "
                           f"({worst}; limit max({off_limit:.3g} px, 3 x the median image)): likely a wrong pose row "
                           "for these images (a typo, a pose taken at another moment, a swapped row)")
    dp, dr = linear_difference
    ok_p = _check(checks, "linear_start_position", dp, LINEAR_POSITION_LIMIT_MM, "mm")
    ok_r = _check(checks, "linear_start_rotation", dr, LINEAR_ROTATION_LIMIT_DEG, "deg")
    if not (ok_p and ok_r):
        reasons.append(f"the refined camera pose is {dp:.4g} mm / {dr:.3g} deg from the linear solution it started "
                       f"from (limits {LINEAR_POSITION_LIMIT_MM:g} mm, {LINEAR_ROTATION_LIMIT_DEG:g} deg): the "
                       "data admit no consistent linear solution")
    return Verdict(tuple(reasons), checks)


class Hypothesis:
    """One alternative reading of the data and how well it fits: ``cause`` (a sentence), the
    median angle mismatch [deg] and, when evaluated, the back-projection RMS [px] of its linear
    solution (NaN when not evaluated or unsolvable)."""

    def __init__(self, cause: str, angle_deg: float, rms_px: float = float("nan")):
        self.cause, self.angle_deg, self.rms_px = cause, float(angle_deg), float(rms_px)

    def fits(self, rms_limit_px: float, reference_rms_px: float = float("inf")) -> bool:
        """Its motions agree and (when evaluated) its linear solution back-projects within
        ``HYPOTHESIS_RMS_FACTOR`` x ``rms_limit_px`` (a linear solution is not refined: the clean
        ROS-Industrial 10x10 set's is 10.4 px) and below a quarter of ``reference_rms_px``, the
        linear solution's RMS on the data as given."""
        if not (math.isfinite(self.angle_deg) and self.angle_deg <= MOTION_ANGLE_LIMIT_DEG):
            return False
        if not math.isfinite(self.rms_px):
            return True
        return self.rms_px <= HYPOTHESIS_RMS_FACTOR * rms_limit_px and not self.rms_px > 0.25 * reference_rms_px


def cause_reasons(hypotheses, rms_limit_px: float, reference_rms_px: float = float("inf")) -> list:
    """Reasons naming the hypotheses that fit the data (``likely cause: ...``), best first."""
    fitting = [h for h in hypotheses if h.fits(rms_limit_px, reference_rms_px)]
    fitting.sort(key=lambda h: (h.rms_px if math.isfinite(h.rms_px) else 0.0, h.angle_deg))
    return [f"likely cause: {h.cause} (the data then fit: motion angle mismatch {h.angle_deg:.3g} deg"
            + (f", linear solution's back-projection RMS {h.rms_px:.3g} px" if math.isfinite(h.rms_px) else "") + ")"
            for h in fitting]


#: Self-calibration: residuals above this multiple of what the corner noise (and the declared joint
#: noise) explain fail: the offsets' sigmas are then optimistic and the offsets biased (0.05 deg
#: reading noise taken as exact: variance factor 2.4, offsets 17 sigma off; tests/test_self_calibration_pipeline.py).
SELF_CALIBRATION_VARIANCE_LIMIT = 1.5
#: An estimated joint-reading noise above this [deg] is no encoder's: the pairing or the model is wrong.
JOINT_NOISE_LIMIT_DEG = 0.5
#: A joint zero offset beyond this [deg] is no mastering error (a wrong pairing of images and joints).
JOINT_OFFSET_LIMIT_DEG = 10.0


def self_calibration_verdict(*, variance_factor: float, pixel_sigma_px: float, rms_px: float, joint_noise_deg,
                             offsets_deg: dict, joint_noise_estimated: bool = False) -> Verdict:
    """The gates of a camera self-calibration.

    variance_factor: sqrt(weighted residual sum / redundancy) of the solve (1 when the residuals
    scatter as the corner noise ``pixel_sigma_px`` [px] and ``joint_noise_deg`` [deg] say);
    rms_px: the reprojection RMS [px]; offsets_deg: {name: joint offset [deg]} of the revolute
    joints; joint_noise_estimated: the noise was estimated (it must then stay within
    ``JOINT_NOISE_LIMIT_DEG``). (Convergence is judged apart: exit code 4, not 3.)
    """
    checks: dict = {}
    reasons = []
    if not _check(checks, "residuals_vs_noise", variance_factor, SELF_CALIBRATION_VARIANCE_LIMIT, "x"):
        declared = ("the joint readings taken as exact" if not joint_noise_deg else
                    f"a joint-reading noise of {joint_noise_deg:g} deg" + (" (estimated)" if joint_noise_estimated
                                                                         else ""))
        reasons.append(f"the residuals (RMS {rms_px:.4g} px) are {variance_factor:.3g} x what the corner noise "
                       f"({pixel_sigma_px:.3g} px) and {declared} explain (limit {SELF_CALIBRATION_VARIANCE_LIMIT:g} x): "
                       "the offsets are biased and their sigmas optimistic; likely noisier joint readings than "
                       "declared (pass --joint-noise), images paired with the wrong joint readings (a clock "
                       "offset, permuted frame times) or a wrong camera")
    if joint_noise_estimated and not _check(checks, "estimated_joint_noise", joint_noise_deg or 0.0,
                                            JOINT_NOISE_LIMIT_DEG, "deg"):
        reasons.append(f"the residuals need a joint-reading noise of {joint_noise_deg:g} deg or more to be explained "
                       f"(limit {JOINT_NOISE_LIMIT_DEG:g} deg): no encoder reads that badly; likely images paired "
                       "with the wrong joint readings (a clock offset, permuted frame times) or a wrong camera")
    worst = max(offsets_deg.items(), key=lambda kv: abs(kv[1]), default=(None, 0.0))
    if not _check(checks, "joint_offset", abs(worst[1]), JOINT_OFFSET_LIMIT_DEG, "deg"):
        reasons.append(f"joint offset {worst[0]} = {worst[1]:+.3g} deg (limit {JOINT_OFFSET_LIMIT_DEG:g} deg): no "
                       "mastering error; likely images paired with the wrong joint readings or the wrong robot")
    return Verdict(tuple(reasons), checks)


#: Camera calibration: a reprojection RMS [px] above this fails (ROS-Industrial ChArUco set: 0.50 px;
#: rendered images: 0.06 px; half the images of a set stretched 1.3 x sideways, as from another
#: camera or a resampling: 3.1 px).
CAMERA_RMS_LIMIT_PX = 2.0


def camera_verdict(rms_px: float) -> Verdict:
    """The basic gate of a camera calibration: its reprojection RMS [px] against ``CAMERA_RMS_LIMIT_PX``
    (distortion-specific gates belong to the camera model's own checks)."""
    checks: dict = {}
    reasons = []
    if not _check(checks, "reprojection_rms", rms_px, CAMERA_RMS_LIMIT_PX, "px"):
        reasons.append(f"reprojection RMS {rms_px:.4g} px (limit {CAMERA_RMS_LIMIT_PX:g} px): one camera model does not "
                       "explain these images; likely images of another camera or resampled images in the set, a "
                       "lens model too simple for the lens (--model, --distortion), or a board spec that does not "
                       "match the printed board")
    return Verdict(tuple(reasons), checks)
