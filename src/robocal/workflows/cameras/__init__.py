"""Camera workflows: camera calibration, hand-eye, self-calibration, their simulations."""
