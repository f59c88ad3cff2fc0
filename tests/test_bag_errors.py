"""Bad input to the bag tools: one line naming the problem, exit code 2, no traceback; and
reindex recovering a crashed recorder's .active file and a truncated bag."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from conftest import read_bag
from conftest import write_bag as _write

from twil_control.bag.__main__ import main
from twil_control.bag.bag_errors import BagError, UnindexedBagError
from twil_control.bag.format import read_index
from twil_control.bag.reader import Bag
from twil_control.bag.recorder import BagRecorder
from twil_control.core import messages
from twil_control.core.bus import Bus


def _float64(v):
    return messages.msg_class("std_msgs/Float64")(data=float(v))


@pytest.fixture
def small_bag(tmp_path):
    js = messages.msg_class("sensor_msgs/JointState")
    return _write(
        tmp_path / "small.bag",
        {
            "/value": [(0.01 * i, _float64(i * 0.5)) for i in range(100)],
            "/joint_states": [
                (
                    0.01 * i,
                    js(
                        header=messages.header("", 0.01 * i),
                        name=["a", "b"],
                        position=np.array([i, -i], float),
                        velocity=np.zeros(2),
                        effort=np.zeros(2),
                    ),
                )
                for i in range(100)
            ],
        },
    )


def _run_cli(capsys, *argv) -> tuple[int, str]:
    code = main(list(argv))
    err = capsys.readouterr().err
    return code, err


def test_missing_file_non_bag_and_empty_file_are_one_line_errors(tmp_path, capsys):
    code, err = _run_cli(capsys, "info", str(tmp_path / "nope.bag"))
    assert code == 2 and err == f"error: {tmp_path / 'nope.bag'}: no such file\n"
    text = tmp_path / "notes.bag"
    text.write_text("hello\n")
    code, err = _run_cli(capsys, "info", str(text))
    assert code == 2 and "is not a ROS bag" in err and err.count("\n") == 1
    empty = tmp_path / "empty.bag"
    empty.write_bytes(b"")
    code, err = _run_cli(capsys, "analyze", str(empty))
    assert code == 2 and "empty file" in err
    v1 = tmp_path / "old.bag"
    v1.write_bytes(b"#ROSBAG V1.2\n" + b"\0" * 20)
    code, err = _run_cli(capsys, "info", str(v1))
    assert code == 2 and "format 1.2 is not supported" in err


def test_unknown_topic_and_field_list_the_choices_with_a_did_you_mean(small_bag, tmp_path, capsys):
    code, err = _run_cli(
        capsys, "plot", str(small_bag), "/joint_state/position[0]", "-o", str(tmp_path / "a.png")
    )
    assert code == 2
    assert "did you mean /joint_states?" in err and "its topics: /joint_states, /value" in err
    code, err = _run_cli(
        capsys, "plot", str(small_bag), "/joint_states/positon[0]", "-o", str(tmp_path / "a.png")
    )
    assert code == 2 and "has no field 'positon[0]' (did you mean position[0]" in err
    assert "its fields: effort, header, name, position, velocity" in err
    code, err = _run_cli(
        capsys, "plot", str(small_bag), "/joint_states/position[5]", "-o", str(tmp_path / "a.png")
    )
    assert code == 2 and "index out of range (position has 2 elements" in err
    code, err = _run_cli(capsys, "export", str(small_bag), "/valeu", "-o", str(tmp_path / "a.csv"))
    assert code == 2 and "topic '/valeu' is not in" in err and "did you mean /value?" in err
    code, err = _run_cli(capsys, "plot", str(small_bag), "/value/data", "-o", str(tmp_path / "a.jpg"))
    assert code == 2 and "must be one of .png, .svg, .pdf" in err
    code, err = _run_cli(capsys, "play", str(small_bag), "--rate", "-1")
    assert code == 2 and "--rate must be >= 0" in err
    code, err = _run_cli(capsys, "analyze", str(small_bag), "--ground-truth-map", str(tmp_path / "m.yaml"))
    assert code == 2 and "no such file" in err
    assert not list(tmp_path.glob("a.*"))


def test_the_module_prints_no_traceback_and_every_command_has_help(tmp_path):
    r = subprocess.run(
        [sys.executable, "-m", "twil_control.bag", "info", str(tmp_path / "x.bag")],
        capture_output=True,
        text=True,
    )
    assert r.returncode == 2 and "Traceback" not in r.stderr and r.stderr.startswith("error: ")
    for cmd in ("info", "plot", "xy", "analyze", "export", "play", "compare", "reindex"):
        with pytest.raises(SystemExit) as done:
            main([cmd, "--help"])
        assert done.value.code == 0


def test_columns_of_messages_with_varying_layout_are_deserialised(tmp_path):
    js = messages.msg_class("sensor_msgs/JointState")
    # the joint names change length: fields are not at fixed offsets any more
    msgs = [
        (
            0.1 * i,
            js(
                header=messages.header("", 0.1 * i),
                name=["j" * (1 + i % 3)],
                position=np.array([i * 1.5]),
                velocity=np.zeros(1),
                effort=np.zeros(1),
            ),
        )
        for i in range(30)
    ]
    bag = Bag(_write(tmp_path / "vary.bag", {"/js": msgs}, compression=False))
    t, cols = bag.columns("/js", ["position[0]", "header.stamp.nanosec"])
    np.testing.assert_array_equal(cols["position[0]"], [i * 1.5 for i in range(30)])
    np.testing.assert_array_equal(t, [int(round(0.1 * i * 1e9)) for i in range(30)])


def _crashed_recording(tmp_path: Path) -> tuple[Path, list]:
    """A recorder killed mid-run: the chunks written so far, no index, the name still .active."""
    bus = Bus()
    path = tmp_path / "run.bag"
    recorder = BagRecorder(path, bus)
    pub = bus.advertise("/big", "std_msgs/Float64MultiArray", node="/t")
    small = bus.advertise("/value", "std_msgs/Float64", node="/t")
    cls = messages.msg_class("std_msgs/Float64MultiArray")
    layout = messages.msg_class("std_msgs/MultiArrayLayout")(dim=[], data_offset=0)
    sent = []
    for i in range(400):  # 8 kB each: about 3 chunks of 1 MB
        bus.clock.set(0.01 * i)
        msg = cls(layout=layout, data=np.full(1000, float(i)))
        pub.publish(msg)
        small.publish(_float64(i))
        sent.append(i)
        recorder.flush()
    recorder._writer.abort()  # the process dies: no index, no rename
    active = tmp_path / "run.bag.active"
    assert active.exists() and not path.exists()
    return active, sent


def test_info_on_a_crashed_recording_says_unindexed_and_how_to_recover(tmp_path, capsys):
    active, _ = _crashed_recording(tmp_path)
    with pytest.raises(UnindexedBagError) as e:
        read_index(active)
    assert e.value.chunks >= 2 and e.value.messages > 0
    code, err = _run_cli(capsys, "info", str(active))
    assert code == 2 and err.count("\n") == 1
    assert "bag has no index (index position 0: the bag was never closed; unindexed" in err
    assert f"recover it with: python -m twil_control.bag reindex {active} -o FIXED.bag" in err


def test_reindex_recovers_every_message_of_the_complete_chunks(tmp_path, capsys):
    active, sent = _crashed_recording(tmp_path)
    recoverable = pytest.raises(UnindexedBagError, read_index, active).value.messages
    fixed = tmp_path / "fixed.bag"
    assert main(["reindex", str(active), "-o", str(fixed)]) == 0
    got = read_bag(fixed)  # rosbags opens it: a valid, indexed bag
    big, value = got["/big"], got["/value"]
    assert len(big) + len(value) == recoverable
    # what survives is a prefix of the run, message for message, with the original stamps
    assert [m.data[0] for _, m in big] == [float(i) for i in range(len(big))]
    assert [m.data for _, m in value] == [float(i) for i in range(len(value))]
    assert [t for t, _ in big] == [int(round(0.01 * i * 1e9)) for i in range(len(big))]
    assert 0 < len(big) < len(sent)
    assert "recovered" in capsys.readouterr().out
    # never overwrites
    code, err = _run_cli(capsys, "reindex", str(active), "-o", str(fixed))
    assert code == 2 and "exists" in err


def test_reindex_recovers_the_complete_records_of_a_chunk_cut_short(small_bag, tmp_path):
    """An uncompressed bag cut in the middle of its only chunk: the messages before the cut."""
    plain = _write(
        tmp_path / "plain.bag", {"/value": [(0.01 * i, _float64(i)) for i in range(200)]}, compression=False
    )
    data = plain.read_bytes()
    cut = tmp_path / "cut.bag"
    cut.write_bytes(data[: len(data) // 2])
    with pytest.raises(BagError, match=rf"truncated at byte {len(data) // 2}, inside a record"):
        Bag(cut)
    fixed = tmp_path / "fixed.bag"
    main(["reindex", str(cut), "-o", str(fixed)])
    values = [m.data for _, m in read_bag(fixed)["/value"]]
    assert values == [float(i) for i in range(len(values))]
    # from rosbags' index of the intact bag: a message is complete if the next record starts
    # (or its chunk ends) before the cut
    from rosbags.rosbag1 import Reader

    with Reader(plain) as r:
        (conn,) = r.connections
        entries = r.indexes[conn.id]
        chunk = r.chunks[entries[0].chunk_pos]
        ends = [chunk.datapos + e.offset for e in entries[1:]] + [chunk.datapos + chunk.datasize]
    assert len(values) == sum(end <= len(data) // 2 for end in ends) > 50
