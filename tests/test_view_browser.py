"""The operator's view in a real browser (headless Chromium): the goal panel drives the simulated
qbot in real time to a goal, switches its controller off, refuses out-of-range values; a
recorded run opens as one HTML file and plays; headless runs create no Meshcat."""

from __future__ import annotations

import json
import re
import subprocess
import sys
import time
import urllib.request

import pytest
from support.view_browser import LaunchProcess, chromium, save_artifact

from twil_control import PACKAGE_ROOT

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def house_map(tmp_path_factory):
    out = tmp_path_factory.mktemp("map") / "house"
    subprocess.run(
        [
            sys.executable,
            "-m",
            "twil_control.tools.rasterize",
            str(PACKAGE_ROOT / "sim/worlds/house.sdf"),
            "-o",
            str(out),
        ],
        check=True,
        capture_output=True,
    )
    return out.with_suffix(".yaml")


def _wait(predicate, timeout: float, what: str):
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        value = predicate()
        if value:
            return value
        time.sleep(0.25)
    raise AssertionError(f"timed out after {timeout} s waiting for {what}")


#: The panel's URL as the launch prints it: the page, and the token the first visit turns into a cookie.
PANEL_URL = r"view: open (http://127\.0\.0\.1:\d+/\?token=[\w-]+)"


def _state(url: str) -> dict:
    """The panel's state, asked as a script does: the token in the Authorization header."""
    base, _, token = url.partition("?token=")
    request = urllib.request.Request(base + "api/state", headers={"Authorization": f"token {token}"})
    with urllib.request.urlopen(request, timeout=5) as r:
        return json.loads(r.read())


@pytest.mark.browser
def test_panel_sends_goal_reaches_it_and_stops_the_controller(tmp_path, root, house_map):
    from selenium.webdriver.common.by import By

    # The launch insists on a goal of its own: one where the robot stands, done at t = 1 s, before ours.
    launch = LaunchProcess(
        [
            str(root / "launch/qbot_navigation.launch.yaml"),
            "slam:=false",
            f"map:={house_map}",
            "goal:=0 0 0",
            "--view",
            "--view-port",
            "0",
            "--duration",
            "300",
            "--no-bag",
        ],
        cwd=tmp_path,
    )
    driver = None
    try:
        url = launch.wait_for(PANEL_URL, 120).group(1)
        driver = chromium(tmp_path / "profile")
        driver.get(url)
        _wait(lambda: (_state(url)["status"] or {}).get("name") == "SUCCEEDED", 90, "the launch's own goal")

        def fill(x, y, ori):
            for key, value in (("x", x), ("y", y), ("ori", ori)):
                box = driver.find_element(By.ID, key)
                box.clear()
                box.send_keys(value)

        # Out of range: refused, the reason shown on the page, nothing sent.
        fill("25", "0", "0")
        driver.find_element(By.ID, "start").click()
        message = driver.find_element(By.ID, "message")
        _wait(lambda: "out of range" in message.text, 10, "the refusal message")
        assert message.is_displayed()
        assert "X = 25 m is out of range: allowed [-20, 20] m" in message.text
        assert _state(url)["status"]["goal"] == "/goals/goal_1"

        # 1 m straight ahead in the free space of the house's first room.
        fill("1", "0", "0")
        driver.find_element(By.ID, "start").click()
        _wait(
            lambda: _state(url)["status"]["goal"].startswith("/move_base-"), 20, "move_base to take our goal"
        )
        # our goal's outcome from the server, then the page showing it (the page polls the state,
        # so right after Start it can still show the launch's own goal's SUCCEEDED)
        _wait(
            lambda: _state(url)["status"]["name"] in ("SUCCEEDED", "ABORTED", "REJECTED"),
            120,
            "the goal's outcome",
        )
        outcome = _state(url)["status"]
        assert outcome["name"] == "SUCCEEDED", outcome["text"]
        status = driver.find_element(By.ID, "status")
        _wait(
            lambda: status.text == "SUCCEEDED" and _state(url)["status"]["goal"] == outcome["goal"],
            10,
            "the page to show our goal's SUCCEEDED",
        )
        x, y, yaw = _state(url)["robot"]
        # within xy_goal_tolerance (0.5 m, config/base_local_planner_params.yaml) of (1, 0), from (0, 0)
        assert ((x - 1.0) ** 2 + y**2) ** 0.5 <= 0.5 + 0.02

        # The controller checkbox: the controller manager lists the drive controller as stopped.
        box = driver.find_element(By.ID, "controller")
        assert box.is_selected()
        box.click()
        _wait(
            lambda: "skid_steer_drive_controller: stopped" in driver.find_element(By.ID, "controllers").text,
            20,
            "the controller to be stopped",
        )
        listed = {c["name"]: c["state"] for c in _state(url)["controllers"]}
        assert listed == {"skid_steer_drive_controller": "stopped"}
        time.sleep(1.0)  # let the 3-D view draw the last plan and scan before the picture
        shot = save_artifact(driver, tmp_path, "view_e2e.png")
        assert shot.stat().st_size > 10_000
    finally:
        if driver is not None:
            driver.quit()
        code = launch.interrupt()
    assert code == 0, "\n".join(launch.lines[-30:])
    m = re.search(r"simulated ([\d.]+) s in ([\d.]+) s \(([\d.]+)x real time\)", "\n".join(launch.lines))
    assert m, "\n".join(launch.lines[-30:])
    sim, wall = float(m.group(1)), float(m.group(2))
    print(f"view on: simulated {sim:.1f} s in {wall:.1f} s wall, real-time factor {sim / wall:.3f}")
    assert sim / wall < 1.02  # paced: never faster than real time (its lower side depends on the machine)


