"""Every way a launch can end leaves the bag it promises: signals (SIGTERM, SIGHUP, a closed
terminal, Ctrl-C before time starts), a hard kill (SIGKILL), a full disk, a bag name taken
during the run. The launch runs in a child process, as a user's shell, systemd or docker runs
it; a test node (tests/support/stop_nodes.py) ends it from inside at an exact simulated time."""

from __future__ import annotations

import fcntl
import os
import resource
import signal
import subprocess
import sys
import termios
import time
from pathlib import Path

import pytest
from conftest import bag_connections
from support import stop_nodes

from twil_control import PACKAGE_ROOT
from twil_control.bag import format as fmt
from twil_control.bag.__main__ import main as bag_main
from twil_control.bag.reader import Bag
from twil_control.launch.runner import SLICE

TWIL_SIM = "$(find twil_control)/launch/twil_sim.launch.yaml"
TWIL_SIM_FILE = str(PACKAGE_ROOT / "launch/twil_sim.launch.yaml")


def _launch_file(tmp_path: Path, *nodes: str) -> Path:
    """twil_sim with extra nodes ('pkg/type args')."""
    lines = ["launch:", f'  - include: {{file: "{TWIL_SIM}"}}']
    for i, node in enumerate(nodes):
        key, args = node.split(" ", 1)
        pkg, typ = key.split("/")
        lines.append(f'  - node: {{pkg: {pkg}, type: {typ}, name: n{i}, args: "{args}"}}')
    path = tmp_path / "run.launch.yaml"
    path.write_text("\n".join(lines) + "\n")
    return path


def _run_child(*args: str, preexec_fn=None, timeout: float = 180) -> subprocess.CompletedProcess:
    return subprocess.run(
        stop_nodes.child_command(*args),
        capture_output=True,
        text=True,
        timeout=timeout,
        preexec_fn=preexec_fn,
        env=dict(os.environ, PYTHONUNBUFFERED="1"),
    )


def _last_stamp(bag: Path, topic: str = "/joint_states") -> float:
    return max(t for t, _ in Bag(bag).messages(topic)) * 1e-9


@pytest.mark.slow
@pytest.mark.parametrize("sig", ["SIGTERM", "SIGHUP"])
def test_sigterm_and_sighup_close_the_bag_like_ctrl_c(tmp_path, sig):
    bag = tmp_path / "run.bag"
    launch = _launch_file(tmp_path, f"test_pkg/self_signal --at 2.0 --signal {sig}")
    proc = _run_child(str(launch), "--bag", str(bag))
    assert proc.returncode == 0, proc.stderr  # as roslaunch and Ctrl-C: 0
    assert f"interrupted by {sig}: simulated " in proc.stderr and "Traceback" not in proc.stderr
    stopped = float(proc.stderr.split("simulated ")[1].split(" s")[0])
    assert 2.0 <= stopped <= 2.0 + SLICE  # at the end of the signal's time slice
    assert bag.exists() and not Path(f"{bag}.active").exists()
    # nothing lost: every message up to the time the run stopped (100 Hz)
    assert _last_stamp(bag) == pytest.approx(stopped, abs=0.011)
    assert bag_connections(bag)["/joint_states"][2] == pytest.approx(100 * stopped, abs=1.5)


@pytest.mark.slow
def test_a_closed_terminal_ends_the_run_with_the_bag_closed(tmp_path):
    """The real SIGHUP: the launch's controlling terminal (a pty) goes away mid-run, and its
    output (progress line, log) then fails to write."""
    bag = tmp_path / "run.bag"
    master, slave = os.openpty()

    def own_terminal():
        fcntl.ioctl(0, termios.TIOCSCTTY, 0)

    env = dict(os.environ, PYTHONUNBUFFERED="1")
    env.pop("CI", None)  # the progress line is drawn on a terminal
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "twil_control.launch",
            str(_launch_file(tmp_path)),
            "--realtime",
            "1",
            "--bag",
            str(bag),
        ],
        stdin=slave,
        stdout=slave,
        stderr=slave,
        start_new_session=True,
        preexec_fn=own_terminal,
        env=env,
    )
    os.close(slave)
    deadline = time.monotonic() + 120
    output, started = b"", None
    while started is None or time.monotonic() < started + 1.5:  # 1.5 s after time starts
        output += _read_available(master)
        if started is None and Path(f"{bag}.active").exists():
            started = time.monotonic()
        assert proc.poll() is None and time.monotonic() < deadline, output
    os.close(master)  # the terminal window is closed
    assert proc.wait(timeout=60) == 0
    assert bag.exists() and not Path(f"{bag}.active").exists()
    assert fmt.read_index(bag).chunks and _last_stamp(bag) > 0.1  # closed, indexed, what ran


