"""Camera simulators: rendered boards, hand-eye points, self-calibration runs and studies."""
