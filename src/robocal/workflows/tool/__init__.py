"""Tool-frame workflows: cross-laser recalibration after collisions, tool accuracy."""
