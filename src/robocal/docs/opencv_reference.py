"""OpenCV end to end on hand-eye detections, the reference robocal is compared with
(tests/test_handeye_images.py and docs/handeye.md's rendered-images figures): ``cv2.solvePnP`` per
image, then every ``cv2.calibrateHandEye`` method and ``cv2.calibrateRobotWorldHandEye`` (SHAH, LI).
OpenCV as a reference lives outside robocal's own packages (the import contract keeps cv2 in io/);
needs the ``images`` extra."""

from __future__ import annotations

import numpy as np

from ..transforms import invert_transforms

__all__ = ["opencv_hand_eye_solutions"]


def _pose(R, t) -> np.ndarray:
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = R, np.ravel(t)
    return T


def opencv_hand_eye_solutions(T_base_flange, image_points, target_points, camera, setup: str) -> dict:
    """``{method: camera pose (4, 4) [mm]}`` in robocal's convention (the camera in the flange frame
    for ``eye_in_hand``, in the base frame for ``eye_to_hand``) for TSAI, PARK, HORAUD, ANDREFF,
    DANIILIDIS, RW_SHAH and RW_LI. ``T_base_flange`` (N, 4, 4) [mm]; ``image_points`` (N, P, 2) [px],
    NaN where a corner was not found; ``target_points`` (P, 3) [mm]; ``camera`` a robocal camera. A
    static camera: OpenCV wants the flange poses inverted."""
    import cv2

    F, X = np.asarray(T_base_flange, dtype=float), np.asarray(target_points, dtype=float)
    C = []
    for pts in np.asarray(image_points, dtype=float):
        ok = np.isfinite(pts[:, 0])
        _, r, t = cv2.solvePnP(X[ok], pts[ok], camera.matrix, np.array(camera.distortion))
        C.append(_pose(cv2.Rodrigues(r)[0], t))
    C = np.array(C)
    G = F if setup == "eye_in_hand" else invert_transforms(F)
    methods = {"TSAI": cv2.CALIB_HAND_EYE_TSAI, "PARK": cv2.CALIB_HAND_EYE_PARK, "HORAUD": cv2.CALIB_HAND_EYE_HORAUD,
               "ANDREFF": cv2.CALIB_HAND_EYE_ANDREFF, "DANIILIDIS": cv2.CALIB_HAND_EYE_DANIILIDIS}
    out = {k: _pose(*cv2.calibrateHandEye(list(G[:, :3, :3]), list(G[:, :3, 3]), list(C[:, :3, :3]), list(C[:, :3, 3]),
                                          method=m)) for k, m in methods.items()}
    B = invert_transforms(G)  # OpenCV's base2gripper
    for k, m in {"RW_SHAH": cv2.CALIB_ROBOT_WORLD_HAND_EYE_SHAH, "RW_LI": cv2.CALIB_ROBOT_WORLD_HAND_EYE_LI}.items():
        _, _, R_cam_gripper, t_cam_gripper = cv2.calibrateRobotWorldHandEye(
            list(C[:, :3, :3]), list(C[:, :3, 3]), list(B[:, :3, :3]), list(B[:, :3, 3]), method=m)
        out[k] = invert_transforms(_pose(R_cam_gripper, t_cam_gripper))
    return out
