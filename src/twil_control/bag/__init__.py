"""ROS 1 bags: recording (recorder), and the tools of ``python -m twil_control.bag``: info,
plot/xy, analyze, export, play (into the Meshcat view through view/bag_replay.py), compare, reindex,
convert. The tools sit above the view in the layers: the view never imports a bag.

The tools read through one reader, ``reader.Bag``, over the format's own index: rosbags' Reader
parses every index entry into objects and is too slow on long runs (docs/bags.md, "How the tools
read a bag"). rosbags' Writer records (bag/writer.py), and ``export`` uses rosbags' AnyReader.
"""
