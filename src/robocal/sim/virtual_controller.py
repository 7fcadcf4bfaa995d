"""A virtual robot controller: runs a robot program on the simulator's hidden true robot.

It does what a real controller does with a program: it knows only the *nominal* model; every
Cartesian target is turned into joints by the nominal inverse kinematics on the target's
configuration data (KUKA ``S``/``T``, ABB ``confdata``, FANUC ``CONFIG``; UR and data-less
targets: the solution nearest the current joints, following the program's order), with the
program's tool and base / work-object frame (:mod:`robocal.io.programs.frames`); joint targets are
commanded as they are. The *true* robot (hidden parameters) then moves to those joints, and the
controller reports where the tool centre point really lands. This is the judge of a corrected
program: compare the landing poses with the poses the original program meant.

Order: UR scripts in the text order of their motion commands, starting at the first joint target
(control flow is not followed); other languages in the order the targets are declared (their
configuration data fixes the solution, the order only matters for targets without it).
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..io.programs.checks import check_program
from ..io.programs.configuration import configuration_of
from ..io.programs.controller import controller_joints, with_tool
from ..io.programs.frames import resolve_frames, urscript_motions
from ..kinematics.arm_configuration import arm_signature
from ..kinematics.ik_analytic import is_analytic
from ..robots import load_robot

__all__ = ["ExecutedTarget", "VirtualController", "true_robot_of", "true_effects_of"]


@dataclass
class ExecutedTarget:
    """Where one target of a program took the true robot.

    name, kind (``cartesian``/``joint``), line; q (n,) commanded joints [rad] (None: not reached,
    ``reason`` says why); T_base_tcp_true (4, 4) where the true TCP landed in the robot base frame
    [mm]; T_base_tcp_commanded (4, 4) where the nominal model believes it is; T_base_frame (4, 4)
    the target's frame; signature (back, elbow_down, wrist_negative) of ``q`` (OPW robots);
    other_joints: commanded joints of later executions that differ from ``q`` (the target was used
    in another configuration). assumed_start: a UR target before any joint target (the joints the
    robot starts from are not in the program; the first joint target's, else all zero, are assumed).
    """

    name: str
    kind: str
    line: int
    q: np.ndarray | None
    T_base_tcp_true: np.ndarray | None = None
    T_base_tcp_commanded: np.ndarray | None = None
    T_base_frame: np.ndarray = field(default_factory=lambda: np.eye(4))
    T_flange_tcp: np.ndarray = field(default_factory=lambda: np.eye(4))
    signature: tuple | None = None
    reason: str = ""
    other_joints: list = field(default_factory=list)
    assumed_start: bool = False

    def T_frame_tcp_true(self) -> np.ndarray | None:
        """Landing pose in the target's own frame (4, 4) [mm]."""
        if self.T_base_tcp_true is None:
            return None
        return np.linalg.inv(self.T_base_frame) @ self.T_base_tcp_true


def true_robot_of(robot):
    """``(nominal, true, T_world_base_true)`` from a truth file of ``robocal simulate tracker``
    (``*.json``: the hidden true parameters and ``T_tracker_base``) or a robot name/file (true =
    nominal, identity base)."""
    p = Path(str(robot))
    if p.suffix.lower() == ".json" and p.is_file():
        truth = json.loads(p.read_text())
        if "true_parameters" not in truth or "robot" not in truth:
            raise ValueError(f"{p}: not a truth file of robocal simulate (no 'robot' / 'true_parameters')")
        nominal = load_robot(truth["robot"])
        true = nominal.with_params(**{k: float(v) for k, v in truth["true_parameters"].items()})
        return nominal, true, np.asarray(truth.get("T_tracker_base", np.eye(4)), dtype=float)
    nominal = load_robot(robot)
    return nominal, nominal, np.eye(4)


def true_effects_of(robot):
    """``(effects, phases)`` of a truth file written by ``robocal simulate tracker --effects
    realistic`` (its ``campaign_effects``: a :class:`~robocal.sim.campaign_effects.CampaignEffects`
    and the transmission phases (2, n_ctrl) [rad]), or None (ideal campaign, or a robot name/file)."""
    p = Path(str(robot))
    if p.suffix.lower() != ".json" or not p.is_file():
        return None
    entry = json.loads(p.read_text()).get("campaign_effects")
    if not entry:
        return None
    from .campaign_effects import CampaignEffects

    return CampaignEffects.from_truth(entry)


class VirtualController:
    """Executes programs as a nominal-model controller, on a robot that follows ``true_model``.

    nominal, true_model: :class:`~robocal.kinematics.model.RobotModel` with the same joints.
    T_world_base_true: (4, 4) where the true robot's base really is in the cell (e.g. the tracker)
    frame [mm]; T_world_cellbase: (4, 4) the base frame in which the program's coordinates are
    *meant* (e.g. a calibrated robot file's ``[base]``, when the cell's frames were measured in it).
    Landing errors are taken in the cell frame; both default to the identity (the program means the
    true robot's own base frame). true_tool: (4, 4) the tool really on the flange [mm] (default:
    exactly the tool the program declares). true_effects: ``(CampaignEffects, phases (2, n_ctrl)
    [rad])`` of the campaign (:func:`true_effects_of`): the true joints turn by the transmission
    error and the arm has grown by ``growth_ppm`` (as warm as at the campaign's last pose; the
    tracker scale error is in the measurements only); None: the true model alone.
    """

    def __init__(self, nominal, true_model, *, T_world_base_true=None, T_world_cellbase=None, true_tool=None,
                 true_effects=None):
        if tuple(nominal.controller_joints) != tuple(true_model.controller_joints):
            raise ValueError("nominal and true models have different controller joints")
        self.nominal = nominal
        self.true_model = true_model
        self.T_world_base_true = np.eye(4) if T_world_base_true is None else np.asarray(T_world_base_true, float)
        self.T_world_cellbase = np.eye(4) if T_world_cellbase is None else np.asarray(T_world_cellbase, float)
        self.true_tool = None if true_tool is None else np.asarray(true_tool, dtype=float)
        self.true_effects = true_effects

    def true_fk(self, tool, q) -> np.ndarray:
        """Where the true robot takes ``tool`` (4, 4) [mm] at commanded joints ``q`` (n,) [rad]:
        (4, 4) in its world frame [mm], with the campaign's effects when it had any."""
        if self.true_effects is None:
            return with_tool(self.true_model, tool).fk(q)
        from .campaign_effects import grown

        effects, phases = self.true_effects
        q = np.asarray(q, dtype=float)
        q_real = q + effects.transmission_error(q, phases, self.true_model.prismatic_joints).reshape(q.shape)
        T = with_tool(self.true_model, tool).fk(q_real)
        return grown(T, self.true_model.T_world_base, effects.growth_ppm * 1e-6)

    def _order(self, program):
        targets = {t.name.casefold(): t for t in program.targets}
        if program.format == "urscript":
            seq = [targets[n.casefold()] for n, _, _ in urscript_motions(program) if n is not None]
            used = {t.name for t in seq}
            return seq + [t for t in program.targets if t.name not in used]
        return list(program.targets)

    def _start(self, program):
        for t in self._order(program):
            if t.kind == "joint":
                return np.asarray(t.joints, dtype=float)
        lo, hi = self.nominal.limits[:, 0], self.nominal.limits[:, 1]
        return np.clip(np.zeros(self.nominal.n_joints), lo, hi)

    def execute(self, program, *, tool=None, base=None, config_dat=None, q_start=None) -> list:
        """Run ``program`` (a :class:`~robocal.io.programs.Program`); returns one
        :class:`ExecutedTarget` per target (first execution; later ones with other joints in
        ``other_joints``), in the program's target order. tool/base/config_dat: as
        :func:`robocal.io.programs.frames.resolve_frames`."""
        check_program(program, self.nominal)
        frames = resolve_frames(program, tool=tool, base=base, config_dat=config_dat)
        analytic = is_analytic(self.nominal)
        q_cur = self._start(program) if q_start is None else np.asarray(q_start, dtype=float)
        done: dict = {}
        known = q_start is not None or program.format != "urscript"
        for t in self._order(program):
            if t.kind == "joint":
                q, reason = np.asarray(t.joints, dtype=float), ""
                T_tool, T_frame = np.eye(4), np.eye(4)
                if not bool(self.nominal.within_limits(q)):
                    q, reason = None, "joints outside the limits"
            else:
                T_tool, T_frame, _ = frames[t.name]
                nom = with_tool(self.nominal, T_tool)
                q, reason = controller_joints(nom, T_frame @ t.T_frame_tcp, configuration_of(t, program.format), q_cur)
            key = t.name.casefold()
            if key in done:
                if q is not None and done[key].q is not None and np.max(np.abs(q - done[key].q)) > 1e-6:
                    done[key].other_joints.append(q)
            else:
                done[key] = self._landing(t, q, reason, T_tool, T_frame, analytic)
                done[key].assumed_start = not known and t.kind == "cartesian"
            known = known or (t.kind == "joint" and q is not None)
            if q is not None:
                q_cur = q
        return [done[t.name.casefold()] for t in program.targets if t.name.casefold() in done]

    def _landing(self, t, q, reason, T_tool, T_frame, analytic) -> ExecutedTarget:
        out = ExecutedTarget(t.name, t.kind, t.line, q, T_base_frame=T_frame, T_flange_tcp=T_tool, reason=reason)
        if q is None:
            return out
        tool = T_tool if self.true_tool is None or t.kind == "joint" else self.true_tool
        out.T_base_tcp_true = self.true_fk(tool, q)
        out.T_base_tcp_commanded = with_tool(self.nominal, T_tool).fk(q)
        if analytic:
            out.signature = tuple(bool(x) for x in arm_signature(self.nominal, q)[0])
        return out


    def landing_errors(self, executed, intended_program, *, tool=None, base=None, config_dat=None) -> dict:
        """``{name: (position error [mm], rotation error [deg])}`` of where each executed target
        landed against what the same-named target of ``intended_program`` means: a Cartesian
        target its pose (in its frame, with its tool); a joint target where the true robot goes at
        the intended joints (so an unchanged joint target has error 0)."""
        intended = {t.name.casefold(): t for t in intended_program.targets}
        frames = resolve_frames(intended_program, tool=tool, base=base, config_dat=config_dat)
        out = {}
        for e in executed:
            t = intended.get(e.name.casefold())
            if t is None or e.T_base_tcp_true is None or t.kind != e.kind:
                continue
            if t.kind == "cartesian":
                T_tool, T_frame, _ = frames[t.name]
                T_meant = T_frame @ t.T_frame_tcp
            else:
                T_meant = self.true_fk(np.eye(4), np.asarray(t.joints, dtype=float))
                T_meant = self.T_world_base_true @ T_meant
            if t.kind == "cartesian":
                T_meant = self.T_world_cellbase @ T_meant
            T_real = self.T_world_base_true @ e.T_base_tcp_true
            dp = np.linalg.norm(T_real[:3, 3] - T_meant[:3, 3])
            R = T_meant[:3, :3].T @ T_real[:3, :3]
            ang = math.degrees(math.acos(max(-1.0, min(1.0, (np.trace(R) - 1) / 2))))
            out[e.name] = (float(dp), ang)
        return out
