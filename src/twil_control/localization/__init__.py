"""Localisation filters as pure mathematics (numpy, numba): amcl's particle filter with its
motion and laser models, and robot_localization's Kalman filters. The nodes that run them on
topics live in nodes/."""
