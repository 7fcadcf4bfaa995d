"""Forward kinematics batched over parameter vectors: P candidate models x N configurations.

:class:`ParameterBatchFK` fixes a model, its configurations and one end effector, and returns
the end-effector frames for any stack of parameter vectors in one compiled call (the particle
swarm's hot path, :mod:`robocal.calib.swarm`). The joint part of every operation is computed
once at construction, so a call costs only the chain products.

Example::

    fk = ParameterBatchFK(model, q)                 # q (N, n_joints)
    T = fk(np.stack([model.params.values] * 20))    # (20, N, 3, 4) in the robot base frame

:meth:`ParameterBatchFK.squared_residuals` goes one step further: it sums the squared point and
rotation residuals of those frames per parameter vector inside the compiled call (P,), without
storing the (P, N) frames.
"""

from __future__ import annotations

import numpy as np

__all__ = ["ParameterBatchFK"]


class ParameterBatchFK:
    """End-effector frames for many parameter vectors of one model at fixed configurations.

    model: a :class:`~robocal.kinematics.model.RobotModel`; q (N, n_joints) controller joints
    [rad | mm]; end_effector: name or index (default the first). Frames are in the robot base
    frame (the model's ``T_world_base`` is *not* applied), as :meth:`RobotModel.target_points`
    without ``root``.
    """

    def __init__(self, model, q, end_effector=None):
        q2, _ = model._as_joints(q)
        self.model = model
        self.n_poses = len(q2)
        qm = model.model_joints(q2)  # (N, n_model)
        jv = np.zeros((len(q2), len(model._op_code)))
        moves = model._op_joint >= 0
        jv[:, moves] = qm[:, model._op_joint[moves]]
        self._op_moves = moves
        self._joint_values = np.ascontiguousarray(jv)
        e = model.end_effector_index(end_effector)
        ee = model.end_effectors[e]
        self._ee_link = int(ee.link)
        self._ee_T = np.ascontiguousarray(np.asarray(ee.T_link_ee, dtype=float)[:3])
        self._op_param = model._op_param

    def _op_values(self, params):
        params = np.asarray(params, dtype=float)
        if params.ndim != 2 or params.shape[1] != len(self.model.params):
            raise ValueError(f"params: expected (P, {len(self.model.params)}), got {params.shape}")
        return np.ascontiguousarray(params[:, self._op_param])

    def squared_residuals(self, params, base, targets, p_meas, p_mask, p_w2, r_right, r_meas, r_w2, out=None):
        """Per parameter vector (P,): ``sum_n sum_k p_w2[k] |p_meas[n, k] - W_n t_k|^2 +
        sum_n sum_m r_w2[m] theta_nm^2`` with ``W_n = base[n] F_n`` (base (N, 3, 4) affine, F_n the
        end-effector frame), targets (P, K, 3) [mm] in the end effector's frame, p_mask (N, K) bool,
        r_right (P, M, 3, 3), r_meas (N, M, 3, 3) and ``theta = 2 asin(||r_meas - W_R r_right||_F / sqrt 8)``
        [rad]. The sum is added to ``out`` when given (one compiled call, no frame stored)."""
        from ._batch_kernels import ee_objective_batch

        ov = self._op_values(params)
        m = self.model
        if out is None:
            out = np.zeros(len(ov))
        ee_objective_batch(ov, self._joint_values, m._op_link, m._op_code, m._op_axis, self._op_moves, m._link_parent,
                           self._ee_link, self._ee_T, base, targets, p_meas, p_mask, p_w2, r_right, r_meas, r_w2, out)
        return out

    def __call__(self, params, out=None) -> np.ndarray:
        """Frames (P, N, 3, 4) [mm] for parameter vectors ``params`` (P, n_params) [mm | rad]."""
        from ._batch_kernels import ee_frames_batch

        ov = self._op_values(params)
        m = self.model
        P = len(ov)
        if out is None:
            out = np.empty((P, self.n_poses, 3, 4))
        ee_frames_batch(ov, self._joint_values, m._op_link,
                        m._op_code, m._op_axis, self._op_moves, m._link_parent, self._ee_link, self._ee_T, out)
        return out
