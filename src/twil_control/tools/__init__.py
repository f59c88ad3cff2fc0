"""Command-line tools that convert files, above the layers they use.

- ``python -m twil_control.tools.rasterize WORLD.sdf -o NAME``: a world's static geometry as
  a map_server map pair (world/ cuts the shapes with Drake, mapping/ rasterises them);
- ``python -m twil_control.tools.carmen_to_bag LOG -o BAG``: a CARMEN laser log as a ROS 1 bag
  (mapping/ reads the log, bag/ records it).
"""
