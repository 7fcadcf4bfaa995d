"""Controller models in and out: UR factory calibration, exports, probing, model diff."""
