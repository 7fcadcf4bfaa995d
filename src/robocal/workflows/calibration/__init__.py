"""Calibration workflows: calibrate (rigid, elastic, swarm), closed chain, correction, plans, import, studies."""
