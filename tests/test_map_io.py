"""Map files (map_server / map_saver formats) and the map_server / map_saver nodes."""

from __future__ import annotations

import numpy as np
import pytest

from twil_control.core.node import Master
from twil_control.core.params import ParamServer
from twil_control.core.ros_node import NodeArgsError
from twil_control.mapping.map_io import (
    MapFileError,
    OccupancyMap,
    grid_to_pixels,
    pixels_to_grid,
    read_map,
    write_map,
    write_pgm,
)
from twil_control.nodes.map_msg import occupancy_grid_msg
from twil_control.nodes.map_saver import MapSaver
from twil_control.nodes.map_server import MapServer


def _yaml(path, image="m.pgm", **over):
    meta = {
        "image": image,
        "resolution": 0.05,
        "origin": "[-1.0, -2.0, 0.0]",
        "negate": 0,
        "occupied_thresh": 0.65,
        "free_thresh": 0.196,
        **over,
    }
    path.write_text("".join(f"{k}: {v}\n" for k, v in meta.items() if v is not None))
    return path


def test_write_then_read_gives_the_same_grid(tmp_path):
    rng = np.random.default_rng(0)
    data = rng.choice(np.array([-1, 0, 100], dtype=np.int8), size=(37, 53))
    grid = OccupancyMap(data, 0.025, (-3.5, 1.25, 0.0))
    yml, pgm = write_map(grid, tmp_path / "room")
    back = read_map(yml)
    assert np.array_equal(back.data, data)
    assert back.resolution == 0.025 and back.origin == (-3.5, 1.25, 0.0)
    assert pgm.read_bytes().startswith(b"P5\n# CREATOR")
    assert "image: room.pgm\n" in yml.read_text()  # relative to the YAML, not the cwd


def test_map_saver_thresholds_survive_a_round_trip(tmp_path):
    values = np.arange(-1, 101, dtype=np.int8).reshape(1, -1)
    yml, _ = write_map(OccupancyMap(values, 0.1), tmp_path / "t")
    back = read_map(yml).data[0]
    v = values[0].astype(int)
    assert np.all(back[(v >= 0) & (v <= 25)] == 0)  # map_saver: 0..25 -> 254 -> free
    assert np.all(back[v >= 65] == 100)  # 65..100 -> 0 -> occupied
    assert np.all(back[(v == -1) | ((v > 25) & (v < 65))] == -1)  # else 205 -> unknown


def test_map_server_thresholds_and_negate():
    # p = (255 - v) / 255: 89 -> 0.651 (> 0.65, occupied), 90 -> 0.647, 205 -> 0.19608
    # (not < 0.196: unknown), 206 -> 0.192 (free)
    pixels = np.array([[89, 90, 205, 206, 0, 255]], dtype=np.uint8)
    assert pixels_to_grid(pixels, False, 0.65, 0.196).tolist() == [[100, -1, -1, 0, 100, 0]]
    # negate: v -> 255 - v, so 89 -> p 0.349 and 90 -> p 0.353 (unknown), 205 -> p 0.804
    assert pixels_to_grid(pixels, True, 0.65, 0.196).tolist() == [[-1, -1, 100, 100, 0, 100]]


def test_scale_and_raw_modes():
    pixels = np.array([[0, 128, 255, 100]], dtype=np.uint8)

    def scale(v):  # between the thresholds: 1 + 98 ratio
        return int(1 + 98 * ((255 - v) / 255 - 0.196) / (0.65 - 0.196))

    scaled = pixels_to_grid(pixels, False, 0.65, 0.196, "scale")
    assert scaled.tolist() == [[100, scale(128), 0, scale(100)]] == [[100, 66, 0, 89]]
    assert pixels_to_grid(pixels, False, 0.65, 0.196, "raw").tolist() == [[0, -128, -1, 100]]


def test_image_top_row_is_the_map_s_highest_row():
    data = np.zeros((4, 3), dtype=np.int8)
    data[3, 1] = 100  # highest y row, middle column
    pixels = grid_to_pixels(data)
    assert pixels[0, 1] == 0 and pixels[3, 1] == 254
    assert np.array_equal(pixels_to_grid(pixels, False, 0.65, 0.196), data)


