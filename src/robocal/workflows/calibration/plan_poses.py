"""``robocal plan-poses``: measurement poses for a calibration, chosen and written as a joint program.

Random candidate configurations within the joint limits (seeded), kept if they are feasible in the
cell (docs/cells.md: no link or tool below the mounting plane, in a box or in another link; with an
instrument, the reflector in range, within its acceptance angle and in sight) and the flange lies
in the workspace box; then D-optimal selection and the first-order prediction of
:func:`robocal.calib.plan.plan_campaign`, ordered for a short path of feasible moves. The poses go to
a ``robocal-program/1`` joint file (degrees) a user can load or convert.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ...calib.cell import Cell, Instrument, default_cell, feasible, nearest_equivalent, order_poses, path_feasible, \
    path_length
from ...calib.plan import _jacobian_at, plan_campaign
from ...io.cell_file import read_cell
from ...io.programs import JointProgram, write_joint_program
from ...robots import load_robot

__all__ = ["candidate_poses", "parse_box", "plan_poses", "plan_cell", "d_efficiency"]


def parse_box(text: str) -> np.ndarray:
    """``"xmin,xmax,ymin,ymax,zmin,zmax"`` [mm] -> (3, 2)."""
    try:
        v = np.array([float(x) for x in str(text).replace(";", ",").split(",")], dtype=float)
    except ValueError:
        raise ValueError(f"--workspace: expected six numbers xmin,xmax,ymin,ymax,zmin,zmax [mm], got {text!r}") from None
    if v.shape != (6,) or np.any(v[1::2] <= v[::2]):
        raise ValueError(f"--workspace: expected xmin,xmax,ymin,ymax,zmin,zmax [mm] with min < max, got {text!r}")
    return v.reshape(3, 2)


def plan_cell(model, cell=None, tracker_at=None, tool=None):
    """The :class:`~robocal.calib.cell.Cell` of a plan: the cell file ``cell`` (path or Cell) or the
    default floor cell; ``tracker_at`` (3,) [mm, robot base frame] sets the instrument (keeping the
    cell's acceptance angle and range), ``tool`` (3,) [mm, flange frame] the reflector."""
    from dataclasses import replace

    if cell is None:
        cell = default_cell()
    elif not isinstance(cell, Cell):
        cell = read_cell(cell, model)
    if tool is not None:
        cell = cell.with_tool(tool)
    if tracker_at is not None:
        pos = cell.T_cell_base[:3, :3] @ np.asarray(tracker_at, dtype=float) + cell.T_cell_base[:3, 3]
        ins = Instrument(tuple(pos)) if cell.instrument is None else replace(cell.instrument, position=tuple(pos))
        cell = cell.with_instrument(ins)
    return cell


def plan_poses(robot, out_file, *, count: int, candidates: int = 1000, workspace=None, tracker_at=None,
               tool=None, sigma_mm: float = 0.02, seed: int = 0, margin: float = 0.05,
               overwrite: bool = False, cell=None, language=None) -> dict:
    """Plan ``count`` poses of ``robot`` out of ``candidates`` feasible ones and write them to ``out_file``.

    workspace: (3, 2) box [mm] in the robot base frame for the flange; tracker_at: (3,) [mm] the
    instrument in the robot base frame (line of sight, range, acceptance angle); tool: reflector in
    the flange frame [mm] (default: the cell's, else (0, 0, 100)); sigma_mm: instrument noise per
    coordinate; cell: cell file or :class:`~robocal.calib.cell.Cell` (default: floor-mounted, the
    floor an obstacle). Every candidate is feasible in the cell; the chosen poses are ordered for a
    short path whose every move is checked (a pose no feasible move reaches is replaced).
    Returns the plan (:func:`~robocal.calib.plan.plan_campaign`) plus ``q`` (count, n) in driving
    order, ``n_candidates``, ``draws`` (random poses drawn), ``d_efficiency`` (D-optimality of the
    plan relative to the plan from as many candidates without the cell), ``path_rad`` (largest
    joint move summed over the path, and ``path_rad_unordered``), ``file``.
    """
    if language is not None:  # refuse before any work
        from ...io.programs.campaign import CAMPAIGN_LANGUAGES

        suffixes = [CAMPAIGN_LANGUAGES.get(language, ("", ""))[1]] + ([".src"] if language == "krl" else [])
        if any(sx and Path(out_file).with_suffix(sx).resolve() == Path(out_file).resolve() for sx in suffixes):
            raise ValueError(f"--out {out_file}: the joint table and the {language} program would be the same file")
        if not overwrite:
            for sx in suffixes:
                if Path(out_file).with_suffix(sx).exists():
                    raise FileExistsError(f"{Path(out_file).with_suffix(sx)}: file exists; pass --overwrite to replace it")
    if cell is not None and not isinstance(cell, Cell):
        outs = [Path(out_file)] + ([Path(out_file).with_suffix(sx) for sx in suffixes] if language else [])
        if any(o.resolve() == Path(cell).resolve() for o in outs):
            raise ValueError(f"--out {out_file}: would replace the cell file {cell} (an input of this command)")
    from ...io.output_paths import check_outputs

    check_outputs(out_file, {"the robot file": robot, "the cell file": cell if not isinstance(cell, Cell) else None},
                  overwrite=overwrite)
    model = load_robot(robot)
    cell = plan_cell(model, cell, tracker_at, tool)
    out = plan_in_cell(model, cell, count=count, candidates=candidates, workspace=workspace, sigma_mm=sigma_mm,
                       seed=seed, margin=margin)
    names = tuple(f"P{i + 1:03d}" for i in range(count))
    prog = JointProgram(out["q"], names, tuple(model.controller_joints), {"angle_unit": "deg"})
    note = (f"robocal plan-poses: {count} of {out['n_candidates']} feasible candidates (seed {seed}, cell: "
            f"{cell.source}), D-optimal, in driving order; predicted held-out RMS {out['holdout_rms_mm']:.4f} mm at "
            f"{sigma_mm} mm noise")
    out["file"] = write_joint_program(out_file, prog, model, overwrite=overwrite, metadata={"note": note})
    if language is not None:
        from ...io.programs.campaign import write_campaign_program

        out["program_files"] = write_campaign_program(out_file, language, out["q"], names, overwrite=overwrite,
                                                      prismatic=model.prismatic_joints)
    return out


def plan_in_cell(model, cell, *, count: int, candidates: int, workspace=None, sigma_mm: float = 0.02, seed: int = 0,
                 margin: float = 0.05, efficiency: bool = True) -> dict:
    """The plan of :func:`plan_poses` for ``model`` in ``cell`` (no file written)."""
    tool = tuple(cell.reflector_mm)
    qk, draws = candidate_poses(model, count, candidates, seed, workspace=workspace, cell=cell, margin=margin)
    lim = cell.limits(model)
    qk = nearest_equivalent(qk, lim.mean(axis=1), lim, ~model.prismatic_joints)  # same poses, mid-range angles
    excluded = np.flatnonzero(~reachable_from_hub(cell, model, qk)).tolist()
    for _ in range(10):
        usable = np.setdiff1d(np.arange(len(qk)), excluded)
        if len(usable) < count:
            raise ValueError(f"only {len(usable)} of {len(qk)} candidates can be joined by feasible moves; need "
                             f"{count}: more --candidates or a roomier cell")
        plan = plan_campaign(model, qk[usable], count, tool=tool, sigma_mm=sigma_mm)
        chosen_idx = usable[plan["indices"]]
        driven, order, left = order_poses(cell, model, qk[chosen_idx])
        if not len(left):
            break
        excluded.extend(chosen_idx[left].tolist())
    else:
        raise ValueError("could not join the planned poses by feasible moves after 10 re-plans: a roomier cell")
    eff = float("nan")
    if efficiency:
        rng = np.random.default_rng(seed)
        lim = cell.limits(model)
        span = lim[:, 1] - lim[:, 0]
        q_free = rng.uniform(lim[:, 0] + margin * span, lim[:, 1] - margin * span, (len(qk), model.n_joints))
        eff = d_efficiency(model, qk[chosen_idx], q_free, count, tool=tool)
    return {**plan, "indices": chosen_idx[order], "q": driven, "n_candidates": len(qk), "draws": draws,
            "model": model, "cell": cell, "d_efficiency": eff, "candidates_q": qk,
            "path_rad": path_length(driven), "path_rad_unordered": path_length(qk[chosen_idx])}


def reachable_from_hub(cell, model, q) -> np.ndarray:
    """(M,) bool: the candidate ``q`` (M, n) is joined by a feasible move to the hub, the candidate
    nearest the middle of the joint ranges: a candidate set where every pose reaches every other one
    (through the hub at worst), so an ordered path exists."""
    lim = cell.limits(model)
    hub = q[np.argmin(np.max(np.abs(q - lim.mean(axis=1)), axis=1))]
    return path_feasible(cell, model, hub, q)


def d_efficiency(model, q_plan, q_free_candidates, count: int, *, tool) -> float:
    """D-efficiency (det ratio to the power 1/p) of the plan ``q_plan`` against the D-optimal plan of
    ``count`` poses from ``q_free_candidates`` (no cell): 1.0 = nothing lost, 0.8 = each
    identifiable direction 20 % less informed (geometric mean)."""
    free = plan_campaign(model, q_free_candidates, count, tool=tool)
    at = free["typical"]  # both plans judged at the same typical robot (calib.plan.calibration_identifiability)
    cols = [at[0].names.index(n) for n in free["identifiable"]]
    Jf = _jacobian_at(at, q_free_candidates[free["indices"]])[..., cols].reshape(-1, len(cols))
    Jp = _jacobian_at(at, np.asarray(q_plan, dtype=float))[..., cols].reshape(-1, len(cols))
    scale = np.linalg.norm(Jf, axis=0)
    ld = [np.linalg.slogdet((J / scale).T @ (J / scale)) for J in (Jp, Jf)]
    if ld[0][0] <= 0:
        return 0.0
    return float(np.exp((ld[0][1] - ld[1][1]) / len(cols)))


def candidate_poses(model, count: int, candidates: int, seed: int, *, workspace=None, cell=None,
                    margin: float = 0.05, max_draws: int = 400000) -> tuple[np.ndarray, int]:
    """The candidate configurations (M, n) of :func:`plan_poses` and the number of random draws:
    seeded uniform draws within the cell's joint ranges (``margin`` of each range kept free) until
    ``candidates`` are feasible in ``cell`` (:func:`~robocal.calib.cell.feasible`) with the flange in
    the ``workspace`` box; a clear error when fewer than ``count`` are found in ``max_draws``."""
    if count < 1 or candidates < count:
        raise ValueError(f"--count must be at least 1 and at most --candidates ({candidates}), got {count}")
    cell = default_cell() if cell is None else cell
    rng = np.random.default_rng(seed)
    lim = cell.limits(model)
    lo, hi = lim[:, 0], lim[:, 1]
    span = hi - lo
    kept, n_kept, draws = [], 0, 0
    batch = max(2000, int(candidates))
    while n_kept < candidates and draws < max_draws:
        q = rng.uniform(lo + margin * span, hi - margin * span, (batch, model.n_joints))
        draws += batch
        keep = feasible(cell, model, q)
        if workspace is not None:
            box = np.asarray(workspace, dtype=float)
            T = model.replace(T_world_base=np.eye(4)).fk(q)
            keep &= np.all((T[:, :3, 3] >= box[:, 0]) & (T[:, :3, 3] <= box[:, 1]), axis=1)
        kept.append(q[keep])
        n_kept += int(keep.sum())
    if n_kept < count:
        raise ValueError(f"only {n_kept} of {draws} random poses are feasible in the cell ({cell.source})"
                         f"{' with the flange inside the workspace box' if workspace is not None else ''}; need "
                         f"{count}: a larger box, another tracker position or a roomier cell")
    return np.vstack(kept)[:candidates], draws
