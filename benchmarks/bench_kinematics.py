"""Kinematics speed benchmark: robocal against plain numpy and Pinocchio, side by side.

Run from the repository root (robocal installed in the environment; Pinocchio from the
``bench`` extra: ``pip install -e .[bench]``)::

    python benchmarks/bench_kinematics.py            # full run (a few minutes)
    python benchmarks/bench_kinematics.py --quick    # smaller sizes, fewer repeats

This is a script, not a test: it prints machine information, correctness checks (the same robot
in robocal and in Pinocchio, built from robocal's URDF export) and one table. Every figure is
the median (and the minimum) of several repeats, all in the same process and on one thread.
See benchmarks/README.md for what each row measures.
"""

from __future__ import annotations

import os

# One thread everywhere, set before numpy / numba / pinocchio are imported.
for _var in ("OMP_NUM_THREADS", "NUMBA_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS",
             "VECLIB_MAXIMUM_THREADS", "NUMEXPR_NUM_THREADS"):
    os.environ[_var] = "1"
# Kernel speed is measured: the compiled kernels from the first call (not numpy until the work pays).
os.environ.setdefault("ROBOCAL_KERNELS", "compiled")

import argparse  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import timeit  # noqa: E402
from pathlib import Path  # noqa: E402

import numba  # noqa: E402
import numpy as np  # noqa: E402
from _machine import machine_info as _machine_info  # noqa: E402  (benchmarks/_machine.py)

from robocal.io.urdf import write_urdf  # noqa: E402
from robocal.robots import load_robot  # noqa: E402

try:
    import pinocchio as pin
except ImportError:  # pragma: no cover - optional peer
    pin = None

try:
    import roboticstoolbox as rtb
except ImportError:  # pragma: no cover - optional peer, deliberately not installed (heavy)
    rtb = None

TARGET_BATCH = 5.0e6  # poses/s, one thread
TARGET_SINGLE = 1.5  # us per call
TARGET_IDJAC = 0.3  # ms for 100 poses x 30 parameters


# ---------------------------------------------------------------------------- helpers
def machine_info() -> list[str]:
    return _machine_info([
        f"numba       {numba.__version__}  (NUMBA_NUM_THREADS={os.environ['NUMBA_NUM_THREADS']})",
        f"pinocchio   {pin.__version__ if pin else 'not installed'}",
        f"rtb         {rtb.__version__ if rtb else 'not installed (skipped)'}",
    ])


def calibrate_number(fn, budget: float) -> int:
    """Loops per repeat so that one repeat takes about ``budget`` seconds."""
    n = 1
    while True:
        t = timeit.Timer(fn).timeit(number=n)
        if t > 0.02 or n >= 1 << 20:
            return max(1, int(budget * n / max(t, 1e-9)))
        n *= 4


def random_q(model, n, rng) -> np.ndarray:
    lo = np.maximum(model.limits[:, 0], -np.pi)
    hi = np.minimum(model.limits[:, 1], np.pi)
    return np.ascontiguousarray(rng.uniform(lo, hi, size=(n, model.n_joints)))


def pin_model(model, tmp: Path):
    """The same robot in Pinocchio, through robocal's URDF export (metres)."""
    path = write_urdf(model, tmp / f"{model.name}.urdf", overwrite=True)
    pm = pin.buildModelFromUrdf(str(path))
    return pm, pm.createData()


def pin_pose_mm(pm, pd, q) -> np.ndarray:
    pin.forwardKinematics(pm, pd, q)
    T = pd.oMi[pm.njoints - 1].homogeneous.copy()
    T[:3, 3] *= 1000.0
    return T


# ---------------------------------------------------------------------------- peers
def dh_table(model):
    """(theta0, d, a, alpha) per joint of a standard-DH serial robot, for the naive numpy FK."""
    if model.kind != "dh" or not model.is_serial or not np.array_equal(model.coupling, np.eye(model.n_joints)):
        raise ValueError("the naive numpy FK handles plain serial standard-DH robots only")
    for M in (model.T_world_base, model.end_effectors[0].T_link_ee):
        if not np.allclose(M, np.eye(4)):
            raise ValueError("the naive numpy FK assumes identity base and flange frames")
    return [(L.params["theta"], L.params["d"], L.params["a"], L.params["alpha"]) for L in model.links]


