"""Image points of a target seen through a robot's flange pose with the pose in the loop (issue 14
item 4: hand-eye refinement with the robot's joint offsets and with per-image flange-pose errors;
METHODS.md section 3, "Hand-eye").

The per-image link ``M_i`` of :class:`~.reprojection.ReprojectionResidual` is built from the
flange pose ``F_i`` -- forward kinematics at the recorded joints with the parameters of a robot
geometry block, or given poses -- and, optionally, a per-image correction frame ``E_i`` (a
FramesBlock near the identity, in the flange frame: the true flange pose is ``F_i E_i``; with a
Gaussian prior it models the robot's pose noise, the errors-in-variables form of the problem):

* eye-in-hand (``invert=True``): ``M_i = (F_i E_i)^-1``, ``p_camera = C^-1 E_i^-1 F_i^-1 T X``;
* eye-to-hand (``invert=False``): ``M_i = F_i E_i``, ``p_camera = C^-1 F_i E_i T X``;
* camera and target on two end effectors of one robot (``target_end_effector``; issue 15, camera
  self-calibration, METHODS.md section 3): ``M_i = A_i^-1 B_i`` with ``A_i`` the camera's end
  effector and ``B_i`` the target's, both from forward kinematics with the same geometry block, so
  the joints of both chains (and those they share) are in the loop: ``p_camera = C^-1 A_i^-1 B_i T X``.
  Optionally (``joint_corrections``, a VectorBlock (N, k) with a Gaussian prior) each image's
  joint readings get corrections (errors in variables for joint-reading noise): the kinematics
  use ``q_i + dq_i`` on the controller columns ``correction_columns``; the derivative w.r.t.
  ``dq_i[j]`` is that image's column of the joint's offset parameter (``correction_params``, its
  position in the geometry block), since an offset adds to the joint angle.

Derivatives (frames left-perturbed, ``F <- [exp(w) | v] F`` with the spatial twist ``xi`` of the
end effector from :meth:`~robocal.kinematics.model.RobotModel.kinematics_with`; ``y = T X``):

* geometry, eye-to-hand: ``q = M_i y`` moves by ``-[q]x w + v``, ``dp = R_C^T (-[q]x w + v)``;
  eye-in-hand: ``dp = -R_C^T R_M (-[y]x w + v)``;
* correction, eye-to-hand: ``E y`` moves by ``-[E y]x w + v`` in the flange, ``dp = R_C^T R_F (...)``;
  eye-in-hand: with ``g = F^-1 y``, ``dp = -R_C^T R_E^T (-[g]x w + v)``;
* geometry, two end effectors: with ``z = B_i y`` (base frame) and the spatial twists ``xi_A``,
  ``xi_B`` of the two end effectors, ``dp = R_C^T R_A^T [-[z]x | I] (xi_B - xi_A)`` -- a joint on
  the path to both (a shared torso joint) moves both frames alike and cancels.
"""

from __future__ import annotations

import numpy as np

from ...camera.projection import project_points
from ...transforms import invert_transforms, skew, so3_exp
from ..blocks.camera import CameraIntrinsics
from ..errors import ProblemError
from .reprojection import ReprojectionResidual, cross_rows

__all__ = ["FlangeReprojectionResidual"]


def _frame_rows(p):
    """(n, 3, 6): ``[-[p]x | I]``, the motion of points p (n, 3) under a left step (w, v)."""
    return np.concatenate([-skew(p), np.broadcast_to(np.eye(3), p.shape + (3,))], axis=2)


