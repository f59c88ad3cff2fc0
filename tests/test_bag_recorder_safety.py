"""What the recorder keeps when a run ends badly, checked on the recorder itself (no Drake):
chunks capped by simulated time and in the file once closed, a full disk, a bag name taken
during the run, and bag info agreeing with reindex on what an unindexed bag holds."""

from __future__ import annotations

import errno
import logging
import os
import threading

import numpy as np
import pytest
from rosbags.rosbag1 import Reader

from twil_control.bag import chunk_file
from twil_control.bag import format as fmt
from twil_control.bag import recorder as rec
from twil_control.bag.__main__ import main as bag_main
from twil_control.bag.bag_errors import UnindexedBagError
from twil_control.bag.reader import Bag
from twil_control.bag.recorder import BagRecorder, RecorderError, check_writable, parse_size
from twil_control.core import messages
from twil_control.core.bus import Bus

RATE = 100  # Hz, like /joint_states
SLICE = 0.05


def _record(recorder: BagRecorder, bus: Bus, start: float, end: float, pub) -> None:
    """Publish a Float64MultiArray of 100 values at RATE from start to end, flushing every
    SLICE as the runner does."""
    cls = messages.msg_class("std_msgs/Float64MultiArray")
    layout = messages.msg_class("std_msgs/MultiArrayLayout")(dim=[], data_offset=0)
    k = int(round(start * RATE))
    while k < int(round(end * RATE)):
        t = k / RATE
        bus.clock.set(t)
        pub.publish(cls(layout=layout, data=np.full(100, float(k))))
        k += 1
        if k % int(RATE * SLICE) == 0:
            bus.clock.set(k / RATE)
            recorder.flush()


def _recorder(tmp_path, **kw) -> tuple[BagRecorder, Bus, object]:
    bus = Bus()
    recorder = BagRecorder(tmp_path / "run.bag", bus, **kw)
    pub = bus.advertise("/data", "std_msgs/Float64MultiArray", node="/t")
    return recorder, bus, pub


def _stamps(path) -> list[float]:
    return [t * 1e-9 for t, _ in Bag(path).messages("/data")]


def test_a_chunk_holds_at_most_chunk_seconds_of_simulated_time(tmp_path):
    recorder, bus, pub = _recorder(tmp_path, chunk_seconds=1.0)
    _record(recorder, bus, 0.0, 5.5, pub)
    recorder.close()
    chunks = fmt.read_index(tmp_path / "run.bag").chunks
    assert len(chunks) == 6
    assert all(c.end - c.start < 1e9 for c in chunks)
    assert [round(c.start * 1e-9, 2) for c in chunks] == [0.0, 1.0, 2.0, 3.0, 4.0, 5.0]
    # 0: by size only (rosbags' 1 MiB): 550 messages of 0.8 kB fit in one chunk
    (tmp_path / "size_only").mkdir()
    recorder, bus, pub = _recorder(tmp_path / "size_only", chunk_seconds=0)
    _record(recorder, bus, 0.0, 5.5, pub)
    recorder.close()
    assert len(fmt.read_index(tmp_path / "size_only" / "run.bag").chunks) == 1


def test_a_closed_chunk_is_in_the_file_while_the_recorder_runs(tmp_path):
    """What a hard kill leaves: everything but the open chunk (and the last slice's messages)."""
    recorder, bus, pub = _recorder(tmp_path)
    _record(recorder, bus, 0.0, 3.5, pub)
    active = tmp_path / "run.bag.active"
    on_disk = fmt.scan(active)  # read by another reader, the recorder still open
    assert on_disk.chunks == 3 and on_disk.messages == 300  # t in [0, 3): 300 messages
    # a stream that goes quiet still reaches the file: one message at t = 3.6, then nothing
    bus.clock.set(3.6)
    pub.publish(
        messages.msg_class("std_msgs/Float64MultiArray")(
            layout=messages.msg_class("std_msgs/MultiArrayLayout")(dim=[], data_offset=0), data=np.zeros(1)
        )
    )
    for t in (4.0, 4.5, 4.55):
        bus.clock.set(t)
        recorder.flush()
    assert fmt.scan(active).messages == 300 + 50 + 1  # [3, 3.5) and the one at 3.6
    recorder.close()


