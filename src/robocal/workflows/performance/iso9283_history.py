"""ISO 9283 figures and verification outcomes in the history database (issue 32, item 7).

A performance test (``robocal iso9283 evaluate --db``) and a quick verification (``robocal
verify --db``) are each one cycle of kind ``measurement``; the figures go to the table
``iso9283_figures`` (per pose, and the run's worst value with pose ``""``), the decision to
``verifications``. Both keep the time, the temperature and the instrument in the cycle's meta.
Headline numbers are also cycle metrics (``iso9283.AP``, ``iso9283.RP`` [mm],
``verify.rms`` [mm], ``verify.T`` [1]) so that every history plot and table shows them.
"""

from __future__ import annotations

import math

__all__ = ["iso_figure_rows", "record_iso_run", "record_verification"]

#: the figures of one pose's dict (``pose_characteristics(...).as_dict()``) stored per pose
_POSE_KEYS = ("AP_mm", "AP_x_mm", "AP_y_mm", "AP_z_mm", "RP_mm", "AP_a_deg", "AP_b_deg", "AP_c_deg",
              "RP_a_deg", "RP_b_deg", "RP_c_deg")


def _figure(key: str, pose: str, value: float, adequacy: dict | None) -> dict:
    """One row: ``AP_a_deg`` -> symbol ``AP_a`` in rad, ``AP_mm`` -> ``AP`` in mm."""
    if key.endswith("_deg"):
        sym, unit, k = key[:-4], "rad", math.pi / 180.0
    else:
        sym, unit, k = key[:-3], "mm", 1.0
    row = {"symbol": sym, "pose": pose, "value": float(value) * k, "unit": unit, "uncertainty": None,
           "adequate": None}
    if adequacy is not None and unit == "mm":
        row["uncertainty"] = float(adequacy["U_mm"])
        row["adequate"] = bool(adequacy["adequate"])
    return row


def iso_figure_rows(run: dict) -> list[dict]:
    """The rows of one evaluated run (:func:`robocal.workflows.performance.iso9283_evaluate.evaluate_iso_run`):
    every pose's AP/RP (and orientation figures), vAP per pose, AD/RD, dAP/dRP, AT/RT per path, and
    for AP, RP, vAP, AT and RT the worst value over poses/paths with pose ``""`` (with the
    uncertainty of that pose). Angles in rad, lengths in mm."""
    ad = run.get("adequacy") or {}
    rows = []
    for name, v in run["pose"].items():
        for key in _POSE_KEYS:
            if key in v:
                rows.append(_figure(key, name, v[key], ad.get(f"{key}.{name}")))
    for name, v in run["vap"].items():
        for key in ("vAP_mm", "vAP_a_deg", "vAP_b_deg", "vAP_c_deg"):
            if key in v:
                rows.append(_figure(key, name, v[key], ad.get(f"{key}.{name}")))
    if run.get("distance"):
        for key in ("AD_mm", "RD_mm"):
            rows.append(_figure(key, "", run["distance"][key], ad.get(key)))
    if run.get("drift"):
        for key in ("dAP_mm", "dRP_mm"):
            rows.append(_figure(key, "", run["drift"][key], ad.get(key)))
    for kind, v in run["path"].items():
        for key in ("AT_mm", "RT_mm"):
            rows.append(_figure(key, kind, v[key], ad.get(f"{key}.{kind}")))
    # the run's worst value of the per-pose figures (the number a plant tracks over the years)
    for sym in ("AP", "RP", "vAP", "AT", "RT", "AP_a", "AP_b", "AP_c", "RP_a", "RP_b", "RP_c"):
        cands = [r for r in rows if r["symbol"] == sym and r["pose"]]
        if cands:
            worst = max(cands, key=lambda r: abs(r["value"]))
            rows.append(dict(worst, pose="", value=abs(worst["value"])))
    return rows


def _meta(temperature_c, instrument, extra):
    meta = dict(extra or {})
    meta.update({"temperature_c": temperature_c, "instrument": instrument})
    return {k: v for k, v in meta.items() if v is not None}


def record_iso_run(db, robot_id: str, run: dict, *, time=None, temperature_c: float | None = None,
                   instrument: str | None = None, robot_model: str | None = None, meta: dict | None = None) -> int:
    """Store one evaluated ISO 9283 run as a cycle of ``robot_id`` in the history database ``db``
    (path or URL, created if absent); ``time``: when it was measured (aware datetime or ISO text,
    default now); ``temperature_c`` [degC]. Returns the cycle id."""
    from ...store import HistoryStore

    rows = iso_figure_rows(run)
    if not rows:
        raise ValueError("the run has no ISO 9283 figure to record (no pose, path or distance evaluated)")
    worst = {r["symbol"]: r for r in rows if r["pose"] == ""}
    m = {"test": "iso9283", "n_points_measured": run.get("n_points_measured")}
    with HistoryStore.open(db) as store:
        with store.cycle(robot_id, "measurement", started_at=time, notes="ISO 9283 performance test",
                         meta=_meta(temperature_c, instrument, m | (meta or {})),
                         robot_model=robot_model) as c:
            c.add_iso_figures(rows)
            c.add_metrics({f"iso9283.{s}": (worst[s]["value"], "mm") for s in ("AP", "RP") if s in worst})
            if temperature_c is not None:
                c.add_metric("temperature", float(temperature_c), "degC")
        return c.id


def record_verification(db, robot_id: str, result: dict, *, time=None, robot_model: str | None = None) -> int:
    """Store one ``robocal verify`` result (:func:`robocal.workflows.performance.verify.run_verify`) as a
    cycle of ``robot_id`` in ``db``; the time defaults to the result's. Returns the cycle id."""
    from ...store import HistoryStore

    suspect = value = unit = None
    if result.get("suspect_joint") is not None:
        cause = result.get("suspect_cause", "offset")
        suspect = f"{result['suspect_joint']} {cause}"
        s = result.get("suspect_offset") or {}
        if s:
            unit = "rad" if s["unit"] == "deg" else "mm"
            value = math.radians(s["value"]) if s["unit"] == "deg" else s["value"]
    m = {"test": "verification", "measurements": result.get("measurements")}
    with HistoryStore.open(db) as store:
        with store.cycle(robot_id, "measurement", started_at=time or result.get("time"),
                         notes=f"verification: {result['decision']}",
                         meta=_meta(result.get("temperature_c"), result.get("instrument"), m),
                         robot_model=robot_model) as c:
            c.add_verification(decision=result["decision"], statistic=result["statistic"], dof=int(result["dof"]),
                               threshold=result["threshold"], false_alarm_rate=result["false_alarm_rate"],
                               n_poses=int(result["n_poses"]), rms_mm=result.get("rms_mm"),
                               max_mm=result.get("max_mm"), suspect=suspect, suspect_value=value,
                               suspect_unit=unit, instrument=result.get("instrument"),
                               temperature_c=result.get("temperature_c"), model=result.get("model"))
            c.add_metrics({"verify.rms": (result["rms_mm"], "mm"), "verify.T": (result["statistic"], "1")})
            if result.get("temperature_c") is not None:
                c.add_metric("temperature", float(result["temperature_c"]), "degC")
        return c.id