def _read_available(fd: int) -> bytes:
    """Drain the pty (a child writing to a full one would block)."""
    import select

    ready, _, _ = select.select([fd], [], [], 0.05)
    try:
        return os.read(fd, 65536) if ready else b""
    except OSError:
        return b""


@pytest.mark.slow
def test_a_hard_kill_loses_at_most_a_chunk_and_info_agrees_with_reindex(tmp_path, capsys):
    bag = tmp_path / "run.bag"
    active = Path(f"{bag}.active")
    launch = _launch_file(tmp_path, "test_pkg/self_signal --at 3.5 --signal SIGKILL")
    proc = _run_child(str(launch), "--bag", str(bag))
    assert proc.returncode == -signal.SIGKILL
    assert active.exists() and not bag.exists()
    # bag info says what is recoverable; reindex recovers exactly that
    assert bag_main(["info", str(active)]) == 2
    err = capsys.readouterr().err
    claimed = int(err.split(" complete messages")[0].rsplit(" ", 1)[1])
    fixed = tmp_path / "fixed.bag"
    assert bag_main(["reindex", str(active), "-o", str(fixed)]) == 0
    assert f"recovered {claimed} messages" in capsys.readouterr().out
    assert Bag(fixed).message_count == claimed
    # at most one chunk (1 simulated s) and the last slice are lost
    lost = 3.5 - _last_stamp(fixed)
    assert 0 < lost <= 1.0 + SLICE, lost
    assert bag_connections(fixed)["/joint_states"][2] >= 100 * (3.5 - 1.0 - SLICE)


def _file_size_limit(limit: int):
    """A child whose files cannot grow past `limit` bytes (RLIMIT_FSIZE): writes past it fail
    with EFBIG, as they fail with ENOSPC on a full disk (SIGXFSZ ignored, as a full disk sends
    none)."""

    def apply():
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))

    return apply


@pytest.mark.slow
def test_a_full_disk_mid_run_closes_the_bag_with_the_chunks_before_and_exits_1(tmp_path):
    bag = tmp_path / "run.bag"
    proc = _run_child(
        TWIL_SIM_FILE, "--duration", "5", "--bag", str(bag), preexec_fn=_file_size_limit(120_000)
    )
    assert proc.returncode == 1, proc.stderr
    err = proc.stderr
    assert "file size limit reached (EFBIG) at t = " in err and " free on " in err
    assert "recording stopped" in err and "nothing was run" not in err
    assert bag.exists() and not Path(f"{bag}.active").exists()
    index = fmt.read_index(bag)  # closed and indexed
    assert 0 < len(index.chunks) < 5 and bag.stat().st_size <= 120_000
    failed_at = float(err.split("at t = ")[1].split(" s")[0])
    assert failed_at - 1.0 - SLICE <= _last_stamp(bag) < failed_at


