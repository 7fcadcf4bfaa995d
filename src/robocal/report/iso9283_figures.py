"""The figures of the ISO 9283 report, as SVG (:class:`robocal.report.svg.Panel`, no matplotlib).

* per commanded pose, three projected views (x–y, x–z, y–z of the base frame) of the attained
  positions around their barycentre, with the repeatability sphere (its projection: a circle of
  radius RP) and the direction and distance to the commanded position (AP);
* the drift of P1: AP and RP per block over the drift run, as changes from the first block;
* the path deviation: per evaluation plane, the distance of the crossings' barycentre from the
  commanded path (AT's terms) and l̄ + 3·S (RT's terms), for the line and the circle.

Input is one evaluated run (:func:`robocal.workflows.performance.iso9283_evaluate.evaluate_iso_run`); nothing
is computed here beyond placing marks.
"""

from __future__ import annotations

import numpy as np

from .svg import Panel

__all__ = ["pose_cloud_svgs", "drift_svg", "path_deviation_svg", "iso_figures"]

_VIEWS = (("x", "y", 0, 1), ("x", "z", 0, 2), ("y", "z", 1, 2))


def _circle(cx: float, cy: float, r: float, n: int = 90):
    t = np.linspace(0.0, 2 * np.pi, n + 1)
    return cx + r * np.cos(t), cy + r * np.sin(t)


def pose_cloud_svgs(name: str, pose: dict, attained_mm) -> list[str]:
    """Three square panels (one per projection) for one commanded pose.

    Parameters
    ----------
    name : str
        The pose (``P1``..``P5``).
    pose : dict
        Its figures (``barycentre_mm`` (3,), ``commanded_mm`` (3,), ``AP_mm``, ``RP_mm``).
    attained_mm : array_like, shape (n, 3)
        Attained positions [mm, base frame].

    Returns
    -------
    list of str
        Three ``<svg>`` elements; coordinates are offsets from the barycentre [mm].
    """
    P = np.asarray(attained_mm, float).reshape(-1, 3)
    bary = np.asarray(pose["barycentre_mm"], float)
    cmd = np.asarray(pose.get("commanded_mm", bary), float)
    rp, ap = float(pose["RP_mm"]), float(pose["AP_mm"])
    d = P - bary
    c = cmd - bary
    half = 1.25 * max(rp, float(np.abs(d).max(initial=0.0)), 1e-6)
    out = []
    for a, b, i, j in _VIEWS:
        # a square plot area (equal scales): 300 - 56 - 12 = 298 - 22 - 40
        p = Panel(300, 298, title=f"{name} {a}–{b}: AP {ap:.3f}, RP {rp:.4f} mm", x_label=f"{a} − barycentre [mm]",
                  y_label=f"{b} − barycentre [mm]", margins=(56, 12, 22, 40))
        p.limits(x=(-half, half), y=(-half, half))
        p.line(*_circle(0.0, 0.0, rp), colour="orange")
        p.points(d[:, i], d[:, j], colour="blue", radius=2.2, opacity=0.7)
        p.points([0.0], [0.0], colour="black", radius=3.5)
        # the commanded position: a line from the barycentre toward it (clipped at the frame)
        n_ij = float(np.hypot(c[i], c[j]))
        if n_ij > 0:
            p.line([0.0, c[i]], [0.0, c[j]], colour="red")
            if n_ij <= half:
                p.points([c[i]], [c[j]], colour="red", radius=3.5)
        out.append(p.svg())
    return out


def drift_svg(drift: dict) -> str:
    """AP and RP of P1 per block as changes from the first block [mm] (dAP and dRP are the last
    block's) against the time of the block [min]: AP itself is often a hundred times the drift."""
    blocks = drift["per_block"]
    t = [b["time_min"] for b in blocks]
    ap = np.array([b["AP_mm"] for b in blocks]) - blocks[0]["AP_mm"]
    rp = np.array([b["RP_mm"] for b in blocks]) - blocks[0]["RP_mm"]
    p = Panel(700, 280, title=f"drift of P1: dAP {drift['dAP_mm']:.4f} mm, dRP {drift['dRP_mm']:.4f} mm "
              f"(AP {blocks[0]['AP_mm']:.3f}, RP {blocks[0]['RP_mm']:.4f} mm in the first block)",
              x_label="time since the start of the drift run [min]", y_label="change from the first block [mm]")
    p.hline(0.0, colour="grey")
    p.line(t, ap, colour="blue", label="AP − AP(first block)")
    p.points(t, ap, colour="blue", radius=3)
    p.line(t, rp, colour="orange", label="RP − RP(first block)")
    p.points(t, rp, colour="orange", radius=3)
    return p.svg()


def path_deviation_svg(kind: str, path: dict) -> str:
    """Per evaluation plane of one path: the deviation of the crossings' barycentre from the
    commanded path and l̄ + 3·S [mm]; AT and RT as horizontal lines."""
    dev = np.asarray(path["deviation_mm"], float)
    rep = np.asarray(path["repeatability_mm"], float)
    k = np.arange(1, len(dev) + 1)
    p = Panel(700, 280, title=f"path {kind}: AT {path['AT_mm']:.4f} mm, RT {path['RT_mm']:.4f} mm "
              f"({path['n_cycles']} cycles)", x_label="evaluation plane along the path", y_label="[mm]")
    p.line(k, dev, colour="blue", label="deviation of the barycentre")
    p.points(k, dev, colour="blue", radius=2.5)
    p.line(k, rep, colour="orange", label="l̄ + 3·S in the plane")
    p.points(k, rep, colour="orange", radius=2.5)
    p.hline(float(path["AT_mm"]), colour="blue")
    p.hline(float(path["RT_mm"]), colour="orange")
    p.limits(y=(0.0, 1.1 * float(max(dev.max(initial=0), rep.max(initial=0), 1e-6))))
    return p.svg()


def iso_figures(run: dict) -> list[tuple[str, list[str]]]:
    """Every figure of one run: ``(heading, [svg, ...])`` in report order."""
    figs = []
    for name, pose in run["pose"].items():
        pts = (run.get("attained_mm") or {}).get(name)
        if pts is not None and len(pts):
            figs.append((f"{name}: attained positions (blue) around their barycentre (black), the repeatability "
                         "sphere of radius RP (orange) and the direction to the commanded position (red; AP away)",
                         pose_cloud_svgs(name, pose, pts)))
    if run.get("drift"):
        figs.append(("drift of P1: AP and RP per block", [drift_svg(run["drift"])]))
    for kind, path in run["path"].items():
        figs.append((f"path {kind}: deviation and l̄ + 3·S per evaluation plane", [path_deviation_svg(kind, path)]))
    return figs
