"""Forward kinematics batched over parameter vectors: P candidate models x N configurations.

:class:`ParameterBatchFK` fixes a model, its configurations and one end effector, and returns
the end-effector frames for any stack of parameter vectors in one compiled call (the particle
swarm's hot path, :mod:`robocal.calib.swarm`). The joint part of every operation is computed
once at construction, so a call costs only the chain products.

Example::

    fk = ParameterBatchFK(model, q)                 # q (N, n_joints)
    T = fk(np.stack([model.params.values] * 20))    # (20, N, 3, 4) in the robot base frame
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

    def __call__(self, params, out=None) -> np.ndarray:
        """Frames (P, N, 3, 4) [mm] for parameter vectors ``params`` (P, n_params) [mm | rad]."""
        from ._batch_kernels import ee_frames_batch

        params = np.asarray(params, dtype=float)
        if params.ndim != 2 or params.shape[1] != len(self.model.params):
            raise ValueError(f"params: expected (P, {len(self.model.params)}), got {params.shape}")
        m = self.model
        P = len(params)
        if out is None:
            out = np.empty((P, self.n_poses, 3, 4))
        ee_frames_batch(np.ascontiguousarray(params[:, self._op_param]), self._joint_values, m._op_link,
                        m._op_code, m._op_axis, self._op_moves, m._link_parent, self._ee_link, self._ee_T, out)
        return out
