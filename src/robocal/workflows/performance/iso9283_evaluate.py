"""``robocal iso9283 evaluate``: every ISO 9283 characteristic the measurements support.

Reads the plan (``protocol.json``) and a measurement file, computes the figures with the
standard's definitions (:mod:`robocal.performance.iso9283`), states for each whether the
instrument is adequate (:mod:`robocal.performance.adequacy`), and writes ``iso9283.json``, the
standard's table as text and an HTML report. Two runs (before / after correction) give a
comparison per characteristic.
"""

from __future__ import annotations

import numpy as np

from ...performance.adequacy import InstrumentMPE, figure_adequacy
from ...performance.iso9283 import (
    distance_characteristics,
    drift_characteristics,
    multidirectional_variation,
    path_characteristics,
    pose_characteristics,
)

__all__ = ["evaluate_iso_run", "iso_table_lines", "compare_runs"]


def _get(meas, mid, what):
    if mid not in meas.positions:
        return None
    return meas.positions[mid] if what == "p" else (meas.rotations or {}).get(mid)


def _stack(meas, ids):
    """Positions (n, 3) and rotations (n, 3, 3) or None of single-point measurements; ids missing
    from the file are skipped (counted by the caller)."""
    P, R = [], []
    for mid in ids:
        p = _get(meas, mid, "p")
        if p is None:
            continue
        P.append(p[0])
        r = _get(meas, mid, "R")
        R.append(None if r is None else r[0])
    if not P:
        return None, None
    rot = None if any(r is None for r in R) else np.array(R)
    return np.array(P), rot


def _eval_points(points: np.ndarray, n_eval: int, closed: bool):
    """``n_eval`` evaluation points (and tangents) spread along a commanded polyline (ends excluded)."""
    seg = np.diff(points, axis=0)
    cum = np.concatenate([[0.0], np.cumsum(np.linalg.norm(seg, axis=1))])
    s = np.linspace(0, cum[-1], n_eval + (0 if closed else 2))[(0 if closed else 1):(None if closed else -1)]
    if closed:
        s = (np.arange(n_eval) + 0.5) * cum[-1] / n_eval
    pts = np.stack([np.interp(s, cum, points[:, j]) for j in range(3)], axis=1)
    k = np.clip(np.searchsorted(cum, s) - 1, 0, len(seg) - 1)
    tang = seg[k] / np.linalg.norm(seg[k], axis=1, keepdims=True)
    return pts, tang


