"""Which parameters figaroh's geometric calibration keeps, against robocal's identifiability analysis.

Same problem as ``bench_calibration.py`` (default: ABB IRB 140, 100 poses, one laser-tracker
reflector 60 mm above the flange and off its axis, 0.02 mm noise, seed 2026; base frame and
reflector unknown). figaroh (https://github.com/thanhndv212/figaroh-plus, PyPI ``figaroh``) is set
up as ``bench_calibration.FigarohSetup`` does it: URDF from ``robocal.io.urdf.write_urdf``, unified
YAML configuration (``full_params``, ``universe`` -> ``flange``, x/y/z of one marker measured), CSV
data, ``known_baseframe`` / ``known_tipframe`` False, and its default ``initialize()``: structural
base parameters by pivoted QR on random configurations (``calculate_base_kinematics_regressor``,
``tol_qr=1e-6``), ``add_base_name`` / ``add_pee_name``, then the data-level elimination of
frame-absorbed parameters (``eliminate_absorbed_parameters``, tol 1e-4).

The parametrizations differ: robocal identifies standard-DH parameters (4 per joint), figaroh 6
offsets per joint placement (``d_px_J2`` ... ``d_phiz_J6``), both with the base frame (6) and the
reflector (3). Parameters cannot be matched one to one, so the comparison is on the directions they
move the measurements: both Jacobians (300 rows: x, y, z of 100 points) are evaluated at the same
state (nominal geometry, the benchmark's base and reflector guesses; the two models' predictions
there agree to ~1e-15 m), columns scaled to unit length. A parameter adds an identifiable direction
to a set when its unit column has a component orthogonal to the set's span above a tolerance
(figaroh's own ``select_identifiable_parameters`` criterion, default 1e-4), i.e. the numerical rank
grows by one. The fits then show what the missing directions cost.

Run with an environment that has both robocal and figaroh (figaroh has its own venv, see
benchmarks/README.md)::

    /tmp/figaroh_venv/bin/python benchmarks/figaroh_identifiability.py [--robot abb_irb140] [--seed 2026]
"""

from __future__ import annotations

import argparse
import math
import sys
import tempfile
import warnings
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import bench_calibration as bc  # noqa: E402  (sets one thread before numpy is imported)
import numpy as np  # noqa: E402

from robocal.calib import solve  # noqa: E402

TOL = 1e-4  # figaroh's default for select_identifiable_parameters / eliminate_absorbed_parameters
RANK_TOL = 1e-6  # relative singular-value threshold for the numerical rank (robocal's QR tolerance)


def unit(A):
    n = np.linalg.norm(A, axis=0)
    return A / np.where(n > 0, n, 1.0)


def rank(A):
    """Numerical rank of the column-scaled matrix and its singular values."""
    if A.shape[1] == 0:
        return 0, np.zeros(0)
    s = np.linalg.svd(unit(A), compute_uv=False)
    return int(np.sum(s > RANK_TOL * s[0])), s


def orth(A, v):
    """Norm of the part of unit(v) orthogonal to the span of A's (scaled) columns."""
    v = v / np.linalg.norm(v)
    if A.shape[1] == 0:
        return 1.0
    U, s, _ = np.linalg.svd(unit(A), full_matrices=False)
    U = U[:, s > RANK_TOL * s[0]]
    return float(np.linalg.norm(v - U @ (U.T @ v)))