def test_colour_images_use_the_mean_of_their_channels(tmp_path):
    import cv2

    img = np.zeros((2, 2, 3), dtype=np.uint8)
    img[0, 0] = (255, 255, 255)
    img[0, 1] = (255, 0, 0)  # mean 85: p = 0.667, occupied
    cv2.imwrite(str(tmp_path / "c.png"), img)
    m = read_map(_yaml(tmp_path / "c.yaml", image="c.png"))
    assert m.data.tolist() == [[100, 100], [0, 100]]  # top image row is row 1


@pytest.mark.parametrize(
    "change, message",
    [
        ({"negate": None}, "missing negate"),
        ({"mode": "fancy"}, "'mode' must be one of trinary, scale, raw"),
        ({"origin": "[1, 2]"}, r"'origin' must be a list \[x, y, yaw\]"),
        ({"resolution": 0}, "'resolution' must be > 0"),
        ({"free_thresh": 0.9}, "free_thresh <= occupied_thresh"),
        ({"color": 3}, "unknown key"),
    ],
)
def test_bad_map_files_name_the_file_and_key(tmp_path, change, message):
    write_pgm(tmp_path / "m.pgm", np.full((2, 2), 254, dtype=np.uint8))
    path = _yaml(tmp_path / "bad.yaml", **change)
    with pytest.raises(MapFileError, match=message) as info:
        read_map(path)
    assert "bad.yaml" in str(info.value)


def _map_pair(tmp_path):
    data = np.zeros((20, 30), dtype=np.int8)
    data[5, :] = 100
    data[10:12, 3:6] = -1
    grid = OccupancyMap(data, 0.05, (-1.0, -2.0, 0.0))
    yml, _ = write_map(grid, tmp_path / "served")
    return grid, yml


def test_map_server_publishes_a_latched_map_that_a_late_subscriber_receives(tmp_path):
    grid, yml = _map_pair(tmp_path)
    params = ParamServer()
    params.set("/map_server/frame_id", "world")
    master = Master(params)
    server = MapServer(master, "map_server", "/", None, [str(yml)])
    master.clock.set(2.5)
    server.on_start()
    got, meta = [], []
    master.bus.subscribe("/map", "nav_msgs/OccupancyGrid", got.append)  # after publishing
    master.bus.subscribe("/map_metadata", "nav_msgs/MapMetaData", meta.append)
    (msg,) = got
    assert msg.header.frame_id == "world" and msg.header.stamp.sec == 2
    assert (msg.info.width, msg.info.height) == (30, 20) and msg.info.resolution == pytest.approx(0.05)
    assert (msg.info.origin.position.x, msg.info.origin.position.y) == (-1.0, -2.0)
    assert np.array_equal(np.asarray(msg.data).reshape(20, 30), grid.data)
    assert msg.data[5 * 30 + 7] == 100  # row-major from cell (0, 0)
    assert len(meta) == 1 and meta[0].width == 30
    assert master.call_service("/static_map") is msg


def test_map_server_bad_file_is_an_error_naming_it(tmp_path):
    with pytest.raises(NodeArgsError, match="nothing.yaml"):
        MapServer(Master(), "map_server", "/", None, [str(tmp_path / "nothing.yaml")])


def test_map_saver_writes_the_first_map_and_the_latest_at_shutdown(tmp_path):
    grid, _ = _map_pair(tmp_path)
    master = Master()
    saver = MapSaver(master, "map_saver", "/", None, ["-f", str(tmp_path / "out" / "saved")])
    pub = master.bus.advertise("/map", "nav_msgs/OccupancyGrid", latch=True)
    pub.publish(occupancy_grid_msg(grid, "map", 1.0))
    assert saver.saved == 1
    assert np.array_equal(read_map(tmp_path / "out" / "saved.yaml").data, grid.data)
    later = OccupancyMap(np.full((20, 30), 100, dtype=np.int8), 0.05, (-1.0, -2.0, 0.0))
    pub.publish(occupancy_grid_msg(later, "map", 2.0))
    assert saver.saved == 1  # kept, not written yet
    saver.shutdown()
    assert saver.saved == 2
    assert np.array_equal(read_map(tmp_path / "out" / "saved.yaml").data, later.data)
    saver.shutdown()
    assert saver.saved == 2  # nothing new: not rewritten
