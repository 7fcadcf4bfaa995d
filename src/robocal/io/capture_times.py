"""Capture times of images and their joint readings (issue 15: camera self-calibration).

Two files, as a user records them from a robot whose camera and controller run on separate clocks:

* the joint log, ``robocal-joint-log/1``: a CSV with a ``time_s`` column [s] and one column per
  controller joint named as in the robot file, the angle unit declared in the header, either as
  ``# angle_unit: deg`` (or ``rad``) or per column (``HeadYaw [deg]``)::

      # format: robocal-joint-log/1
      # angle_unit: rad
      time_s,HeadYaw,HeadPitch,...

* the frames file: ``image,time_s`` (the image file name and its capture time on the same clock),
  optionally ``board_on``: the end effector holding the board in that image (or ``world``).

:func:`match_capture_times` gives each image its joints: the nearest log row (``"nearest"``) or
the linear interpolation of the two rows around it (``"interpolate"``), if within ``tolerance``
seconds; otherwise the image is unmatched and gets a reason.
"""

from __future__ import annotations

import numpy as np

from .header import KEY_RE, FileFormatError, read_text
from .importers.joint_log import read_joint_log
from .importers.table import read_table
from .importers.timestamps import time_cell

__all__ = ["read_frames", "read_timed_joint_log", "match_capture_times", "write_timed_joint_log", "write_frames", "JOINT_LOG_FORMAT", "MATCH_MODES"]

JOINT_LOG_FORMAT = "robocal-joint-log/1"
MATCH_MODES = ("nearest", "interpolate")


def _header(path) -> dict:
    out = {}
    for line in read_text(path).splitlines():
        if not line.startswith("#"):
            break
        m = KEY_RE.match(line)
        if m:
            out[m.group(1).lower()] = m.group(2).strip()
    return out


def read_timed_joint_log(path, joint_names, angle_unit: str | None = None):
    """``(times (M,) [s], joints (M, n) [rad | mm], lines (M,))`` of a ``robocal-joint-log/1`` file
    with the columns ``joint_names`` (the robot's controller joints, in that order)."""
    unit = angle_unit or _header(path).get("angle_unit") or None
    log = read_joint_log(path, angle_unit=unit, joint_columns=list(joint_names))
    if log.times is None:
        raise FileFormatError(path, "no time column (time_s [s]): a joint log for image matching needs time stamps")
    if len(log) == 0:
        raise FileFormatError(path, "no joint rows")
    order = np.argsort(log.times, kind="stable")
    return log.times[order], log.joints[order], np.asarray(log.lines)[order]


def read_frames(path):
    """``(images (N,) names, times (N,) [s], board_on (N,) names or None)`` of a frames file."""
    table = read_table(path, lambda names: "image" in names, "e.g. 'image,time_s'")
    i_img, i_t = table.index(("image",)), table.index(("time_s", "time"))
    if i_t is None:
        table.fail("no time_s column", table.header_line)
    i_on = table.index(("board_on",))
    names, times, on = [], [], []
    for row, ln in zip(table.rows, table.lines):
        name = row[i_img].strip()
        if not name:
            raise FileFormatError(path, "empty image name", ln, "image")
        names.append(name)
        times.append(time_cell(row[i_t], table.decimal, table.units[i_t], path, ln, table.columns[i_t])[0])
        if i_on is not None:
            on.append(row[i_on].strip())
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        raise FileFormatError(path, f"image(s) listed twice: {', '.join(dup)}")
    return names, np.array(times, dtype=float), (on if i_on is not None else None)


def match_capture_times(image_times, log_times, log_joints, *, tolerance: float, mode: str = "nearest",
                        offset: float = 0.0):
    """``(joints (N, n) NaN where unmatched, dt (N,) [s] image time minus the matched reading's,
    reasons (N,) None or why unmatched)``.

    tolerance [s]: how far the nearest reading (``"nearest"``), or both readings around the image
    (``"interpolate"``), may be from the capture time; offset [s] is added to the log's times.
    """
    if mode not in MATCH_MODES:
        raise ValueError(f"match mode must be one of {', '.join(MATCH_MODES)}, got {mode!r}")
    if not tolerance > 0:
        raise ValueError(f"tolerance: expected a positive number of seconds, got {tolerance!r}")
    t = np.asarray(image_times, dtype=float)
    tl = np.asarray(log_times, dtype=float) + offset
    Q = np.asarray(log_joints, dtype=float)
    M = len(tl)
    k = np.searchsorted(tl, t)  # tl[k-1] <= t < tl[k]
    lo, hi = np.clip(k - 1, 0, M - 1), np.clip(k, 0, M - 1)
    d_lo, d_hi = np.abs(t - tl[lo]), np.abs(tl[hi] - t)
    nearest = np.where(d_lo <= d_hi, lo, hi)
    dt = t - tl[nearest]
    q = Q[nearest].copy()
    reasons = [None] * len(t)
    if mode == "interpolate":
        both = (k > 0) & (k < M) & (d_lo <= tolerance) & (d_hi <= tolerance)
        span = np.where(tl[hi] > tl[lo], tl[hi] - tl[lo], 1.0)
        f = np.clip((t - tl[lo]) / span, 0.0, 1.0)[:, None]
        q = np.where(both[:, None], (1 - f) * Q[lo] + f * Q[hi], q)
        dt = np.where(both, 0.0, dt)
        bad = ~both
    else:
        bad = np.abs(dt) > tolerance
    for i in np.flatnonzero(bad):
        if mode == "interpolate" and abs(dt[i]) <= tolerance:
            reasons[i] = (f"no joint readings on both sides within {tolerance:g} s (nearest {dt[i]:+.3f} s away; "
                          "use --match nearest)")
        else:
            reasons[i] = (f"no joint reading within {tolerance:g} s of the capture time (nearest "
                          f"{dt[i]:+.3f} s away; log {tl.min():.3f}..{tl.max():.3f} s)")
    q[bad] = np.nan
    return q, dt, reasons


def write_timed_joint_log(path, times, joints, joint_names, *, angle_unit: str = "rad", overwrite: bool = False):
    """Write a ``robocal-joint-log/1`` file (atomic): times (M,) [s], joints (M, n) [rad]."""
    from .atomic import atomic_write_text

    if angle_unit not in ("rad", "deg"):
        raise ValueError(f"angle_unit: expected rad or deg, got {angle_unit!r}")
    q = np.degrees(joints) if angle_unit == "deg" else np.asarray(joints, dtype=float)
    lines = [f"# format: {JOINT_LOG_FORMAT}", f"# angle_unit: {angle_unit}", ",".join(["time_s", *joint_names])]
    lines += [",".join([f"{t:.4f}"] + [f"{v:.9g}" for v in row]) for t, row in zip(times, q)]
    return atomic_write_text(path, "\n".join(lines) + "\n", overwrite=overwrite)


def write_frames(path, images, times, board_on=None, *, overwrite: bool = False):
    """Write a frames file (atomic): image names, capture times [s], optional carriers."""
    from .atomic import atomic_write_text

    head = "image,time_s" + (",board_on" if board_on is not None else "")
    rows = [f"{n},{t:.4f}" + (f",{board_on[i]}" if board_on is not None else "")
            for i, (n, t) in enumerate(zip(images, times))]
    return atomic_write_text(path, "\n".join([head, *rows]) + "\n", overwrite=overwrite)