def table(header, rows):
    w = [max(len(str(x)) for x in col) for col in zip(header, *rows)]
    line = "  ".join(f"{h:<{k}}" for h, k in zip(header, w)).rstrip()
    print(line)
    print("-" * len(line))
    for r in rows:
        print("  ".join(f"{str(x):<{k}}" for x, k in zip(r, w)).rstrip())


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--robot", default="abb_irb140")
    ap.add_argument("--poses", type=int, default=100)
    ap.add_argument("--seed", type=int, default=2026)
    args = ap.parse_args(argv)
    warnings.simplefilter("ignore", category=RuntimeWarning)
    if bc.load_figaroh() is None:
        print(f"figaroh: {bc.FIGAROH_WHY}")
        return 1
    import pinocchio as pin
    from figaroh.calibration.calibration_tools import measurement_jacobian, select_identifiable_parameters
    from figaroh.calibration.parameter import BASE_TPL

    sc = bc.Scenario(args.robot, args.poses, args.seed)
    N = args.poses

    # ------------------------------------------------------------------ robocal
    full = sc.problem()  # every model parameter free, base 6, reflector 3
    rep = solve(full).identifiability
    rc_kept = list(rep.identifiable)
    geom = [n for n in full.free_params if n in set(rc_kept)]
    prob = sc.problem(free=geom)
    res = solve(prob)
    rc_std = dict(zip(res.names, res.std))
    rc_val = dict(zip(res.names, res.values - res.initial))
    _, Jp = full.predict_points(full.initial_state(), jacobian=True)  # (N, 1, 3, n) [mm per mm|rad]
    Jr = np.transpose(Jp[:, 0], (1, 0, 2)).reshape(3 * N, -1)  # rows component-major, as figaroh's
    rcol = {n: Jr[:, i] for i, n in enumerate(full.names)}

    # ------------------------------------------------------------------ figaroh
    tmp = tempfile.TemporaryDirectory(prefix="robocal_figaroh_ident_")
    fs = bc.FigarohSetup(sc, tmp.name)
    c = fs.calibration()
    c.initialize()
    cfg = c.calib_config
    fg_kept = list(cfg["param_name"])
    cands = fs.candidates(c)
    nonzero = set(cfg["base_mapping_param_names"])  # structural regressor columns kept (norm^2 >= 1e-6)
    struct_base = list(cfg["base_mapping_row_names_full"])  # structural QR base parameters
    renamed = struct_base[:len(BASE_TPL)]  # add_base_name: the first 6 become base_px ... base_phiz
    absorbed = list(cfg.get("absorbed_param_name", []))

    def stage(n):
        if n in fg_kept:
            return "kept"
        if n.startswith("base_") or n.startswith("pEE"):
            return "kept"
        if n not in nonzero:
            return "structural: zero column (tool-frame origin, position rows)"
        if n in renamed:
            return "add_base_name: renamed to " + BASE_TPL[renamed.index(n)]
        if n not in struct_base:
            return "structural QR: dependent"
        if n in absorbed:
            return "data level: absorbed by frames"
        return "?"

    # common state: robocal's start (nominal, base0, point0) in figaroh's variables
    x = dict.fromkeys(cands, 0.0)
    B0 = sc.base0
    x.update(zip(BASE_TPL, np.r_[B0[:3, 3] / 1000.0, pin.rpy.matrixToRpy(B0[:3, :3])]))
    x.update(zip(["pEEx_1", "pEEy_1", "pEEz_1"], np.asarray(sc.point0, float) / 1000.0))
    xv = np.array([x[n] for n in cands])
    cfg_all = dict(cfg, param_name=cands)
    P = 1000.0 * bc_points(fs, c, xv, cfg_all)
    agree = float(np.abs(P - full.predict_points(full.initial_state())[:, 0]).max())
    Jf = measurement_jacobian(c.model, c.data, xv, c.q_measured, cfg_all)  # (3N, 45) [m per m|rad]
    fcol = {n: Jf[:, i] for i, n in enumerate(cands)}

    def F(names):
        return np.column_stack([fcol[n] for n in names]) if names else np.zeros((3 * N, 0))

    def R(names):
        return np.column_stack([rcol[n] for n in names]) if names else np.zeros((3 * N, 0))

    r_fall, s_fall = rank(F(cands))
    r_rall, _ = rank(R(list(full.names)))
    r_fk, _ = rank(F(fg_kept))
    r_rk, _ = rank(R(rc_kept))
    r_union, _ = rank(np.c_[F(fg_kept), R(rc_kept)])
    r_everything, _ = rank(np.c_[F(cands), R(list(full.names))])
    frames = [n for n in cands if n.startswith("base_") or n.startswith("pEE")]
    own_all, _ = select_identifiable_parameters(Jf, cands, always_keep=frames, tol=TOL)
    own_all7, _ = select_identifiable_parameters(Jf, cands, always_keep=frames, tol=1e-7)

    print("figaroh vs robocal: identifiable parameters")
    print(f"  problem: {sc.nominal.name}, {N} poses, one reflector {np.round(sc.tracker.reflectors[0], 1)} mm on the "
          f"flange, noise {bc.SIGMA_MM} mm, seed {args.seed}; figaroh {bc.peer_version('figaroh')}, "
          f"pinocchio {bc.peer_version('pin')}")
    print(f"  both models at robocal's start state: predictions agree to {agree:.1e} mm; Jacobians 3N = {3 * N} rows; "
          f"numerical rank: singular values of unit columns > {RANK_TOL:g} x the largest")
    print(f"  complete set (figaroh's {len(cands)} candidates): singular values around the rank: "
          f"{' '.join(f'{v:.1e}' for v in s_fall[r_fall - 2:r_fall + 2])}")
    print()
    n_fj = sum(1 for n in fg_kept if n.startswith("d_"))
    n_rj = len(geom)
    table(["", "candidates", "kept", "rank", "geometry + base + reflector"], [
        ["figaroh parametrization, all candidates", len(cands), "-", r_fall, f"{len(cands) - 9} + 6 + 3"],
        ["robocal DH, all candidates", len(full.names), "-", r_rall, f"{len(full.free_params)} + 6 + 3"],
        ["figaroh default selection (structural + absorbed)", len(cands), len(fg_kept), r_fk, f"{n_fj} + 6 + 3"],
        ["robocal analyse_identifiability (solve().identifiability)", len(full.names), len(rc_kept), r_rk,
         f"{n_rj} + 6 + 3"],
        ["union of the two kept sets", "", "", r_union, ""],
        ["union of all candidates of both", "", "", r_everything, ""],
        [f"figaroh select_identifiable_parameters on all {len(cands)} (tol {TOL:g})", len(cands), len(own_all),
         rank(F(own_all))[0], "not figaroh's default path"],
        ["  same, tol 1e-7 (estimation.method != structural)", len(cands), len(own_all7), rank(F(own_all7))[0], ""],
    ])
    print()
    print(f"robocal identifiable parameters that add a direction to figaroh's kept set (|orth| > {TOL:g}):")
    rows = []
    for n in rc_kept:
        o = orth(F(fg_kept), rcol[n])
        if o > TOL:
            unit_s = "urad" if full.units[full.names.index(n)] == "rad" else "mm"
            k, fmt = (1e6, ".1f") if unit_s == "urad" else (1.0, ".4f")
            rows.append([n, f"{o:.3f}", f"{rank(np.c_[F(fg_kept), rcol[n]])[0] - r_fk:+d}",
                         f"{k * rc_val[n]:+{fmt}} {unit_s}", f"{k * rc_std[n]:{fmt}} {unit_s}",
                         f"{abs(rc_val[n]) / rc_std[n]:.0f}"])
    if rows:
        table(["robocal", "|orth| vs figaroh kept", "rank +", "estimate - nominal", "std", "|est|/std"], rows)
        both = [r[0] for r in rows]
        print(f"  all {len(both)} together: rank {r_fk} -> {rank(np.c_[F(fg_kept), R(both)])[0]}")
    else:
        print("  none")
    print()
    print("figaroh candidates its default selection leaves out, why, and whether they are identifiable on these data:")
    rows = []
    for n in cands:
        if n in fg_kept:
            continue
        o = orth(F(fg_kept), fcol[n])
        rows.append([n, stage(n), f"{o:.1e}", "IDENTIFIABLE (dropped)" if o > TOL else "dependent"])
    table(["figaroh", "dropped at", "|orth| vs kept", "verdict"], rows)
    extra = fs.dropped_identifiable(c)  # figaroh's own test, kept set always kept
    print(f"  figaroh's own select_identifiable_parameters(kept always kept, tol {TOL:g}) adds back: "
          f"{' '.join(extra) or '-'} (rank {r_fk} -> {rank(F(fg_kept + extra))[0]})")
    print()
    print("all of robocal's kept parameters inside figaroh's complete span: "
          f"{'yes' if all(orth(F(cands), rcol[n]) < TOL for n in rc_kept) else 'NO'}; "
          "figaroh parameters (kept + restored) outside robocal's identifiable span (directions DH cannot express):")
    out = [(n, orth(R(rc_kept), fcol[n])) for n in fg_kept + extra]
    out = [(n, o) for n, o in out if o > TOL]
    print("  " + (", ".join(f"{n} (|orth| {o:.3f})" for n, o in out) or "none")
          + f"; rank of the union of robocal's kept and figaroh's complete span: {r_everything}")

    # ------------------------------------------------------------------ what it costs: the fits
    print()
    qv = sc.vr.random_configurations(1000, np.random.default_rng(args.seed + 1), margin=0.1)
    true_v = sc.tracker.true_points(sc.vr, qv)[:, 0]
    zeros = np.zeros(len(qv), int)
    e_rc = np.linalg.norm(prob.predict_points(res.state, q=qv, stations=zeros)[:, 0] - true_v, axis=1)
    rows = [[f"robocal solve (DH, {prob.n_variables} variables)", prob.n_variables, f"{res.rms_after:.4f}",
             f"{np.sqrt(np.mean(e_rc ** 2)):.4f}", f"{e_rc.max():.4f}", f"{res.rank}"]]
    fits = {}
    for label, ex in (("figaroh default selection", ()), ("figaroh + the dropped identifiable", tuple(extra))):
        cc, r, calls = fs.run(ex)
        pts = fs.points_mm(cc, r.x)
        rms = float(np.sqrt(np.mean(np.sum((pts - sc.points[:, 0]) ** 2, axis=1))))
        ev = np.linalg.norm(fs.points_mm(cc, r.x, qv) - true_v, axis=1)
        rk = rank(np.asarray(r.jac))[0]
        rows.append([f"{label} ({len(r.x)} variables)", len(r.x), f"{rms:.4f}", f"{np.sqrt(np.mean(ev ** 2)):.4f}",
                     f"{ev.max():.4f}", f"{rk}"])
        fits[label] = (cc, r)
    print(f"fits on the same data (noise alone gives a fit RMS of ~{math.sqrt(3) * bc.SIGMA_MM:.4f} mm):")
    table(["fit", "variables", "fit RMS mm", "1000 fresh poses RMS mm", "max mm", "rank of final J"], rows)
    cc, r = fits["figaroh + the dropped identifiable"]
    names = list(cc.calib_config["param_name"])
    if extra:
        print("  the restored figaroh parameters in that fit (figaroh's own calc_stddev):")
        print("  " + ", ".join(
            f"{n} = {r.x[names.index(n)] * 1e6:+.1f} +- {cc.std_dev[names.index(n)] * 1e6:.1f} "
            f"{'urad' if 'phi' in n else 'um'}" for n in extra))
    tmp.cleanup()
    return 0


def bc_points(fs, c, xv, cfg_all):
    """(N, 3) predicted points [m] of figaroh's model with the variables ``xv`` named by ``cfg_all``."""
    from figaroh.calibration.calibration_tools import calc_updated_fkm

    cfg = dict(cfg_all, NbSample=len(c.q_measured))
    return calc_updated_fkm(c.model, c.data, xv, c.q_measured, cfg).reshape(3, -1).T


if __name__ == "__main__":
    sys.exit(main())
