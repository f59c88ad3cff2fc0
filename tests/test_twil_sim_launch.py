"""launch/twil_sim.launch.yaml end to end: the bag it records, reproducibility, Ctrl-C."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from conftest import bag_connections, read_bag

from twil_control import PACKAGE_ROOT
from twil_control.launch.__main__ import main
from twil_control.launch.loader import load_launch
from twil_control.launch.runner import RunOptions, run

LAUNCH = PACKAGE_ROOT / "launch/twil_sim.launch.yaml"
# md5sums of the ROS Noetic message definitions (as `rosmsg md5` prints them).
NOETIC_MD5 = {
    "sensor_msgs/msg/JointState": "3066dcd76a6cfaef579bd0f34173e9fd",
    "nav_msgs/msg/Odometry": "cd5e73d190d741a2f92e81eda573aca7",
    "tf2_msgs/msg/TFMessage": "94810edda583a504dfda3829e70d7eec",
}
JOINTS = ["left_wheel_joint", "right_wheel_joint"] + [f"wam_joint_{i}" for i in range(1, 8)]


@pytest.fixture(scope="module")
def five_second_bag(tmp_path_factory) -> Path:
    bag = tmp_path_factory.mktemp("twil") / "out.bag"
    assert main([str(LAUNCH), "--duration", "5", "--bag", str(bag), "--quiet"]) == 0
    return bag


def test_bag_holds_joint_states_at_the_configured_rate(five_second_bag):
    conns = bag_connections(five_second_bag)
    msgtype, md5, count = conns["/joint_states"]
    assert msgtype == "sensor_msgs/msg/JointState" and md5 == NOETIC_MD5[msgtype]
    assert abs(count - 500) <= 1, count  # publish_rate 100 Hz for 5 s, +-1 message


def test_joint_states_cover_every_joint_with_position_velocity_effort(five_second_bag):
    msgs = [m for _, m in read_bag(five_second_bag)["/joint_states"]]
    assert sorted(msgs[0].name) == sorted(JOINTS)
    for m in msgs[::50]:
        assert len(m.position) == len(m.velocity) == len(m.effort) == len(JOINTS)
        assert np.isfinite(m.position).all() and np.isfinite(m.velocity).all()
    # Zero effort: the arm falls under gravity, so shoulder/elbow angles change.
    first, last = np.array(msgs[0].position), np.array(msgs[-1].position)
    assert np.abs(last - first).max() > 0.1


def test_bag_holds_tf_odometry_and_ground_truth_with_noetic_md5(five_second_bag):
    conns = bag_connections(five_second_bag)
    for topic, msgtype in [
        ("/tf", "tf2_msgs/msg/TFMessage"),
        ("/tf_static", "tf2_msgs/msg/TFMessage"),
        ("/twil/odom", "nav_msgs/msg/Odometry"),
        ("/twil/ground_truth/odom", "nav_msgs/msg/Odometry"),
    ]:
        assert conns[topic][0] == msgtype
        assert conns[topic][1] == NOETIC_MD5[msgtype]
        assert conns[topic][2] >= 1
    frames = set()
    for _, m in read_bag(five_second_bag)["/tf"][:50]:
        frames |= {(t.header.frame_id, t.child_frame_id) for t in m.transforms}
    assert ("odom", "base_link") in frames
    assert ("world", "base_link_ground_truth") in frames


def test_robot_state_publisher_gives_every_link_a_frame_matching_the_model(five_second_bag):
    """/tf and /tf_static hold every link of the description (robot_state_publisher: fixed
    joints once, the wheels and the arm from /joint_states), and the arm's mount composes to the
    pose the simulated model has."""
    from twil_control.core.node import Master, Node
    from twil_control.core.tf import TfBuffer
    from twil_control.description.urdf import parse_urdf
    from twil_control.description.xacro_command import run_xacro
    from twil_control.world.simulation import Simulation

    bag = read_bag(five_second_bag)
    links = parse_urdf(run_xacro([str(PACKAGE_ROOT / "sim/robots/twil_wam.urdf.xacro")])).links
    frames = {
        f
        for topic in ("/tf", "/tf_static")
        for _, m in bag[topic]
        for t in m.transforms
        for f in (t.header.frame_id, t.child_frame_id)
    }
    assert set(links) <= frames
    buffer = TfBuffer(Node(Master(), "listener"))
    ((_, static),) = bag["/tf_static"]
    for t in static.transforms:
        p, q = t.transform.translation, t.transform.rotation
        buffer.set_transform(
            t.header.frame_id, t.child_frame_id, 0.0, ((p.x, p.y, p.z), (q.x, q.y, q.z, q.w)), static=True
        )
    translation, _ = buffer.lookup_transform("base_link", "wam_base_link")
    sim = Simulation()
    sim.spawn("twil_wam", "twil_wam")
    sim.finalize()
    ctx = sim.plant.CreateDefaultContext()
    X = sim.plant.GetFrameByName("wam_base_link").CalcPose(ctx, sim.plant.GetFrameByName("base_link"))
    np.testing.assert_allclose(translation, X.translation(), atol=1e-12)
    np.testing.assert_allclose(translation, [0.15, 0.0, 0.651], atol=1e-9)


def _contents(bag: Path) -> list:
    from twil_control.core.messages import serialize

    return [(topic, t, serialize(m)) for topic, msgs in sorted(read_bag(bag).items()) for t, m in msgs]


def test_same_arguments_and_seed_give_identical_bags(tmp_path):
    plan_args = {"x": "0.5", "yaw": "0.3"}
    bags = []
    for k in range(2):
        bag = tmp_path / f"run{k}.bag"
        result = run(load_launch(LAUNCH, plan_args), RunOptions(duration=1.0, bag=bag, seed=7))
        assert result.error is None
        bags.append(bag)
    a, b = _contents(bags[0]), _contents(bags[1])
    assert len(a) > 300
    assert a == b


def test_ground_truth_starts_at_the_spawn_pose(tmp_path):
    bag = tmp_path / "spawn.bag"
    result = run(
        load_launch(LAUNCH, {"x": "1.5", "y": "-0.5", "yaw": "1.0"}), RunOptions(duration=0.05, bag=bag)
    )
    assert result.error is None
    odom = read_bag(bag)["/twil/ground_truth/odom"][0][1]
    p = odom.pose.pose.position
    q = odom.pose.pose.orientation
    assert abs(p.x - 1.5) < 1e-3 and abs(p.y + 0.5) < 1e-3
    assert abs(2 * np.arctan2(q.z, q.w) - 1.0) < 1e-3


def _realtime_launch_running(bag: Path) -> subprocess.Popen:
    """The launch CLI at real time in a child process, returned once time runs (the bag's
    .active file appears)."""
    proc = subprocess.Popen(
        [sys.executable, "-m", "twil_control.launch", str(LAUNCH), "--realtime", "1", "--bag", str(bag)],
        env=dict(os.environ, PYTHONUNBUFFERED="1"),
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    deadline = time.monotonic() + 120
    while not Path(str(bag) + ".active").exists():
        assert proc.poll() is None, proc.communicate()
        assert time.monotonic() < deadline
        time.sleep(0.05)
    return proc


def _wait_for_chunks(proc: subprocess.Popen, bag: Path, chunks: int) -> None:
    """Wait until the recorder has written `chunks` chunks (one per simulated second by default:
    the .active file grows once per chunk), so the run has gone that far in simulated time
    however loaded the machine is."""
    active = Path(str(bag) + ".active")
    header = len(b"#ROSBAG V2.0\n") + 4096  # the version line and the padded bag header record
    size, grown = 0, 0
    deadline = time.monotonic() + 120
    while grown < chunks:
        assert proc.poll() is None, proc.communicate()
        assert time.monotonic() < deadline
        time.sleep(0.02)
        now = active.stat().st_size
        grown, size = grown + (now > max(size, header)), now


@pytest.mark.slow
def test_ctrl_c_two_seconds_into_a_realtime_run_leaves_a_valid_bag(tmp_path):
    bag = tmp_path / "sigint.bag"
    proc = _realtime_launch_running(bag)
    _wait_for_chunks(proc, bag, 2)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 0, err
    assert "interrupted" in err
    assert bag.exists() and not Path(str(bag) + ".active").exists()
    count = bag_connections(bag)["/joint_states"][2]
    assert 200 <= count <= 400, count  # 2 s at 100 Hz recorded, and what ran until the signal was seen


@pytest.mark.slow
def test_ctrl_c_repeated_until_the_launch_exits_still_ends_it_cleanly(tmp_path):
    # as a sweep's worker stops a run past its timeout, and an impatient user does: SIGINT
    # again every 0.1 s until the process is gone; the bag is closed and the exit code is 0
    bag = tmp_path / "sigints.bag"
    proc = _realtime_launch_running(bag)
    _wait_for_chunks(proc, bag, 1)
    deadline = time.monotonic() + 60
    while proc.poll() is None and time.monotonic() < deadline:
        proc.send_signal(signal.SIGINT)
        time.sleep(0.1)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 0, err
    assert "interrupted" in err and "Traceback" not in err
    assert bag.exists() and not Path(str(bag) + ".active").exists()
    assert bag_connections(bag)["/joint_states"][2] >= 100


def test_realtime_pacing_starts_at_time_zero_of_the_run(tmp_path, monkeypatch):
    """--realtime paces from the run's start, not from the simulator's Initialize(): set-up that
    happens in between (here a recorder made 0.5 s slower) must not be run off faster than real
    time afterwards. 1 simulated s at rate 2 takes at least 0.5 s of wall time."""
    from twil_control.bag import recorder as rec

    make = rec.BagRecorder.__init__

    def slow_init(self, *a, **kw):
        time.sleep(0.5)
        make(self, *a, **kw)

    monkeypatch.setattr(rec.BagRecorder, "__init__", slow_init)
    result = run(load_launch(LAUNCH, {}), RunOptions(duration=1.0, bag=tmp_path / "paced.bag", realtime=2.0))
    assert result.error is None and result.sim_time == pytest.approx(1.0)
    assert result.wall_time >= 0.5 - 0.01, result.wall_time


def test_gil_switch_interval_is_short_while_time_runs_and_restored_after(tmp_path, monkeypatch):
    """The simulation takes the GIL for every Python system's event, so while time runs the
    runner makes other Python threads (slam_gmapping's worker) hand it over within
    SWITCH_INTERVAL instead of Python's 5 ms; the process's own setting is back afterwards, also
    when a node fails."""
    import sys

    from twil_control.bag import recorder as rec
    from twil_control.launch import runner

    seen = []
    flush = rec.BagRecorder.flush

    def spy(self):
        seen.append(sys.getswitchinterval())
        flush(self)

    monkeypatch.setattr(rec.BagRecorder, "flush", spy)
    before = sys.getswitchinterval()
    result = run(load_launch(LAUNCH, {}), RunOptions(duration=0.2, bag=tmp_path / "a.bag"))
    assert result.error is None and len(seen) == 5  # one flush per 0.05 s slice, one at close
    assert seen[:4] == pytest.approx([runner.SWITCH_INTERVAL] * 4, rel=1e-6)
    assert runner.SWITCH_INTERVAL < 0.001 < before  # shorter than the default it replaces
    assert sys.getswitchinterval() == before

    def fail_once(self):  # the run fails; the recorder's own flush at close works
        monkeypatch.setattr(rec.BagRecorder, "flush", flush)
        raise RuntimeError("a node failed")

    monkeypatch.setattr(rec.BagRecorder, "flush", fail_once)
    result = run(load_launch(LAUNCH, {}), RunOptions(duration=0.2, bag=tmp_path / "b.bag"))
    assert isinstance(result.error, RuntimeError)
    assert sys.getswitchinterval() == before


def test_a_second_ctrl_c_while_the_bag_closes_does_not_break_the_close(tmp_path, monkeypatch):
    # a sweep's worker repeats SIGINT every 0.5 s until the launch exits, and people press
    # Ctrl-C twice: the run's handler stays until the nodes are shut down and the bag is closed
    import os

    from twil_control.bag import recorder as rec
    from twil_control.bag.reader import Bag

    close = rec.BagRecorder.close

    def interrupted_close(self):
        os.kill(os.getpid(), signal.SIGINT)
        return close(self)

    monkeypatch.setattr(rec.BagRecorder, "close", interrupted_close)
    before = signal.getsignal(signal.SIGINT)  # SIG_IGN when pytest runs in a background job
    result = run(load_launch(LAUNCH, {}), RunOptions(duration=0.2, bag=tmp_path / "a.bag"))
    assert result.error is None and result.bag == tmp_path / "a.bag"
    assert result.messages > 0 and len(list(Bag(result.bag).messages("/joint_states"))) > 0
    assert signal.getsignal(signal.SIGINT) is before  # restored after
