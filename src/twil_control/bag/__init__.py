"""ROS 1 bags: recording (recorder), and the tools of ``python -m twil_control.bag``: info,
plot/xy, analyze (``analyze.analyze_bag``), export, play, compare, reindex."""