def numpy_dh_fk(q, table) -> np.ndarray:
    """Naive vectorized FK: build the n DH matrices (N, 4, 4) with numpy, chain them with ``@``."""
    N = q.shape[0]
    T = None
    for i, (theta0, d, a, alpha) in enumerate(table):
        th = q[:, i] + theta0
        ct, st = np.cos(th), np.sin(th)
        ca, sa = np.cos(alpha), np.sin(alpha)
        A = np.zeros((N, 4, 4))
        A[:, 0, 0] = ct
        A[:, 0, 1] = -st * ca
        A[:, 0, 2] = st * sa
        A[:, 0, 3] = a * ct
        A[:, 1, 0] = st
        A[:, 1, 1] = ct * ca
        A[:, 1, 2] = -ct * sa
        A[:, 1, 3] = a * st
        A[:, 2, 1] = sa
        A[:, 2, 2] = ca
        A[:, 2, 3] = d
        A[:, 3, 3] = 1.0
        T = A if T is None else T @ A
    return T


def pin_loop_fk(pm, pd, Q) -> np.ndarray:
    """Pinocchio from Python: forwardKinematics per configuration, pose copied into an array."""
    out = np.zeros((len(Q), 4, 4))
    out[:, 3, 3] = 1.0
    j = pm.njoints - 1
    fk = pin.forwardKinematics
    oMi = pd.oMi
    for i, q in enumerate(Q):
        fk(pm, pd, q)
        M = oMi[j]
        out[i, :3, :3] = M.rotation
        out[i, :3, 3] = M.translation
    out[:, :3, 3] *= 1000.0  # m -> mm, as robocal
    return out


def fd_identification_jacobian(model, q, point, h=1e-6) -> np.ndarray:
    """Forward differences of the world point over every parameter: with_params + fk, (N, 3, P)."""
    p0 = model.params.values
    T0 = model.fk(q)
    x0 = T0[:, :3, :3] @ point + T0[:, :3, 3]
    J = np.empty((len(q), 3, len(p0)))
    for j in range(len(p0)):
        v = p0.copy()
        v[j] += h
        T = model.with_params(v).fk(q)
        J[:, :, j] = (T[:, :3, :3] @ point + T[:, :3, 3] - x0) / h
    return J


