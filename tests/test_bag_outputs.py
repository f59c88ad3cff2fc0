"""The bag commands that write a file never overwrite one: an existing output is refused with
exit code 2 and left as it was, unless --force; a file appearing while a command works is not
overwritten either."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import read_bag, write_bag

from twil_control.bag import output
from twil_control.bag.__main__ import main
from twil_control.bag.bag_errors import BagError
from twil_control.core import messages


@pytest.fixture
def odom_bag(tmp_path):
    """A short qbot-like bag: odometry moving along x (what plot, xy, export and analyze read)."""
    odom = messages.msg_class("nav_msgs/Odometry")
    cls = messages.msg_class
    msgs = []
    for i in range(50):
        t = 0.1 * i
        msgs.append(
            (
                t,
                odom(
                    header=messages.header("odom", t),
                    child_frame_id="base_link",
                    pose=cls("geometry_msgs/PoseWithCovariance")(
                        pose=cls("geometry_msgs/Pose")(
                            position=cls("geometry_msgs/Point")(x=0.1 * t, y=0.0, z=0.0),
                            orientation=cls("geometry_msgs/Quaternion")(x=0.0, y=0.0, z=0.0, w=1.0),
                        ),
                        covariance=np.zeros(36),
                    ),
                    twist=cls("geometry_msgs/TwistWithCovariance")(
                        twist=cls("geometry_msgs/Twist")(
                            linear=cls("geometry_msgs/Vector3")(x=0.1, y=0.0, z=0.0),
                            angular=cls("geometry_msgs/Vector3")(x=0.0, y=0.0, z=0.0),
                        ),
                        covariance=np.zeros(36),
                    ),
                ),
            )
        )
    return write_bag(tmp_path / "in.bag", {"/odom": msgs})


X = "/odom/pose/pose/position/x"
COMMANDS = {
    "plot": lambda bag, out: ["plot", bag, X, "-o", out],
    "xy": lambda bag, out: ["xy", bag, f"{X}:/odom/pose/pose/position/y", "-o", out],
    "analyze": lambda bag, out: ["analyze", bag, "-o", out],
    "export": lambda bag, out: ["export", bag, "/odom", "-o", out],
    "reindex": lambda bag, out: ["reindex", bag, "-o", out],
}
SUFFIX = {"plot": ".png", "xy": ".svg", "analyze": ".html", "export": ".csv", "reindex": ".bag"}


@pytest.mark.parametrize("command", list(COMMANDS))
def test_an_existing_output_is_refused_unless_forced(command, odom_bag, tmp_path, capsys):
    out = tmp_path / f"out{SUFFIX[command]}"
    out.write_text("precious")
    argv = [str(a) for a in COMMANDS[command](odom_bag, out)]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert f"{out} exists; it is never overwritten: choose another name, or add --force" in err
    assert err.count("\n") == 1 and out.read_text() == "precious"
    assert main(argv + ["--force"]) == 0
    assert out.read_bytes() != b"precious" and out.stat().st_size > 100
    if command == "reindex":
        assert len(read_bag(out)["/odom"]) == 50


def test_a_markdown_report_also_refuses_an_existing_figures_folder(odom_bag, tmp_path, capsys):
    (tmp_path / "report_files").mkdir()
    assert main(["analyze", str(odom_bag), "-o", str(tmp_path / "report.md")]) == 2
    assert "report_files exists" in capsys.readouterr().err
    assert not (tmp_path / "report.md").exists()


def test_a_file_that_appears_while_a_command_works_is_not_overwritten(tmp_path):
    out = output.check_new_output(tmp_path / "late.csv", "output")
    out.write_text("precious")  # appeared after the check
    with pytest.raises(BagError, match="appeared meanwhile; it is never overwritten"):
        output.open_new(out)
    assert out.read_text() == "precious"
    with output.open_new(out, force=True, mode="w") as f:
        f.write("replaced")
    assert out.read_text() == "replaced"


def test_link_new_refuses_an_existing_name_even_without_hard_links(tmp_path, monkeypatch):
    src, dst = tmp_path / "a.bag.active", tmp_path / "a.bag"
    src.write_text("new")
    dst.write_text("precious")
    with pytest.raises(FileExistsError):
        output.link_new(src, dst)

    def no_links(a, b):
        raise PermissionError(1, "Operation not permitted")  # a filesystem without hard links

    monkeypatch.setattr(output.os, "link", no_links)
    with pytest.raises(FileExistsError):
        output.link_new(src, dst)
    assert dst.read_text() == "precious" and src.read_text() == "new"
    dst.unlink()
    output.link_new(src, dst)
    assert dst.read_text() == "new" and not src.exists()
