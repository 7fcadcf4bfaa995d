"""Light-barrier simulators: beam geometry, effects, the parallel-barrier cell."""