# ---------------------------------------------------------------------------- main
def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="smaller sizes and fewer repeats (a smoke run)")
    ap.add_argument("--repeat", type=int, default=None, help="repeats per figure (default 7, quick 3)")
    args = ap.parse_args(argv)

    repeat = args.repeat or (3 if args.quick else 7)
    n_batch = 20_000 if args.quick else 100_000
    n_pin = 2_000 if args.quick else 20_000
    single_budget = 0.05 if args.quick else 0.2  # seconds per repeat of a single-call figure
    rng = np.random.default_rng(20240501)

    print("robocal kinematics benchmark" + ("  [--quick]" if args.quick else ""))
    for line in machine_info():
        print("  " + line)
    print(f"  repeats     {repeat} per figure (median and min reported); one thread")
    print()

    ur = load_robot("ur10")
    kuka = load_robot("kuka_kr150_r3100")
    Qb = random_q(ur, n_batch, rng)
    q1 = np.ascontiguousarray(Qb[0])
    Qk = random_q(kuka, 100, rng)

    # ---- warm-up (numba JIT / cache load) before any timing
    ur.fk(Qb[:10])
    ur.fk(q1)
    ur.fk_single(q1)
    ur.fk_single(q1, np.empty((4, 4)))
    kuka.identification_jacobian(Qk, points=[0.0, 0.0, 0.0])
    kuka.identification_jacobian(Qk)

    # ---- correctness checks (printed) before timing
    print("checks (max abs difference; positions mm, rotation matrix entries):")
    table = dh_table(ur)
    ref = ur.fk(Qb[:1000])
    d = numpy_dh_fk(Qb[:1000], table) - ref
    print(f"  UR10  numpy DH chain vs robocal fk            pos {np.abs(d[:, :3, 3]).max():.2e}  rot {np.abs(d[:, :3, :3]).max():.2e}")
    d = np.array([ur.fk_single(q) for q in Qb[:1000]]) - ref
    print(f"  UR10  robocal fk_single vs fk                 pos {np.abs(d[:, :3, 3]).max():.2e}  rot {np.abs(d[:, :3, :3]).max():.2e}")
    pins = {}
    if pin is not None:
        with tempfile.TemporaryDirectory() as tmp:
            for model, Q in ((ur, Qb[:1000]), (kuka, Qk)):
                pm, pd = pin_model(model, Path(tmp))
                pins[model.name] = (pm, pd)
                fid = pm.getFrameId(model.end_effectors[0].name)
                P_joint = np.array([pin_pose_mm(pm, pd, q) for q in Q])
                P_frame = []
                for q in Q:
                    pin.framesForwardKinematics(pm, pd, q)
                    T = pd.oMf[fid].homogeneous.copy()
                    T[:3, 3] *= 1000.0
                    P_frame.append(T)
                R = model.fk(Q)
                for what, P in ((f"oMi[{pm.njoints - 1}]", P_joint), ("oMf[flange]", np.array(P_frame))):
                    d = P - R
                    label = "UR10" if model is ur else "KUKA"
                    print(f"  {label:5s} Pinocchio {what:12s} vs robocal fk (x1000) "
                          f"pos {np.abs(d[:, :3, 3]).max():.2e}  rot {np.abs(d[:, :3, :3]).max():.2e}"
                          f"  ({len(Q)} random q)")
                    if np.abs(d[:, :3, 3]).max() > 1e-6 or np.abs(d[:, :3, :3]).max() > 1e-9:
                        print("ERROR: Pinocchio and robocal disagree; not timing a different robot", file=sys.stderr)
                        return 1
    else:
        print("  Pinocchio not installed (pip install -e .[bench]): its rows are skipped")
    Jp = kuka.identification_jacobian(Qk, points=[0.0, 0.0, 0.0])
    Jfd = fd_identification_jacobian(kuka, Qk, np.zeros(3))
    print(f"  KUKA  identification_jacobian vs forward differences (h=1e-6): {np.abs(Jp - Jfd).max():.2e} "
          f"(entries up to {np.abs(Jp).max():.0f}; truncation + rounding of the differences)")
    print()

    rows = []  # (section, name, median, best, unit, ratio text, target text)
    nan = float("nan")

    def run_section(section, cases, unit, ref, ratio_label, targets):
        """Time ``cases`` [(name, fn, calls per repeat, items per call)] interleaved: one repeat of
        each in turn, so a change in machine load hits every row alike. Adds one row per case:
        median and best over the repeats, the ratio of its median time per item to ``ref``'s, and
        the target check of ``targets[name] = (passes(median value), text)``."""
        per_item = {c[0]: [] for c in cases}
        for _ in range(repeat):
            for name, fn, number, items in cases:
                per_item[name].append(timeit.Timer(fn).timeit(number=number) / number / items)
        med = {name: float(np.median(t)) for name, t in per_item.items()}
        to_unit = {"poses/s": lambda t: 1.0 / t, "us": lambda t: t * 1e6, "ms": lambda t: t * 1e3}[unit]
        for name, *_ in cases:
            v = to_unit(np.array(per_item[name]))
            best = float(v.max() if unit == "poses/s" else v.min())
            ratio = "" if name == ref or name in targets else f"{ratio_label} x{med[name] / med[ref]:.1f}"
            target = ""
            if name in targets:
                passes, text = targets[name]
                target = ("ok   " if passes(float(np.median(v))) else "MISS ") + text
            rows.append((section, name, float(np.median(v)), best, unit, ratio, target))

    def calibrated(name, fn, items=1, budget=single_budget):
        return (name, fn, calibrate_number(fn, budget), items)

    # ---- 1. batched FK (poses/s; ratios compare the time per pose)
    sec = f"1. batched FK, UR10, N={n_batch:,}"
    rc = "robocal fk"
    cases = [calibrated(rc, lambda: ur.fk(Qb), n_batch),
             ("numpy DH matrices + @ chain", lambda: numpy_dh_fk(Qb, table), 1, n_batch)]
    if pin is not None:
        pm, pd = pins["ur10"]
        Qp = Qb[:n_pin]
        cases.append((f"Pinocchio python loop ({n_pin:,}, extrapolated)", lambda: pin_loop_fk(pm, pd, Qp), 1, n_pin))
    skipped = "roboticstoolbox: not installed (heavy; not a robocal dependency), skipped"
    if rtb is not None:
        try:
            ets = rtb.models.DH.UR10().ets()
            Qr = Qb[:n_pin]
            ets.eval(Qr[:2])
            cases.append((f"roboticstoolbox ETS.eval ({n_pin:,})", lambda: ets.eval(Qr), 1, n_pin))
            skipped = None
        except Exception as exc:  # API differences between rtb versions
            skipped = f"roboticstoolbox: skipped ({type(exc).__name__}: {exc})"
    run_section(sec, cases, "poses/s", rc, "robocal",
                {rc: (lambda v: v >= TARGET_BATCH, f">= {TARGET_BATCH / 1e6:g} M poses/s")})
    if skipped:
        rows.append((sec, skipped, nan, nan, "", "", ""))

    # ---- 2. single-call latency (us)
    sec = "2. single-call FK latency, UR10"
    buf = np.empty((4, 4))
    cases = [
        calibrated("robocal fk_single(q)", lambda: ur.fk_single(q1)),
        calibrated("robocal fk_single(q, out)", lambda: ur.fk_single(q1, buf)),
        calibrated("robocal fk(q) (checked path)", lambda: ur.fk(q1)),
    ]
    if pin is not None:
        pm, pd = pins["ur10"]
        j = pm.njoints - 1

        def pin_single():
            pin.forwardKinematics(pm, pd, q1)
            return pd.oMi[j].homogeneous

        cases.append(calibrated("Pinocchio forwardKinematics + oMi[6].homogeneous", pin_single))
        cases.append(calibrated("Pinocchio forwardKinematics only (no pose read)",
                                lambda: pin.forwardKinematics(pm, pd, q1)))
    single_target = (lambda v: v <= TARGET_SINGLE, f"<= {TARGET_SINGLE:g} us")
    run_section(sec, cases, "us", "robocal fk_single(q, out)", "fk_single(q,out)",
                {"robocal fk_single(q)": single_target, "robocal fk_single(q, out)": single_target})

    # ---- 3. identification Jacobian (ms)
    sec = f"3. identification Jacobian, KUKA KR150, {len(Qk)} poses x {len(kuka.params)} params"
    pt = [0.0, 0.0, 0.0]
    z3 = np.zeros(3)
    perturbed = []
    for jj in range(len(kuka.params)):
        v = kuka.params.values.copy()
        v[jj] += 1e-6
        perturbed.append(kuka.with_params(v))

    def fd_fk_only():
        T0 = kuka.fk(Qk)
        return [m.fk(Qk)[:, :3, 3] - T0[:, :3, 3] for m in perturbed]

    ref = "robocal identification_jacobian(points=[0,0,0]) (N,3,P)"
    cases = [
        calibrated(ref, lambda: kuka.identification_jacobian(Qk, points=pt)),
        calibrated("robocal identification_jacobian() pose rows (N,6,P)", lambda: kuka.identification_jacobian(Qk)),
        ("finite differences: P x with_params + P+1 fk calls", lambda: fd_identification_jacobian(kuka, Qk, z3), 1, 1),
        calibrated("  of which the P+1 fk calls (models prebuilt)", fd_fk_only),
    ]
    idj_target = (lambda v: v <= TARGET_IDJAC, f"<= {TARGET_IDJAC:g} ms")
    run_section(sec, cases, "ms", ref, "robocal",
                {ref: idj_target, cases[1][0]: idj_target})

    # ---- print the table
    w = max(len(r[1]) for r in rows if not np.isnan(r[2]))
    head = f"{'':{w}}  {'median':>12}  {'best':>12}  {'unit':7}  {'ratio':24}  target"
    print(head)
    print("-" * len(head))
    section = None
    for sec_name, name, med, best, unit, ratio, target in rows:
        if sec_name != section:
            section = sec_name
            print(sec_name)
        if np.isnan(med):
            print(f"  {name}")
            continue
        f = (lambda x: f"{x / 1e6:10.2f} M") if unit == "poses/s" else (lambda x: f"{x:12.3f}")
        print(f"{name:{w}}  {f(med):>12}  {f(best):>12}  {unit:7}  {ratio:24}  {target}")
    print()
    print("best = fastest repeat (max poses/s, min time). ratio = how many times faster robocal is than that row")
    print("(section 2: than robocal fk_single(q, out)). Pinocchio rows include the Python call overhead of")
    print("pinocchio's bindings and copying the pose into numpy; robocal's include its Python wrapper.")
    try:
        print(f"load avg at end: {'%.2f %.2f %.2f' % os.getloadavg()}")
    except OSError:
        pass
    return 0


if __name__ == "__main__":
    sys.exit(main())
