"""Fleets on Dask: calibrate many robots, studies as tasks, fleet status."""
