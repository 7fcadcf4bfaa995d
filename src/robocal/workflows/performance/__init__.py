"""Performance: the ISO 9283 test (plan, simulate, evaluate, report) and quick verification."""
