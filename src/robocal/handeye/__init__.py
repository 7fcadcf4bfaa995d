"""Hand-eye calibration (issue 14): AX=XB and AX=ZB solvers. Math only."""
