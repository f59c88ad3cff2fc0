"""slam_gmapping's parameter names (every one the original qbot launch sets, and gmapping's
defaults) and a scan frame without a transform (one warning, never a crash)."""

from __future__ import annotations

import logging

import numpy as np
from test_gmapping_node import PARAMS, feed, loop_path, make, scan_msg

# the original qbot launch's gmapping parameters, and gmapping's defaults
ORIGINAL = dict(
    odom_frame="odom",
    base_frame="base_link",
    map_update_interval=1.0,
    maxUrange=10.0,
    maxRange=60.0,
    sigma=0.05,
    kernelSize=1,
    lstep=0.05,
    astep=0.05,
    iterations=5,
    lsigma=0.075,
    ogain=3.0,
    lskip=0,
    linearUpdate=0.5,
    angularUpdate=0.436,
    temporalUpdate=-1.0,
    resampleThreshold=0.5,
    particles=80,
    xmin=-5,
    ymin=-5,
    xmax=5,
    ymax=5,
    delta=0.025,
    llsamplerange=0.01,
    llsamplestep=0.01,
    lasamplerange=0.005,
    lasamplestep=0.005,
)
DEFAULTS = dict(
    srr=0.1,
    srt=0.2,
    str=0.1,
    stt=0.2,
    minimumScore=0,
    occ_thresh=0.25,
    transform_publish_period=0.05,
    throttle_scans=1,
)


def test_every_parameter_name_of_the_original_and_of_gmappings_defaults_is_taken():
    master, node, *_ = make({**ORIGINAL, **DEFAULTS, "particles": 3})
    for name, value in {**ORIGINAL, **DEFAULTS, "particles": 3}.items():
        assert getattr(node.params, name) == value, name


def test_scan_frame_without_transform_is_skipped_with_one_warning(caplog):
    master, node, feeder, pubs = make(PARAMS)
    with caplog.at_level(logging.WARNING):
        for k in range(5):
            master.spin_until(0.1 * (k + 1))
            pubs["scan"].publish(scan_msg(0.1 * (k + 1), np.full(640, 3.0), frame="laser_nowhere"))
    warnings = [r.getMessage() for r in caplog.records if r.levelno == logging.WARNING]
    assert len(warnings) == 1 and "laser_nowhere" in warnings[0], warnings
    assert node.slam is None
    feed(master, pubs, loop_path()[:5], loop_path()[:5])  # a good laser frame then maps
    assert node.slam is not None and node.slam.count == 1
