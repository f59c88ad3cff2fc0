"""MCAP beside rosbag 1: the recorder's MCAP files (ROS 1 profile, time-capped zstd chunks, a
summary, written safely), `bag convert` both ways and to ROS 2, the bag tools reading MCAP, and
readers not written here (the `mcap` package with `mcap-ros1-support`, rosbags) reading the files
back message for message.
"""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from mcap.reader import make_reader
from mcap_ros1.decoder import DecoderFactory
from rosbags.highlevel import AnyReader
from rosbags.rosbag1 import Reader

from twil_control.bag.bag_errors import BagError
from twil_control.bag.convert import convert
from twil_control.bag.info import bag_info
from twil_control.bag.reader import Bag
from twil_control.bag.recorder import BagRecorder, RecorderError, active_path
from twil_control.bag.reindex import reindex
from twil_control.core import messages
from twil_control.core.bus import Bus
from twil_control.launch.loader import LaunchError, load_launch

M = messages.msg_class


def odom(t: float, x: float):
    return M("nav_msgs/Odometry")(
        header=messages.header("odom", t),
        child_frame_id="base_link",
        pose=M("geometry_msgs/PoseWithCovariance")(
            pose=M("geometry_msgs/Pose")(
                position=M("geometry_msgs/Point")(x=x, y=-x, z=0.0),
                orientation=M("geometry_msgs/Quaternion")(x=0.0, y=0.0, z=0.0, w=1.0),
            ),
            covariance=np.zeros(36),
        ),
        twist=M("geometry_msgs/TwistWithCovariance")(
            twist=M("geometry_msgs/Twist")(
                linear=M("geometry_msgs/Vector3")(x=x, y=0.0, z=0.0),
                angular=M("geometry_msgs/Vector3")(x=0.0, y=0.0, z=0.1),
            ),
            covariance=np.zeros(36),
        ),
    )


def status(t: float, text: str):
    return M("std_msgs/String")(data=f"{text} {t:.2f}")


def record(path: Path, seconds: float = 3.0, bus: Bus | None = None, stop_at: float | None = None):
    """A recorder on a bus with /odom at 100 Hz, /status at 2 Hz and a latched /map_name, flushed
    every 0.05 s as the runner does; stop_at: return the open recorder at that time."""
    bus = bus or Bus()
    pub_o = bus.advertise("/odom", "nav_msgs/Odometry", node="/o")
    pub_s = bus.advertise("/status", "std_msgs/String", node="/s")
    pub_l = bus.advertise("/map_name", "std_msgs/String", node="/m", latch=True)
    pub_l.publish(M("std_msgs/String")(data="house"))
    rec = BagRecorder(path, bus)
    sent = []
    for k in range(1, int(round(seconds * 100)) + 1):
        t = k / 100
        bus.clock.set(t)
        msg = odom(t, 0.01 * k)
        pub_o.publish(msg)
        sent.append(("/odom", t, msg))
        if k % 50 == 0:
            pub_s.publish(status(t, "ok"))
        if k % 5 == 0:
            rec.flush()
        if stop_at is not None and t >= stop_at - 1e-9:
            return rec, sent
    rec.close()
    return rec, sent


def bag_contents(path: Path):
    with Reader(path) as r:
        conns = sorted(
            (c.topic, c.msgtype, c.msgdef.data, c.digest, c.ext.latching, c.ext.callerid)
            for c in r.connections
        )
        msgs = [(c.topic, t, bytes(raw)) for c, t, raw in r.messages()]
    return conns, msgs


@pytest.fixture
def recorded_bag(tmp_path):
    path = tmp_path / "run.bag"
    record(path)
    return path


def test_bag_to_mcap_to_bag_gives_the_same_connections_and_message_data(recorded_bag, tmp_path):
    convert(recorded_bag, tmp_path / "run.mcap")
    convert(tmp_path / "run.mcap", tmp_path / "back.bag")
    before, after = bag_contents(recorded_bag), bag_contents(tmp_path / "back.bag")
    assert after[0] == before[0]  # topics, types, definitions, md5sums, latching, callerids
    assert after[1] == before[1]  # every message: topic, stamp and bytes, in order
    assert len(before[1]) == 300 + 6 + 1 and ("/map_name", "std_msgs/msg/String") in [
        c[:2] for c in before[0]
    ]
    assert [c[4] for c in before[0] if c[0] == "/map_name"] == [1]


