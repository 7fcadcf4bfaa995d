"""The thermal simulator: heat, deformation, measurement, schedules, realistic effects, run files."""
