"""Regenerate ``thermal_ideal_fae18d9.npz``: the thermal cell's output from the simulator as it was at
commit fae18d9, before the realistic effects existed (issue 11). Run from the repository root:

    mkdir -p /tmp/old && git archive fae18d9 src | tar -x -C /tmp/old
    PYTHONPATH=/tmp/old/src python tests/data/make_thermal_ideal_reference.py

``tests/test_thermal_realism.py`` checks that today's ``preset="ideal"`` reproduces these arrays to
1e-9 mm (rounding differs between machines; the values do not).
"""

from pathlib import Path

import numpy as np

from robocal.sim.thermal.simulator import ThermalCell, standard_schedules

FIELDS = ("sphere", "monitor", "delta_true", "tcp_drift_mm", "sphere_cold", "monitor_cold")

if __name__ == "__main__":
    run = ThermalCell.standard(2024).simulate(standard_schedules(7, 12)[1], 5)
    np.savez_compressed(Path(__file__).with_name("thermal_ideal_fae18d9.npz"),
                        **{k: getattr(run, k) for k in FIELDS})