def evaluate_iso_run(protocol: dict, meas, *, mpe: InstrumentMPE | None = None, instrument_at_mm=None) -> dict:
    """All characteristics of one run.

    Parameters
    ----------
    protocol : dict
        The plan.
    meas : IsoMeasurements
    mpe : InstrumentMPE, optional
        With ``instrument_at_mm`` (3,) [mm, base frame]: the adequacy of every figure.

    Returns
    -------
    dict
        ``pose`` (per pose P1–P5: AP/RP ...), ``vap`` (P1, P2, P4), ``distance`` (P2–P4),
        ``drift``, ``path`` (line, circle), ``adequacy``, ``missing`` (plan ids without data) and
        ``summary`` (the worst value of each characteristic, keyed by the standard's symbols),
        ``attained_mm`` (per pose, the attained positions (n, 3) [mm], for the report's figures).
    """
    poses = protocol["poses"]
    ms = protocol["measurements"]
    out = {"robot": protocol.get("robot"), "n_points_measured": int(sum(len(v) for v in meas.positions.values())),
           "pose": {}, "vap": {}, "distance": None, "drift": None, "path": {}, "adequacy": {}, "missing": [],
           "attained_mm": {}}
    planned = {m["id"] for m in ms}
    out["missing"] = sorted(planned - set(meas.positions))
    unknown = sorted(set(meas.positions) - planned)
    if unknown:
        from ...errors import InputFileError

        raise InputFileError(f"{meas.path}: {len(unknown)} measurement id(s) not in the plan, e.g. {unknown[0]!r} "
                             "(is this the plan the robot ran?)")
    station = None if instrument_at_mm is None else np.asarray(instrument_at_mm, float)

    def dist_of(points):
        return float(np.max(np.linalg.norm(np.atleast_2d(points) - station, axis=1)))

    def adequacy(key, value, points):
        if mpe is not None and station is not None and value is not None:
            out["adequacy"][key] = figure_adequacy(value, mpe, dist_of(points))

    pose_cycles = {}
    for name, pose in poses.items():
        ids = [m["id"] for m in ms if m["test"] == "pose" and m["pose"] == name]
        P, R = _stack(meas, ids)
        if P is None or len(P) < 2:
            continue
        Rc = np.asarray(pose["R"], float)
        pc = pose_characteristics(P, pose["position_mm"], R, Rc if R is not None else None)
        out["pose"][name] = pc.as_dict()
        out["pose"][name]["commanded_mm"] = [float(v) for v in pose["position_mm"]]
        out["attained_mm"][name] = P.tolist()
        pose_cycles[name] = {m["cycle"]: i for i, m in enumerate(m for m in ms if m["id"] in ids
                                                                 and m["id"] in meas.positions)}
        adequacy(f"AP_mm.{name}", pc.AP_mm, P)
        adequacy(f"RP_mm.{name}", pc.RP_mm, P)
    for name in ("P1", "P2", "P4"):
        groups, rots = [], []
        for d in ("+x", "+y", "+z"):
            ids = [m["id"] for m in ms if m["test"] == "vap" and m["pose"] == name and m.get("direction") == d]
            P, R = _stack(meas, ids)
            if P is not None and len(P) >= 2:
                groups.append(P)
                rots.append(R)
        if len(groups) >= 2:
            have_r = all(r is not None for r in rots)
            v = multidirectional_variation(groups, rots if have_r else None, np.asarray(poses[name]["R"]) if have_r else None)
            out["vap"][name] = v
            adequacy(f"vAP_mm.{name}", v["vAP_mm"], np.vstack(groups))
    # distance P2-P4 over the pose test's cycles (both measured in the same cycle)
    c2, c4 = pose_cycles.get("P2", {}), pose_cycles.get("P4", {})
    common = sorted(set(c2) & set(c4))
    if len(common) >= 2:
        a = np.array([meas.positions[f"pose.c{k:02d}.P2"][0] for k in common])
        b = np.array([meas.positions[f"pose.c{k:02d}.P4"][0] for k in common])
        out["distance"] = distance_characteristics(a, b, poses["P2"]["position_mm"], poses["P4"]["position_mm"])
        adequacy("AD_mm", out["distance"]["AD_mm"], np.vstack([a, b]))
        adequacy("RD_mm", out["distance"]["RD_mm"], np.vstack([a, b]))
    blocks = sorted({m["block"] for m in ms if m["test"] == "drift"})
    if len(blocks) >= 2:
        chars = []
        for b in blocks:
            ids = [m["id"] for m in ms if m["test"] == "drift" and m["block"] == b]
            P, _ = _stack(meas, ids)
            if P is not None and len(P) >= 2:
                chars.append((b, pose_characteristics(P, poses["P1"]["position_mm"])))
        if len(chars) >= 2:
            d = drift_characteristics(chars[0][1], chars[-1][1])
            d["per_block"] = [{"block": b, "time_min": b * protocol.get("drift_interval_min", 10.0),
                               "AP_mm": c.AP_mm, "RP_mm": c.RP_mm} for b, c in chars]
            out["drift"] = d
            adequacy("dAP_mm", d["dAP_mm"], poses["P1"]["position_mm"])
            adequacy("dRP_mm", d["dRP_mm"], poses["P1"]["position_mm"])
    for kind in ("line", "circle"):
        spec = protocol["paths"][kind]
        ids = [m["id"] for m in ms if m["test"] == kind and m["id"] in meas.positions]
        if len(ids) < 2:
            continue
        pts, tang = _eval_points(np.asarray(spec["points_mm"], float), int(spec["evaluation_points"]),
                                 closed=(kind == "circle"))
        try:
            pc = path_characteristics(pts, tang, [meas.positions[i] for i in ids])
        except ValueError as exc:  # the measured path misses the commanded one: judged by the gate
            out.setdefault("path_problems", []).append(f"path {kind}: {exc}")
            continue
        out["path"][kind] = pc.as_dict()
        adequacy(f"AT_mm.{kind}", pc.AT_mm, pts)
        adequacy(f"RT_mm.{kind}", pc.RT_mm, pts)
    out["summary"] = _summary(out)
    out["status"], out["reasons"] = _gate(protocol, meas, out)
    return out


#: a measured pose farther than this from its commanded pose is not a robot's inaccuracy but a
#: frame or pairing error (the instrument not registered to the base, another plan's file) [mm]
FRAME_GATE_MM = 25.0


def _gate(protocol: dict, meas, out: dict) -> tuple:
    """The sanity gate of an evaluation: ``("ok" | "failed", reasons)``. Fails when no
    characteristic could be computed, or when measured poses lie farther than
    :data:`FRAME_GATE_MM` from what was commanded (named, with the likely cause)."""
    reasons = []
    if not out["summary"]:
        reasons.append("no ISO 9283 characteristic could be computed from these measurements "
                       f"({len(out['missing'])} of {len(protocol['measurements'])} planned measurements missing)")
    reasons += [f"{p} (not evaluated)" for p in out.get("path_problems", [])]
    far = []
    for m in protocol["measurements"]:
        if m["test"] in ("pose", "vap", "drift") and m["id"] in meas.positions:
            d = float(np.linalg.norm(meas.positions[m["id"]][0] - np.asarray(protocol["poses"][m["pose"]]["position_mm"])))
            if d > FRAME_GATE_MM:
                far.append((d, m["id"]))
    if far:
        far.sort(reverse=True)
        reasons.append(f"{len(far)} measured pose(s) lie more than {FRAME_GATE_MM:g} mm from the commanded pose (worst "
                       f"{far[0][1]}: {far[0][0]:.1f} mm): likely cause: the instrument is not registered to the robot's "
                       "base frame, the file belongs to another plan, or ids are paired with the wrong points")
    return ("failed" if reasons else "ok"), reasons