def test_the_mcap_package_reads_the_recorders_mcap_message_for_message(tmp_path):
    path = tmp_path / "run.mcap"
    _, sent = record(path)
    with path.open("rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        summary = reader.get_summary()
        assert reader.get_header().profile == "ros1"
        decoded = [
            (ch.topic, m.log_time, msg) for _, ch, m, msg in reader.iter_decoded_messages(log_time_order=True)
        ]
    channels = {c.topic: c for c in summary.channels.values()}
    assert {c.message_encoding for c in channels.values()} == {"ros1"}
    assert {s.encoding for s in summary.schemas.values()} == {"ros1msg"}
    schema = summary.schemas[channels["/odom"].schema_id]
    assert (schema.name, schema.data.decode()) == (
        "nav_msgs/Odometry",
        messages.definition("nav_msgs/Odometry")[0],
    )
    assert (
        channels["/map_name"].metadata["latching"] == "true"
        and channels["/odom"].metadata["latching"] == "false"
    )
    assert summary.statistics.message_count == len(decoded) == 307
    odoms = [(t, msg) for topic, t, msg in decoded if topic == "/odom"]
    assert [t for t, _ in odoms] == [int(round(t * 1e9)) for _, t, _ in sent]
    for (_, mine), (_, _, theirs) in zip(odoms, sent):
        assert mine.pose.pose.position.x == theirs.pose.pose.position.x
        assert mine.header.stamp.nsecs == theirs.header.stamp.nanosec
    assert decoded[0][0] == "/map_name" and decoded[0][2].data == "house"


def test_mcap_chunks_hold_at_most_a_second_of_simulated_time_and_are_zstd(tmp_path):
    path = tmp_path / "run.mcap"
    record(path, seconds=3.5)
    with path.open("rb") as f:
        chunks = make_reader(f).get_summary().chunk_indexes
    assert len(chunks) == 4
    assert all(c.compression == "zstd" for c in chunks)
    assert all(c.message_end_time - c.message_start_time < 1_000_000_000 for c in chunks)


def test_the_mcap_file_is_active_while_recording_and_never_overwritten(tmp_path):
    path = tmp_path / "run.mcap"
    rec, _ = record(path, stop_at=1.5)
    assert active_path(path).exists() and not path.exists()
    rec.close()
    assert path.exists() and not active_path(path).exists()
    with pytest.raises(RecorderError, match="exists; bags are never overwritten"):
        BagRecorder(path, Bus())
    with pytest.raises(RecorderError, match="must end in .bag or .mcap"):
        BagRecorder(tmp_path / "run.mcp", Bus())


def test_an_mcap_cut_by_a_hard_kill_keeps_every_chunk_closed_a_second_before(tmp_path):
    path = tmp_path / "run.mcap"
    rec, sent = record(path, stop_at=2.73)
    cut = tmp_path / "killed.mcap.active"
    shutil.copy(active_path(path), cut)  # what the disk holds at a SIGKILL at t = 2.73 s
    rec.close()
    with pytest.raises(BagError, match="reindex"):
        Bag(cut)
    r = reindex(cut, tmp_path / "recovered.mcap")
    recovered = Bag(tmp_path / "recovered.mcap")
    t, _ = recovered.columns("/odom", ["pose.pose.position.x"])
    # the recorder writes whole chunks: the file ends at a chunk boundary, not inside one
    assert not r.partial_chunk and r.messages == recovered.message_count
    assert 2.73 - 1.05 <= t[-1] * 1e-9 < 2.73  # lost: at most the open chunk (a second and a slice)
    full = Bag(path)
    assert list(t) == list(full.columns("/odom", ["pose.pose.position.x"])[0][: len(t)])


def test_the_bag_tools_read_mcap_as_they_read_the_bag(recorded_bag, tmp_path):
    mcap = tmp_path / "run.mcap"
    convert(recorded_bag, mcap, compression="lz4")
    a, b = Bag(recorded_bag), Bag(mcap)
    assert (b.start_ns, b.end_ns, b.message_count) == (a.start_ns, a.end_ns, a.message_count)
    assert {n: (t.ros1_type, t.count, t.latching, t.md5sum) for n, t in b.topics.items()} == {
        n: (t.ros1_type, t.count, t.latching, t.md5sum) for n, t in a.topics.items()
    }
    ta, ca = a.columns("/odom", ["pose.pose.position.x", "twist.twist.angular.z"])
    tb, cb = b.columns("/odom", ["pose.pose.position.x", "twist.twist.angular.z"])
    assert np.array_equal(ta, tb) and all(np.array_equal(ca[k], cb[k]) for k in ca)
    assert list(a.raw_messages(["/status", "/map_name"])) == list(b.raw_messages(["/status", "/map_name"]))
    ia, ib = bag_info(recorded_bag), bag_info(mcap)
    assert ib["version"] == "MCAP (ros1 profile)" and ib["compression"] == "lz4"
    assert [t for t in ia["topics"]] == [t for t in ib["topics"]]  # counts, rates, latching
    for name, bag in (("a", recorded_bag), ("b", mcap)):
        subprocess.run(
            [
                sys.executable,
                "-m",
                "twil_control.bag",
                "export",
                str(bag),
                "/odom",
                "-o",
                str(tmp_path / f"{name}.csv"),
            ],
            check=True,
            capture_output=True,
        )
    assert (tmp_path / "a.csv").read_text() == (tmp_path / "b.csv").read_text()


def test_a_ros2_bag_from_mcap_or_bag_is_read_by_rosbags(recorded_bag, tmp_path):
    convert(recorded_bag, tmp_path / "run.mcap")
    for src, out in ((recorded_bag, tmp_path / "ros2_a"), (tmp_path / "run.mcap", tmp_path / "ros2_b")):
        c = convert(src, out, to="ros2")
        assert c.messages == 307 and (out / "metadata.yaml").is_file()
        with AnyReader([out]) as reader:
            xs = [
                reader.deserialize(raw, conn.msgtype).pose.pose.position.x
                for conn, _, raw in reader.messages()
                if conn.topic == "/odom"
            ]
        assert xs == pytest.approx([0.01 * k for k in range(1, 301)], abs=1e-12)


def test_rosbags_anyreader_refuses_ros1_mcap_so_the_ros2_conversion_is_the_way(recorded_bag, tmp_path):
    convert(recorded_bag, tmp_path / "run.mcap")
    with pytest.raises(Exception, match="ros2"):
        with AnyReader([tmp_path / "run.mcap"]):
            pass


@pytest.mark.parametrize(
    "out,to,why",
    [
        ("other.bag", None, "already a ROS 1 bag"),
        ("run.txt", None, "name it .bag or .mcap"),
        ("x.bag", "mcap", "a mcap file is named .mcap"),
        ("run.mcap", None, "exists"),
    ],
)
def test_convert_refuses_what_it_cannot_do_without_writing(recorded_bag, tmp_path, out, to, why):
    (tmp_path / "run.mcap").write_bytes(b"keep me")
    with pytest.raises(BagError, match=why):
        convert(recorded_bag, tmp_path / out, to)
    assert (tmp_path / "run.mcap").read_bytes() == b"keep me"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.bag", "run.mcap"]


def test_record_options_in_a_launch_file(tmp_path):
    f = tmp_path / "l.launch.yaml"
    f.write_text("launch:\n  - record: {format: mcap, compression: lz4}\n  - record: {topics: [/a]}\n")
    plan = load_launch(f)
    assert (plan.record_format, plan.record_compression, plan.record_topics) == ("mcap", "lz4", ["/a"])
    f.write_text("launch:\n  - record: {format: rosbag}\n")
    with pytest.raises(LaunchError, match="record format 'rosbag' is not one of bag, mcap"):
        load_launch(f)


@pytest.mark.slow
def test_a_launch_killed_hard_while_recording_mcap_loses_at_most_about_a_second(tmp_path, root):
    """SIGKILL (no handler runs) once the log says 3 simulated seconds have passed; the .active
    file is recovered by reindex up to within a chunk (1 s) and a time slice of the kill."""
    import re
    import signal

    bag = tmp_path / "run.mcap"
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "twil_control.launch",
            str(root / "launch/qbot_navigation.launch.yaml"),
            "--bag",
            str(bag),
            "--duration",
            "30",
        ],
        cwd=tmp_path,
        stderr=subprocess.PIPE,
        text=True,
    )
    killed_at = None
    for line in proc.stderr:
        m = re.match(r"\[INFO\] \[(\d+\.\d+)\]: /goals: no goals given", line)
        if m and float(m.group(1)) >= 3.0:
            proc.send_signal(signal.SIGKILL)
            killed_at = float(m.group(1))
            break
    proc.wait(timeout=60)
    assert killed_at is not None and not bag.exists() and active_path(bag).exists()
    r = reindex(active_path(bag), tmp_path / "recovered.mcap")
    recovered = Bag(tmp_path / "recovered.mcap")
    assert r.messages == recovered.message_count > 1000
    assert recovered.end_ns * 1e-9 >= killed_at - 1.0 - 0.05 - 0.01  # a chunk, a slice, /joint_states' period
