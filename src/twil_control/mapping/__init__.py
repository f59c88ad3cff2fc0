"""mapping: occupancy grids, map files, the simulated laser's ray casting, SLAM (pure code, no Drake)."""