def _summary(r: dict) -> dict:
    s = {}
    if r["pose"]:
        s["AP_mm"] = max(v["AP_mm"] for v in r["pose"].values())
        s["RP_mm"] = max(v["RP_mm"] for v in r["pose"].values())
        for k in ("a", "b", "c"):
            vals = [abs(v[f"AP_{k}_deg"]) for v in r["pose"].values() if f"AP_{k}_deg" in v]
            if vals:
                s[f"AP_{k}_deg"] = max(vals)
                s[f"RP_{k}_deg"] = max(v[f"RP_{k}_deg"] for v in r["pose"].values())
    if r["vap"]:
        s["vAP_mm"] = max(v["vAP_mm"] for v in r["vap"].values())
    if r["distance"]:
        s["AD_mm"] = r["distance"]["AD_mm"]
        s["RD_mm"] = r["distance"]["RD_mm"]
    if r["drift"]:
        s["dAP_mm"] = r["drift"]["dAP_mm"]
        s["dRP_mm"] = r["drift"]["dRP_mm"]
    for kind, v in r["path"].items():
        s[f"AT_mm_{kind}"] = v["AT_mm"]
        s[f"RT_mm_{kind}"] = v["RT_mm"]
    return s


def iso_table_lines(r: dict) -> list[str]:
    """The standard's table layout, as text lines (one row per pose and characteristic)."""
    ad = r.get("adequacy", {})

    def flag(key):
        a = ad.get(key)
        return "" if a is None else ("" if a["adequate"] else f"  (instrument NOT adequate: U {a['U_mm']:.3f} mm)")

    lines = [f"ISO 9283 performance test, {r.get('robot')}", "",
             f"{'pose':<6}{'AP [mm]':>10}{'AP_x':>9}{'AP_y':>9}{'AP_z':>9}{'RP [mm]':>10}"
             f"{'AP_a':>9}{'AP_b':>9}{'AP_c':>9}{'RP_a':>8}{'RP_b':>8}{'RP_c':>8}  [deg]"]
    for name, v in r["pose"].items():
        o = "".join(f"{v[k]:>9.4f}" for k in ("AP_a_deg", "AP_b_deg", "AP_c_deg")) if "AP_a_deg" in v else ""
        o += "".join(f"{v[k]:>8.4f}" for k in ("RP_a_deg", "RP_b_deg", "RP_c_deg")) if "RP_a_deg" in v else ""
        lines.append(f"{name:<6}{v['AP_mm']:>10.3f}{v['AP_x_mm']:>9.3f}{v['AP_y_mm']:>9.3f}{v['AP_z_mm']:>9.3f}"
                     f"{v['RP_mm']:>10.3f}{o}{flag('RP_mm.' + name)}")
    if r["vap"]:
        lines += ["", "multi-directional pose accuracy variation"]
        for name, v in r["vap"].items():
            extra = "".join(f"  vAP_{k} {v[f'vAP_{k}_deg']:.4f} deg" for k in "abc" if f"vAP_{k}_deg" in v)
            lines.append(f"  {name}: vAP {v['vAP_mm']:.3f} mm{extra}{flag('vAP_mm.' + name)}")
    if r["distance"]:
        d = r["distance"]
        lines += ["", f"distance P2-P4 (commanded {d['D_c_mm']:.2f} mm): AD {d['AD_mm']:+.3f} mm "
                      f"(x {d['AD_x_mm']:+.3f}, y {d['AD_y_mm']:+.3f}, z {d['AD_z_mm']:+.3f}), "
                      f"RD ±{d['RD_mm']:.3f} mm{flag('RD_mm')}"]
    if r["drift"]:
        d = r["drift"]
        lines += ["", f"drift (first vs last block): dAP {d['dAP_mm']:.3f} mm, dRP {d['dRP_mm']:.3f} mm"]
    for kind, v in r["path"].items():
        lines.append(f"path {kind}: AT {v['AT_mm']:.3f} mm, RT {v['RT_mm']:.3f} mm ({v['n_cycles']} cycles)"
                     f"{flag('AT_mm.' + kind)}")
    bad = [k for k, a in ad.items() if not a["adequate"]]
    if bad:
        lines += ["", f"Instrument not adequate (ISO 9283: uncertainty <= 25 % of the figure) for: {', '.join(bad)}"]
    if r["missing"]:
        lines += ["", f"{len(r['missing'])} planned measurement(s) without data (e.g. {r['missing'][0]})"]
    return lines


def compare_runs(before: dict, after: dict) -> list[dict]:
    """Per characteristic of the summary: before, after and the gain (before − after) [mm | deg]."""
    rows = []
    for k in before["summary"]:
        if k in after["summary"]:
            b, a = before["summary"][k], after["summary"][k]
            rows.append({"characteristic": k, "before": b, "after": a, "gain": abs(b) - abs(a)})
    return rows