@pytest.mark.slow
def test_no_space_at_start_runs_nothing_and_leaves_no_file(tmp_path):
    bag = tmp_path / "run.bag"
    # below --min-space: refused before anything runs
    proc = _run_child(TWIL_SIM_FILE, "--duration", "1", "--bag", str(bag), "--min-space", "1000000000G")
    assert proc.returncode == 2 and "less than --min-space" in proc.stderr
    assert list(tmp_path.iterdir()) == []
    # a disk that cannot take even the bag's header: no 0-byte .active left behind
    proc = _run_child(
        TWIL_SIM_FILE,
        "--duration",
        "1",
        "--bag",
        str(bag),
        "--min-space",
        "0",
        preexec_fn=_file_size_limit(1000),
    )
    assert proc.returncode == 2, proc.stderr
    assert f"cannot create {bag}.active: file size limit reached (EFBIG)" in proc.stderr
    assert list(tmp_path.iterdir()) == []


@pytest.mark.slow
def test_ctrl_c_before_time_starts_exits_0_quietly(tmp_path):
    """SIGINT at several moments of the start (imports, launch file, diagram build): exit 0,
    no traceback, no bag or .active file; once time runs it is an ordinary interrupted run."""
    before_time = 0
    for i, delay in enumerate([0.0, 0.3, 0.7, 1.2, 2.0]):
        bag = tmp_path / f"run{i}.bag"
        proc = subprocess.Popen(
            [
                sys.executable,
                "-m",
                "twil_control.launch",
                TWIL_SIM_FILE,
                "--duration",
                "2",
                "--bag",
                str(bag),
            ],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            env=dict(os.environ, PYTHONUNBUFFERED="1"),
        )
        _wait_until_main_runs(proc)
        time.sleep(delay)
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=120)
        assert proc.returncode == 0, (delay, err)
        assert "Traceback" not in err and "KeyboardInterrupt" not in err, (delay, err)
        assert not Path(f"{bag}.active").exists()
        if "interrupted by SIGINT before time started: nothing was run, no bag written" in err:
            before_time += 1
            assert not bag.exists()
        else:
            assert bag.exists()
    assert before_time >= 3  # most of the moments fall in the start, as intended


@pytest.mark.slow
@pytest.mark.parametrize("sig", ["SIGTERM", "SIGHUP"])
def test_sigterm_and_sighup_before_time_starts_exit_0_quietly(tmp_path, sig):
    """timeout, docker stop or a closed terminal while the launch is still importing: the same
    quiet exit 0 as Ctrl-C, naming the signal, nothing written (the default would be death by
    the signal, exit -15 or -1)."""
    bag = tmp_path / "run.bag"
    proc = subprocess.Popen(
        [sys.executable, "-m", "twil_control.launch", TWIL_SIM_FILE, "--duration", "2", "--bag", str(bag)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=dict(os.environ, PYTHONUNBUFFERED="1"),
    )
    _wait_until_main_runs(proc)
    time.sleep(0.3)  # importing pydrake and the nodes: well before time starts
    proc.send_signal(getattr(signal, sig))
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 0, err
    assert f"interrupted by {sig} before time started: nothing was run, no bag written" in err
    assert "Traceback" not in err
    assert not bag.exists() and not Path(f"{bag}.active").exists()


def _wait_until_main_runs(proc: subprocess.Popen) -> None:
    """Until the launch's main() runs: it has loaded numpy, which nothing imports before main()
    does (a SIGINT before that, while the interpreter itself starts, is Python's to handle)."""
    maps = Path(f"/proc/{proc.pid}/maps")
    deadline = time.monotonic() + 60
    while "numpy" not in maps.read_text():
        assert proc.poll() is None and time.monotonic() < deadline
        time.sleep(0.005)


@pytest.mark.slow
def test_a_bag_that_appeared_during_the_run_is_not_replaced(tmp_path):
    bag = tmp_path / "run.bag"
    launch = _launch_file(tmp_path, f"test_pkg/file_maker --at 0.2 --path {bag}")
    proc = _run_child(str(launch), "--duration", "0.5", "--bag", str(bag))
    assert proc.returncode == 1, proc.stderr
    assert f"{bag} appeared during the run and is not replaced" in proc.stderr
    assert bag.read_text() == "precious"
    active = Path(f"{bag}.active")
    assert _last_stamp(active) == pytest.approx(0.5, abs=0.011)  # complete, indexed
    assert fmt.read_index(active).chunks
