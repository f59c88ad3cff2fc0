"""ROS 1 bags: recording (recorder), and the tools of ``python -m twil_control.bag``: info,
plot/xy, analyze (``analyze.analyze_bag``), export, play (``play_view``: into the Meshcat view),
compare, reindex. The tools sit above the view in the layers: the view never imports a bag.

One reader for the tools: ``reader.Bag``, over ``format`` (the bag's index, chunks located by
their index data with numpy). rosbags' Reader would do the same job, but on a bag of 1.2 million
messages it takes 9-11 s to open (it parses every index entry into objects) and about 60-90 s to
deserialise the million status messages an analysis reads, where ``bag info`` answers in 1.3-3 s
and ``bag analyze`` in 9-17 s, Python start-up included (bench/bag_bench.py, shared host).
rosbags' Writer records (bag/writer.py: chunks capped in simulated time, each written whole),
and ``export`` uses rosbags' AnyReader through rosbags-dataframe,
whose tables are what it exports.
"""