@pytest.mark.browser
def test_panel_refuses_bad_values_in_the_browser(tmp_path, root):
    """Every field's range and a non-number, as the user sees them (a launch without move_base:
    the refusal happens before anything would be sent)."""
    from selenium.webdriver.common.by import By

    launch = LaunchProcess(
        [
            str(root / "launch/qbot_sim.launch.yaml"),
            "--view",
            "--view-port",
            "0",
            "--duration",
            "120",
            "--no-bag",
        ],
        cwd=tmp_path,
    )
    driver = None
    try:
        url = launch.wait_for(PANEL_URL, 120).group(1)
        driver = chromium(tmp_path / "profile")
        driver.get(url)
        cases = [
            (("0", "-20.5", "0"), "Y = -20.5 m is out of range: allowed [-20, 20] m"),
            (("0", "0", "3.2"), "Ori = 3.2 rad is out of range: allowed [-3.14, 3.14] rad"),
            (("", "0", "0"), "X is empty"),
        ]
        for (x, y, ori), expected in cases:
            for key, value in (("x", x), ("y", y), ("ori", ori)):
                box = driver.find_element(By.ID, key)
                box.clear()
                if value:
                    box.send_keys(value)
            driver.find_element(By.ID, "start").click()
            message = driver.find_element(By.ID, "message")
            _wait(lambda: expected in message.text, 10, f"the message {expected!r}")
            assert message.is_displayed()
        save_artifact(driver, tmp_path, "view_refused.png")
    finally:
        if driver is not None:
            driver.quit()
        assert launch.interrupt() == 0


@pytest.mark.browser
def test_saved_html_opens_and_has_the_animation(tmp_path, root, house_map):
    html = tmp_path / "run.html"
    launch = LaunchProcess(
        [
            str(root / "launch/qbot_navigation.launch.yaml"),
            "slam:=false",
            f"map:={house_map}",
            "goal:=1 0 0",
            "--duration",
            "6",
            "--no-bag",
            "--save-html",
            str(html),
        ],
        cwd=tmp_path,
    )
    assert launch.proc.wait(600) == 0, "\n".join(launch.lines[-30:])
    sim = float(launch.wait_for(r"simulated ([\d.]+) s in", 1).group(1))
    size = html.stat().st_size
    print(f"static HTML of a {sim:.1f} s navigation run: {size / 1e6:.2f} MB")
    text = html.read_text()
    assert "http://" not in text.split("<script", 1)[0]  # nothing fetched before the scripts
    driver = chromium(tmp_path / "profile")
    try:
        driver.get(html.as_uri())
        time.sleep(3)
        duration = driver.execute_script("return viewer.animator.duration")
        controls = driver.execute_script(
            "return Array.from(document.querySelectorAll('.dg li.cr .property-name')).map(e => e.textContent)"
        )
        # replayed from the start: on a loaded machine the page can take longer to open than the
        # run lasts, and the animation stops at its end (the mixer's clock stops with it)
        t0 = driver.execute_script(
            "viewer.animator.reset(); viewer.animator.play(); return viewer.animator.mixer.time"
        )
        time.sleep(1.0)
        t1 = driver.execute_script("return viewer.animator.mixer.time")
        save_artifact(driver, tmp_path, "view_static_html.png")
    finally:
        driver.quit()
    assert duration == pytest.approx(sim, abs=0.1)  # the whole run is in the animation
    assert {"play", "pause", "reset", "time"} <= set(controls)
    assert t1 > t0  # and it plays


def test_headless_run_creates_no_meshcat(tmp_path, root):
    script = (
        "import sys, logging\n"
        "from twil_control.launch.__main__ import main\n"
        f"code = main([{str(root / 'launch/qbot_sim.launch.yaml')!r}, '--duration', '0.2', '--no-bag'])\n"
        "print('view imported:', 'twil_control.view.view_node' in sys.modules)\n"
        "sys.exit(code)\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", script], cwd=tmp_path, capture_output=True, text=True, timeout=300
    )
    assert out.returncode == 0, out.stderr
    assert "view imported: False" in out.stdout
    assert "Meshcat listening" not in out.stderr + out.stdout
