"""Orchestration of library steps for the command line (may import I/O and reports)."""
