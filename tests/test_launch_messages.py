"""Error messages that name what to fix (issue 35, item 11): an include chain deeper than
roslaunch trees go is refused with its chain, not Python's recursion limit; a node's `model`
parameter naming no spawned model names the node, the parameter and where it was set; a
--view-port in use names the option and the port."""

from __future__ import annotations

import socket
import subprocess
import sys

import pytest

from twil_control import PACKAGE_ROOT
from twil_control.launch.loader import load_launch
from twil_control.launch.plan import LaunchError
from twil_control.launch.scoping import MAX_INCLUDE_DEPTH


def test_a_2000_deep_include_chain_is_refused_with_its_chain(tmp_path):
    n = 2000
    for i in range(n):
        body = f'<include file="f{i + 1}.launch"/>' if i < n - 1 else '<param name="x" value="1"/>'
        (tmp_path / f"f{i}.launch").write_text(f"<launch>\n  {body}\n</launch>\n")
    with pytest.raises(LaunchError) as error:
        load_launch(tmp_path / "f0.launch", {})
    text = str(error.value)
    assert text.startswith(f"{tmp_path / f'f{MAX_INCLUDE_DEPTH - 1}.launch'}:2:3: includes nest more than")
    assert f"{tmp_path / 'f0.launch'} -> {tmp_path / 'f1.launch'} -> ... 97 more ..." in text
    assert "recursion" not in text and "\n" not in text


def _launch(tmp_path, *args: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [
            sys.executable,
            "-m",
            "twil_control.launch",
            *args,
            "--duration",
            "0.1",
            "--bag",
            str(tmp_path / "r.bag"),
        ],
        capture_output=True,
        text=True,
        timeout=600,
        cwd=tmp_path,
    )


@pytest.mark.slow
def test_a_model_parameter_naming_no_spawned_model_names_node_and_parameter(tmp_path):
    launch = tmp_path / "ghost.launch.yaml"
    launch.write_text(
        "launch:\n"
        "  - arg: {name: model, default: qbot}\n"
        f"  - include: {{file: {PACKAGE_ROOT / 'launch/qbot_sim.launch.yaml'}}}\n"
        "  - node: {pkg: twil_control, type: ground_truth, name: truth_of_ghost,\n"
        "           params: {model: $(arg model)}}\n"
    )
    proc = _launch(tmp_path, str(launch), "model:=ghost")
    assert proc.returncode == 2, proc.stderr
    (line,) = [x for x in proc.stderr.splitlines() if x.startswith("error:")]
    assert "node /truth_of_ghost:" in line and "ghost.launch.yaml:5" in line, line
    assert "parameter '/truth_of_ghost/model' names no spawned model (spawned: qbot) (got 'ghost')" in line
    assert not (tmp_path / "r.bag").exists()


@pytest.mark.slow
def test_a_view_port_in_use_names_the_option_and_the_port(tmp_path):
    with socket.socket() as busy:
        busy.bind(("127.0.0.1", 0))
        busy.listen()
        port = busy.getsockname()[1]
        proc = _launch(
            tmp_path,
            str(PACKAGE_ROOT / "launch/wam_computed_torque.launch.yaml"),
            "--view",
            "--view-port",
            str(port),
        )
    assert proc.returncode == 2, proc.stderr
    (line,) = [x for x in proc.stderr.splitlines() if x.startswith("error:")]
    assert line.startswith(f"error: --view-port {port}: the view cannot serve on 127.0.0.1:{port}"), line
    assert "Address already in use" in line and "choose another port with --view-port PORT" in line
