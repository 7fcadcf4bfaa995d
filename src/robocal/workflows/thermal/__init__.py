"""Thermal workflows: simulated runs, screening and compensation commands, their inputs."""