def _disk_full_from_now(monkeypatch) -> None:
    """Every write of the bag writer from now on fails as on a full disk."""

    def pwrite(fd, data, pos):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(chunk_file.os, "pwrite", pwrite)


def test_a_full_disk_stops_the_recording_and_the_bag_is_closed_with_the_chunks_before(tmp_path, monkeypatch):
    recorder, bus, pub = _recorder(tmp_path)
    _record(recorder, bus, 0.0, 2.5, pub)  # two chunks written
    # the third chunk fails (half of it written, then ENOSPC); the index fits after it
    real = os.pwrite
    state = {"failed": False}

    def pwrite(fd, data, pos):
        if not state["failed"]:  # the next write, the third chunk's
            state["failed"] = True
            real(fd, bytes(data[: len(data) // 2]), pos)
            raise OSError(errno.ENOSPC, "No space left on device")
        return real(fd, data, pos)

    monkeypatch.setattr(chunk_file.os, "pwrite", pwrite)
    with pytest.raises(RecorderError) as e:
        _record(recorder, bus, 2.5, 4.0, pub)
    text = str(e.value)
    assert "disk full (ENOSPC) at t = 3.000 s" in text and "free on" in text
    assert "recording stopped; 200 messages in 2 chunks written before are kept" in text
    _record(recorder, bus, 4.0, 4.5, pub)  # nothing more is recorded
    path = recorder.close()
    assert path == tmp_path / "run.bag" and not (tmp_path / "run.bag.active").exists()
    assert recorder.failure is not None and recorder.count == 200
    with Reader(path) as r:  # rosbags reads it: a valid, indexed bag
        assert r.message_count == 200
    assert _stamps(path) == pytest.approx([k / RATE for k in range(200)])


def test_when_the_index_does_not_fit_the_active_file_is_kept_with_how_to_recover_it(
    tmp_path, monkeypatch, caplog
):
    recorder, bus, pub = _recorder(tmp_path)
    _record(recorder, bus, 0.0, 2.5, pub)
    _disk_full_from_now(monkeypatch)
    with pytest.raises(RecorderError):
        _record(recorder, bus, 2.5, 4.0, pub)
    with caplog.at_level(logging.ERROR):
        path = recorder.close()
    active = tmp_path / "run.bag.active"
    assert path == active and active.exists() and not (tmp_path / "run.bag").exists()
    assert "could not be closed" in recorder.failure
    assert (
        f"recover them with: python -m twil_control.bag reindex {active} -o {tmp_path / 'run.bag'}"
        in caplog.text
    )
    monkeypatch.undo()
    assert pytest.raises(UnindexedBagError, fmt.read_index, active).value.messages == 200
    assert bag_main(["reindex", str(active), "-o", str(tmp_path / "fixed.bag")]) == 0
    assert _stamps(tmp_path / "fixed.bag") == pytest.approx([k / RATE for k in range(200)])


def test_a_disk_that_cannot_take_the_bag_header_leaves_no_file(tmp_path, monkeypatch):
    def full(self, raw, fsync):  # the header's write to the file fails
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(chunk_file.ChunkFile, "__init__", full)
    with pytest.raises(RecorderError, match=r"cannot create .*run\.bag\.active: disk full \(ENOSPC\)"):
        BagRecorder(tmp_path / "run.bag", Bus())
    assert list(tmp_path.iterdir()) == []


def test_min_space_is_checked_at_start_and_warned_about_while_recording(tmp_path, monkeypatch, caplog):
    free = {"bytes": 10 << 20}
    monkeypatch.setattr(rec, "free_space", lambda folder: free["bytes"])
    with pytest.raises(RecorderError, match=r"only 10\.0 MB free on .* less than --min-space 1\.0 GB"):
        check_writable(tmp_path / "run.bag", min_space=parse_size("1G"))
    assert list(tmp_path.iterdir()) == []
    free["bytes"] = 3 << 30
    recorder, bus, pub = _recorder(tmp_path, min_space=2 << 30)
    with caplog.at_level(logging.WARNING):
        _record(recorder, bus, 0.0, 1.5, pub)
        assert "less than --min-space" not in caplog.text
        free["bytes"] = 1 << 30
        _record(recorder, bus, 1.5, 4.5, pub)  # three more chunks: one warning
    recorder.close()
    assert caplog.text.count("1.0 GB free on") == 1 and "less than --min-space 2.0 GB" in caplog.text


@pytest.mark.parametrize(
    "text, value",
    [("1G", 1 << 30), ("500M", 500 << 20), ("64k", 65536), ("0", 0), ("1.5G", 3 << 29), ("123", 123)],
)
def test_min_space_takes_rosbag_record_sizes(text, value):
    assert parse_size(text) == value


def test_min_space_refuses_other_text():
    with pytest.raises(ValueError, match=r"--min-space '1 GiB'.*1G or 500M"):
        parse_size("1 GiB")


def test_the_close_never_replaces_a_bag_that_appeared_during_the_run(tmp_path, caplog):
    recorder, bus, pub = _recorder(tmp_path)
    _record(recorder, bus, 0.0, 1.5, pub)
    (tmp_path / "run.bag").write_text("precious")
    with caplog.at_level(logging.ERROR):
        path = recorder.close()
    active = tmp_path / "run.bag.active"
    assert path == active and (tmp_path / "run.bag").read_text() == "precious"
    assert "appeared during the run and is not replaced" in recorder.failure
    assert f"complete and indexed in {active}" in caplog.text
    assert len(fmt.read_index(active).chunks) == 2  # indexed: only its name is .active
    assert _stamps(active) == pytest.approx([k / RATE for k in range(150)])


def test_info_and_reindex_agree_when_the_file_ends_in_a_chunk_s_index_data(tmp_path, capsys):
    """A kill between a chunk and the index data after it: bag info's count of recoverable
    messages is what reindex recovers."""
    recorder, bus, pub = _recorder(tmp_path)
    _record(recorder, bus, 0.0, 3.5, pub)
    recorder._writer.abort()
    active = tmp_path / "run.bag.active"
    data = active.read_bytes()
    # the end of the last complete chunk record, then 10 bytes into its index data record
    ends = []
    with active.open("rb") as f:
        f.seek(len(fmt.MAGIC))
        size = len(data)
        while True:
            try:
                h, pos, n = fmt._read_record(f, size)
            except fmt._Truncated:
                break
            if fmt._op(h) == fmt.OP_CHUNK:
                ends.append(pos + n)
            f.seek(pos + n)
    cut = tmp_path / "cut.bag.active"
    cut.write_bytes(data[: ends[-1] + 10])
    assert bag_main(["info", str(cut)]) == 2
    err = capsys.readouterr().err
    claimed = int(err.split(" complete messages")[0].rsplit(" ", 1)[1])
    assert bag_main(["reindex", str(cut), "-o", str(tmp_path / "fixed.bag")]) == 0
    out = capsys.readouterr().out
    assert f"recovered {claimed} messages" in out
    assert claimed == len(_stamps(tmp_path / "fixed.bag")) == 300


def test_fdatasync_runs_beside_the_recording_and_the_last_one_covers_the_closed_file(tmp_path, monkeypatch):
    """The recorder never waits for the disk: while one fdatasync is held up, chunks go on being
    written and no second one starts; close waits for a last one of the whole file."""
    held, release, synced_sizes, starts = threading.Event(), threading.Event(), [], []

    def slow_fdatasync(fd):
        starts.append(fd)
        held.set()
        assert release.wait(30)
        synced_sizes.append(os.fstat(fd).st_size)

    monkeypatch.setattr(chunk_file.os, "fdatasync", slow_fdatasync)
    recorder, bus, pub = _recorder(tmp_path, fsync=True)
    _record(recorder, bus, 0.0, 1.5, pub)
    assert held.wait(30)  # the first chunk's sync runs, held
    _record(recorder, bus, 1.5, 4.5, pub)  # three more chunks meanwhile
    assert fmt.scan(tmp_path / "run.bag.active").chunks == 4
    assert synced_sizes == [] and len(starts) == 1
    release.set()
    path = recorder.close()
    assert len(synced_sizes) >= 2 and synced_sizes[-1] == path.stat().st_size


def test_an_fdatasync_error_stops_the_recording_at_the_next_chunk(tmp_path, monkeypatch):
    failed = threading.Event()

    def failing(fd):
        failed.set()
        raise OSError(errno.EIO, "Input/output error")

    monkeypatch.setattr(chunk_file.os, "fdatasync", failing)
    recorder, bus, pub = _recorder(tmp_path, fsync=True)
    _record(recorder, bus, 0.0, 1.5, pub)  # the first chunk, then its sync fails
    assert failed.wait(30)  # (kept by the sync thread just after)
    with pytest.raises(RecorderError, match=r"Input/output error at t = [23]\.000 s"):
        _record(recorder, bus, 1.5, 3.5, pub)
    recorder.close()


def test_info_and_reindex_agree_on_an_mcap_file_cut_by_a_kill(tmp_path, capsys):
    bus = Bus()
    recorder = BagRecorder(tmp_path / "run.mcap", bus)
    pub = bus.advertise("/data", "std_msgs/Float64MultiArray", node="/t")
    _record(recorder, bus, 0.0, 3.5, pub)
    data = (tmp_path / "run.mcap.active").read_bytes()
    recorder.close()
    cut = tmp_path / "cut.mcap.active"
    cut.write_bytes(data[:-20])  # the kill came while the last chunk's indexes were written
    assert bag_main(["info", str(cut)]) == 2
    err = capsys.readouterr().err
    claimed = int(err.split(" complete messages")[0].rsplit(" ", 1)[1])
    assert f"recover them with: python -m twil_control.bag reindex {cut} -o NEW.mcap" in err
    assert bag_main(["reindex", str(cut), "-o", str(tmp_path / "fixed.mcap")]) == 0
    assert f"recovered {claimed} messages" in capsys.readouterr().out
    assert claimed == len(_stamps(tmp_path / "fixed.mcap")) == 300


def test_a_full_disk_while_recording_mcap_keeps_the_chunks_before_for_reindex(tmp_path, monkeypatch, caplog):
    """An MCAP file gets no summary after a failed write (the mcap Writer would index the chunk
    cut off): it stays .active, and the log says how to recover its chunks."""
    bus = Bus()
    recorder = BagRecorder(tmp_path / "run.mcap", bus)
    pub = bus.advertise("/data", "std_msgs/Float64MultiArray", node="/t")
    _record(recorder, bus, 0.0, 2.5, pub)
    _disk_full_from_now(monkeypatch)
    with pytest.raises(RecorderError, match=r"disk full \(ENOSPC\) at t = 3\.000 s"):
        _record(recorder, bus, 2.5, 4.0, pub)
    with caplog.at_level(logging.ERROR):
        path = recorder.close()
    monkeypatch.undo()
    assert path == tmp_path / "run.mcap.active" and not (tmp_path / "run.mcap").exists()
    assert f"reindex {path} -o {tmp_path / 'run.mcap'}" in caplog.text
    assert bag_main(["reindex", str(path), "-o", str(tmp_path / "run.mcap")]) == 0
    assert _stamps(tmp_path / "run.mcap") == pytest.approx([k / RATE for k in range(200)])


def test_the_close_writes_what_was_published_since_the_last_flush(tmp_path):
    """A run stopped within a time slice (a required node failing): its messages are kept."""
    recorder, bus, pub = _recorder(tmp_path)
    _record(recorder, bus, 0.0, 1.03, pub)  # flushed up to 1.0, then three more published
    recorder.close()
    assert _stamps(tmp_path / "run.bag") == pytest.approx([k / RATE for k in range(103)])