class FlangeReprojectionResidual(ReprojectionResidual):
    """:class:`ReprojectionResidual` with the flange pose in the loop (module docstring).

    Either ``model`` (a RobotModel), ``q`` (N, n_ctrl) [rad | mm] and ``geometry`` (a
    :class:`~robocal.calib.blocks.RobotGeometry` on the model; ``end_effector`` names the frame,
    default the model's first) or ``flange_poses`` (N, 4, 4) [mm] fixed; ``corrections``: an
    optional FramesBlock of N per-image flange corrections; ``invert``: eye-in-hand. Other
    arguments as :class:`ReprojectionResidual` (no ``links``). ``target_end_effector``: the end
    effector that carries the target (``T`` is then the target in that end effector's frame and
    ``end_effector`` the one that carries the camera, ``invert`` must be True, no corrections).
    ``compact_corrections``: return the corrections' Jacobian as (M, 6), each row's derivative by
    its own image's correction (``correction_frame_of_row`` (M,) says which), instead of
    (M, 6 N) mostly zeros -- for the structured solver (:mod:`robocal.calib.schur`), not for
    :meth:`Problem.evaluate`.
    """

    def __init__(self, camera, camera_poses, target_poses, image_points, target_points, *, model=None, q=None,
                 geometry=None, flange_poses=None, corrections=None, end_effector=None, invert: bool = True,
                 camera_index=None, target_index=None, sigma: float | None = None, target_end_effector=None,
                 joint_corrections=None, correction_columns=None, correction_params=None,
                 compact_corrections: bool = False):
        super().__init__(camera, camera_poses, target_poses, image_points, target_points,
                         camera_index=camera_index, target_index=target_index, sigma=sigma)
        N = len(self.image_points)
        self.model, self.geometry, self.corrections, self.invert = model, geometry, corrections, bool(invert)
        extra = ()
        if model is not None:
            if geometry is None or q is None:
                raise ProblemError("flange reprojection: a robot model needs q and a geometry block")
            self.q = np.asarray(q, dtype=float)
            if len(self.q) != N:
                raise ProblemError(f"flange reprojection: {len(self.q)} joint rows for {N} images")
            self.ee = model.end_effector_index(end_effector)
            extra += (geometry,)
            self.target_ee = None
            if target_end_effector is not None:
                if not invert or corrections is not None:
                    raise ProblemError("flange reprojection: a target on an end effector needs the camera on the "
                                       "robot (invert=True) and no per-image corrections")
                self.target_ee = model.end_effector_index(target_end_effector)
            self.joint_corrections = joint_corrections
            if joint_corrections is not None:
                self.correction_columns = np.asarray(correction_columns, dtype=int)
                self.correction_params = np.asarray(correction_params, dtype=int)
                k = len(self.correction_columns)
                if joint_corrections.initial.shape != (N, k) or self.correction_params.shape != (k,):
                    raise ProblemError(f"flange reprojection: joint corrections must be ({N}, {k}) with {k} "
                                       "columns and parameters")
                extra += (joint_corrections,)
        else:
            F = np.asarray(flange_poses, dtype=float) if flange_poses is not None else None
            if target_end_effector is not None or joint_corrections is not None:
                raise ProblemError("flange reprojection: target_end_effector and joint corrections need a robot model")
            self.joint_corrections = None
            self.target_ee = None
            if F is None or F.shape != (N, 4, 4):
                raise ProblemError(f"flange reprojection: flange_poses must be ({N}, 4, 4) without a robot model")
            self.flange_poses = F
        if corrections is not None:
            if corrections.n_frames != N:
                raise ProblemError(f"flange reprojection: {corrections.n_frames} correction frames for {N} images")
            extra += (corrections,)
        self.compact_corrections = bool(compact_corrections) and corrections is not None
        self.correction_frame_of_row = np.repeat(self.image_of_row, 2)
        # given flange poses, one camera and one target frame (hand-eye): the per-image chain is
        # composed first and every point moved by one batched product (:meth:`_evaluate_fixed`)
        self._fixed = (self.model is None and camera_poses.n_frames == 1 and target_poses.n_frames == 1)
        if self._fixed:
            self._point_of_row = np.nonzero(self.mask)[1]
            self._all_detected = bool(self.mask.all())
            self._F_inv = invert_transforms(self.flange_poses)
        self.parameter_blocks = self.parameter_blocks + extra

    def _flange(self, ev):
        """(F (N, 4, 4), twists (N, 6, k) or None) at this evaluation, computed once."""
        if self.model is None:
            return self.flange_poses, None

        return self._kinematics(ev)[:2]

    def _kinematics(self, ev):
        """(A, twists of A, B or None, twists of B or None): the camera's end effector and the
        target's, (N, 4, 4) and (N, 6, k), computed once per evaluation."""
        def compute(ev):
            ees = [self.ee] if self.target_ee is None else [self.ee, self.target_ee]
            q = self.q
            if self.joint_corrections is not None:
                q = q.copy()
                q[:, self.correction_columns] += ev[self.joint_corrections]
            T, ptw, _, masks = self.model.kinematics_with(q, ev[self.geometry], T_world_base=np.eye(4),
                                                          end_effectors=ees)
            tw = [(ptw * m)[:, :, self.geometry.index] for m in masks]
            if self.target_ee is None:
                return T[:, 0], tw[0], None, None
            return T[:, 0], tw[0], T[:, 1], tw[1]
        return ev.shared((self, "kinematics"), compute)

    def _links(self, ev):
        if self.target_ee is not None:
            A, _, B, _ = self._kinematics(ev)
            return invert_transforms(A) @ B
        F = self._flange(ev)[0]
        if self.corrections is not None:
            F = F @ ev[self.corrections]
        return invert_transforms(F) if self.invert else F

    def _per_image(self, rows, R):
        """``rows`` (n, 2, 3) of the detected points times their image's matrix R (N, 3, 3): (n, 2, 3)."""
        N, P = self.mask.shape
        if self._all_detected:
            return (rows.reshape(N, 2 * P, 3) @ R).reshape(-1, 2, 3)
        full = np.zeros((N, P, 2, 3))
        full[self.mask] = rows
        return (full.reshape(N, 2 * P, 3) @ R).reshape(N, P, 2, 3)[self.mask]

    def _evaluate_fixed(self, ev, jacobian):
        """:meth:`evaluate` for given flange poses, one camera frame and one target frame: the same
        residuals and derivatives (module docstring), with the per-image links composed first and the
        points moved per image by one batched product instead of a 3 x 3 product per point."""
        T = ev[self.target_poses][0]
        Cf = ev[self.camera_poses][0]
        RC, c = Cf[:3, :3], Cf[:3, 3]
        y0 = self.target_points @ T[:3, :3].T + T[:3, 3]  # (P, 3): the target's points in its parent frame
        E = ev[self.corrections] if self.corrections is not None else None
        if self.invert:  # M_i = (F_i E_i)^-1 = E_i^-1 F_i^-1
            M = self._F_inv if E is None else invert_transforms(E) @ self._F_inv
        else:
            M = self.flange_poses if E is None else self.flange_poses @ E
        q = (y0 @ np.swapaxes(M[:, :3, :3], 1, 2) + M[:, None, :3, 3])[self.mask]  # (n, 3) in C's parent frame
        p = (q - c) @ RC
        intr, dist = CameraIntrinsics.split(ev[self.camera])
        wants_cam = jacobian and ev.wants(self.camera)
        proj = project_points(p, intr, dist, self.camera.model, jacobian, point_only=jacobian and not wants_cam)
        w = self.weight
        r = (self._detected - proj.pixels).ravel()
        if w != 1.0:
            r *= w
        if not jacobian:
            return r, None
        jac = {}
        m = len(r)
        if wants_cam:
            jac[self.camera] = np.concatenate([proj.d_intrinsics, proj.d_distortion], axis=2).reshape(m, -1) * w
        e_C = (proj.d_point.reshape(-1, 3) @ RC.T).reshape(-1, 2, 3)  # (n, 2, 3): d u / d q, one product
        if ev.wants(self.camera_poses):
            jac[self.camera_poses] = cross_rows(q, e_C, -w).reshape(m, 6)  # the weight folded into the sign
        if ev.wants(self.target_poses):
            e_T = self._per_image(e_C, M[:, :3, :3])
            jac[self.target_poses] = cross_rows(y0[self._point_of_row], e_T, w).reshape(m, 6)
        if E is not None and ev.wants(self.corrections):
            F = self.flange_poses
            if self.invert:  # g = F^-1 y in the reported flange frame; rows -(e_C R_E^T) [-[g]x | I]
                G = y0 @ np.swapaxes(self._F_inv[:, :3, :3], 1, 2) + self._F_inv[:, None, :3, 3]
                d = cross_rows(G[self.mask], self._per_image(e_C, np.swapaxes(E[:, :3, :3], 1, 2)), -w)
            else:  # e = E y in the flange frame; rows (e_C R_F) [-[e]x | I]
                G = y0 @ np.swapaxes(E[:, :3, :3], 1, 2) + E[:, None, :3, 3]
                d = cross_rows(G[self.mask], self._per_image(e_C, F[:, :3, :3]), w)
            if self.compact_corrections:
                jac[self.corrections] = d.reshape(m, 6)
            else:
                J = np.zeros((len(p), 2, self.corrections.n_frames, 6))
                J[np.arange(len(p)), :, self.image_of_row, :] = d
                jac[self.corrections] = J.reshape(m, -1)
        return r, jac

    def evaluate(self, ev, jacobian):
        if self._fixed:
            return self._evaluate_fixed(ev, jacobian)
        r, jac, (y, q, p, RC, RM, img, d_point) = self._evaluate(ev, jacobian)
        if not jacobian:
            return r, jac
        RCt = np.swapaxes(RC, 1, 2)
        w = self.weight
        wants_dq = self.model is not None and self.joint_corrections is not None and ev.wants(self.joint_corrections)
        Jg = None
        if self.model is not None and self.target_ee is not None and (ev.wants(self.geometry) or wants_dq):
            A, xi_a, B, xi_b = self._kinematics(ev)
            Bi = B[img]
            z = np.einsum("nij,nj->ni", Bi[:, :3, :3], y) + Bi[:, :3, 3]
            dp = (RCt @ np.swapaxes(A[img][:, :3, :3], 1, 2)) @ _frame_rows(z)
            Jg = d_point @ dp @ (xi_b[img] - xi_a[img])
        elif self.model is not None and (ev.wants(self.geometry) or wants_dq):
            xi = self._flange(ev)[1][img]  # (n, 6, k)
            dp = -(RCt @ RM) @ _frame_rows(y) if self.invert else RCt @ _frame_rows(q)
            Jg = d_point @ dp @ xi
        if Jg is not None and ev.wants(self.geometry):
            jac[self.geometry] = Jg.reshape(len(r), -1) * w
        if Jg is not None and wants_dq:
            N, k = self.joint_corrections.initial.shape
            J = np.zeros((len(p), 2, N, k))
            J[np.arange(len(p)), :, img, :] = Jg[:, :, self.correction_params]
            jac[self.joint_corrections] = J.reshape(len(r), -1) * w
        if self.corrections is not None and ev.wants(self.corrections):
            F = self._flange(ev)[0][img]
            E = ev[self.corrections][img]
            if self.invert:  # g = F^-1 y
                g = np.einsum("nji,nj->ni", F[:, :3, :3], y - F[:, :3, 3])
                dp = -(RCt @ np.swapaxes(E[:, :3, :3], 1, 2)) @ _frame_rows(g)
            else:
                e = np.einsum("nij,nj->ni", E[:, :3, :3], y) + E[:, :3, 3]
                dp = (RCt @ F[:, :3, :3]) @ _frame_rows(e)
            if self.compact_corrections:
                jac[self.corrections] = (d_point @ dp).reshape(len(r), 6) * w
            else:
                J = np.zeros((len(p), 2, self.corrections.n_frames, 6))
                J[np.arange(len(p)), :, img, :] = d_point @ dp
                jac[self.corrections] = J.reshape(len(r), -1) * w
        return r, jac

    @classmethod
    def example(cls, rng):
        """On the 4-joint example robot (eye-in-hand and eye-to-hand, every parameter and a
        correction per image free) and with fixed flange poses and corrections; and a camera and a
        target on two end effectors of one robot."""
        from ..blocks import CameraIntrinsics, FramesBlock, RobotGeometry
        from .examples import example_frames, example_robot

        grid = np.stack(np.meshgrid(np.arange(4.0), np.arange(3.0)), -1).reshape(-1, 2) * 30.0
        X = np.column_stack([grid - 45.0, np.zeros(len(grid))])
        out = []
        for invert, robot in ((True, True), (False, True), (True, False), (False, False)):
            N = 4
            model = example_robot(rng)
            q = rng.uniform(-1.0, 1.0, (N, model.n_joints))
            geometry = RobotGeometry(model)
            F = model.kinematics_with(q, geometry.initial, T_world_base=np.eye(4), end_effectors=[0])[0][:, 0]
            E = np.tile(np.eye(4), (N, 1, 1))
            E[:, :3, :3] = so3_exp(rng.normal(0, 0.02, (N, 3)))
            E[:, :3, 3] = rng.normal(0, 1.0, (N, 3))
            FE = F @ E
            M = invert_transforms(FE) if invert else FE
            cam = CameraIntrinsics(rng.uniform([900, 900, 600, 450], [1100, 1100, 700, 550]),
                                   rng.normal(0, [0.1, 0.05, 0.002, 0.002, 0.02]))
            T_ct = example_frames(rng, N)
            T_ct[:, :3, 3] = np.column_stack([rng.normal(0, 40, (N, 2)), rng.uniform(400, 700, N)])
            C = example_frames(rng, 1)
            T = invert_transforms(M) @ C @ T_ct  # per-image target frames so that every point is seen
            uv = np.full((N, len(X), 2), 500.0) + rng.normal(0, 50, (N, len(X), 2))
            uv[2, 1] = np.nan
            kw = dict(model=model, q=q, geometry=geometry) if robot else dict(flange_poses=F)
            out.append(cls(cam, FramesBlock("camera", C), FramesBlock("target", T), uv, X, invert=invert,
                           corrections=FramesBlock("corrections", E), target_index=np.arange(N), sigma=0.3, **kw))
        out.append(cls._two_end_effector_example(rng))
        out += cls._hand_eye_examples(rng)
        return out

    @classmethod
    def _hand_eye_examples(cls, rng):
        """Given flange poses, one camera frame and one target frame, with per-image corrections
        (eye-in-hand and eye-to-hand; the hand-eye refinement's set-up)."""
        from ..blocks import CameraIntrinsics, FramesBlock
        from .examples import example_frames

        grid = np.stack(np.meshgrid(np.arange(4.0), np.arange(3.0)), -1).reshape(-1, 2) * 30.0
        X = np.column_stack([grid - 45.0, np.zeros(len(grid))])
        out = []
        for invert in (True, False):
            N = 4
            E = np.tile(np.eye(4), (N, 1, 1))
            E[:, :3, :3] = so3_exp(rng.normal(0, 0.02, (N, 3)))
            E[:, :3, 3] = rng.normal(0, 1.0, (N, 3))
            T_ct = example_frames(rng, N)
            T_ct[:, :3, 3] = np.column_stack([rng.normal(0, 40, (N, 2)), rng.uniform(400, 700, N)])
            C, T = example_frames(rng, 1), example_frames(rng, 1)
            # flange poses that put the target in view: T_ct = C^-1 M_i T with M_i = (F_i E_i)^-1 or F_i E_i
            M = C @ T_ct @ invert_transforms(T)
            F = (invert_transforms(M) if invert else M) @ invert_transforms(E)
            cam = CameraIntrinsics(rng.uniform([900, 900, 600, 450], [1100, 1100, 700, 550]),
                                   rng.normal(0, [0.1, 0.05, 0.002, 0.002, 0.02]))
            uv = np.full((N, len(X), 2), 500.0) + rng.normal(0, 50, (N, len(X), 2))
            uv[1, 4] = np.nan
            out.append(cls(cam, FramesBlock("camera", C), FramesBlock("target", T), uv, X, invert=invert,
                           flange_poses=F, corrections=FramesBlock("corrections", E), sigma=0.3))
        return out

    @classmethod
    def _two_end_effector_example(cls, rng):
        """Camera on the example robot's ``side`` end effector, target on its ``flange``."""
        from ..blocks import CameraIntrinsics, FramesBlock, RobotGeometry
        from .examples import example_frames, example_robot

        grid = np.stack(np.meshgrid(np.arange(4.0), np.arange(3.0)), -1).reshape(-1, 2) * 30.0
        X = np.column_stack([grid - 45.0, np.zeros(len(grid))])
        N = 4
        model = example_robot(rng)
        q = rng.uniform(-1.0, 1.0, (N, model.n_joints))
        geometry = RobotGeometry(model)
        cam = CameraIntrinsics(rng.uniform([900, 900, 600, 450], [1100, 1100, 700, 550]),
                               rng.normal(0, [0.1, 0.05, 0.002, 0.002, 0.02]))
        uv = np.full((N, len(X), 2), 500.0) + rng.normal(0, 50, (N, len(X), 2))
        uv[1, 3] = np.nan
        T = example_frames(rng, 1)
        T[0, :3, 3] = rng.normal(0, 30, 3)
        F = model.kinematics_with(q, geometry.initial, T_world_base=np.eye(4), end_effectors=[1, 0])[0]
        T_ct = example_frames(rng, N)
        T_ct[:, :3, 3] = np.column_stack([rng.normal(0, 40, (N, 2)), rng.uniform(400, 700, N)])
        C = invert_transforms(F[:, 0]) @ F[:, 1] @ T @ invert_transforms(T_ct)  # one camera frame per image, in view
        from ..blocks import GaussianPrior, VectorBlock

        dq = VectorBlock("dq", [f"dq{i}.{j}" for i in range(N) for j in range(2)], ["rad"] * (2 * N),
                         rng.normal(0, 0.01, (N, 2)), prior=GaussianPrior(0.01, np.zeros((N, 2))))
        params = [model.params.names.index(f"theta{j}") for j in (3, 4)]
        return cls(cam, FramesBlock("camera", C), FramesBlock("target", T), uv, X, camera_index=np.arange(N),
                   model=model, q=q, geometry=geometry, end_effector="side", target_end_effector="flange", sigma=0.3,
                   joint_corrections=dq, correction_columns=[2, 3],
                   correction_params=[list(geometry.index).index(i) for i in params])
