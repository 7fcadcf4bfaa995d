"""Machine description printed at the top of every benchmark (imported by the scripts beside it)."""

from __future__ import annotations

import datetime
import os
import platform
from pathlib import Path

import numpy as np


def cpu_model() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def machine_info(extra=()) -> list[str]:
    """Date, CPU, load, OS, Python and numpy lines, then the script's own ``extra`` lines."""
    try:
        affinity = len(os.sched_getaffinity(0))
    except AttributeError:
        affinity = os.cpu_count()
    try:
        load = "%.2f %.2f %.2f" % os.getloadavg()
    except OSError:
        load = "n/a"
    return [
        f"date        {datetime.datetime.now(datetime.timezone.utc).strftime('%Y-%m-%d %H:%M UTC')}",
        f"cpu         {cpu_model()} ({os.cpu_count()} logical CPUs, {affinity} usable)",
        f"load avg    {load}  (1/5/15 min, at start)",
        f"os          {platform.platform()}",
        f"python      {platform.python_version()} ({platform.python_implementation()})",
        f"numpy       {np.__version__}",
        *extra,
    ]
