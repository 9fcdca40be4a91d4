"""map.yaml + map.pgm as nav2's map_server reads them (tests/ros/nav2_map.py follows map_io.cpp)."""

from __future__ import annotations

import numpy as np
import pytest

from mobot_cli.ros.map_files import grid_cells, pgm_bytes, write_map, yaml_text
from tests.ros.nav2_map import load_map


def cells_with_corners() -> np.ndarray:
    """5 x 3 cells, row 0 at the origin: occupied at (ix 1, iy 0), unknown at (ix 4, iy 2)."""
    cells = np.zeros((3, 5), dtype=np.int8)
    cells[0, 1] = 100
    cells[2, 4] = -1
    return cells


def test_image_rows_run_from_the_top_and_pixels_are_trinary():
    image = pgm_bytes(cells_with_corners())
    header, pixels = image[:len(b"P5\n5 3\n255\n")], image[len(b"P5\n5 3\n255\n"):]
    assert header == b"P5\n5 3\n255\n"
    rows = [list(pixels[i * 5:(i + 1) * 5]) for i in range(3)]
    assert rows == [[254, 254, 254, 254, 205],  # the top row is the map's last (highest y)
                    [254, 254, 254, 254, 254],
                    [254, 0, 254, 254, 254]]  # the bottom row holds the origin cell


def test_nav2_loads_the_same_cells_at_the_same_place(tmp_path):
    cells = cells_with_corners()
    files = write_map(tmp_path, cells, 0.05, (-1.25, 2.5, 0.0))
    data, resolution, origin = load_map(files.yaml)
    assert (resolution, origin) == (0.05, (-1.25, 2.5, 0.0))
    assert data[0, 1] == 100 and (data == 100).sum() == 1  # the occupied cell stays at the origin's row
    # 205 is map_saver's unknown; under the 0.25 free threshold nav2 itself loads it as free
    # (occ = 1 - 205/255 = 0.196): mobot's world maps hold no unknown cells for that reason.
    assert data[2, 4] == 0
    assert ((data == 0) == (cells != 100)).all()


def test_yaml_is_map_saver_s_layout():
    assert yaml_text("map.pgm", 0.05, (-6.6000000000000005, -5.6, -0.0)) == (
        "image: map.pgm\nmode: trinary\nresolution: 0.05\norigin: [-6.6, -5.6, 0.0]\n"
        "negate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.25\n")


def test_a_negated_map_reads_the_other_way_round(tmp_path):
    """The loader follows negate, so the files' negate: 0 is what makes black occupied."""
    files = write_map(tmp_path, grid_cells(np.eye(3, dtype=bool)), 0.1, (0.0, 0.0, 0.0))
    files.yaml.write_text(files.yaml.read_text().replace("negate: 0", "negate: 1"))
    data, _, _ = load_map(files.yaml)
    assert (data[np.eye(3, dtype=bool)] == 0).all() and (data[~np.eye(3, dtype=bool)] == 100).all()


def test_non_finite_metadata_is_refused():
    with pytest.raises(ValueError, match="finite"):
        yaml_text("map.pgm", 0.05, (float("nan"), 0.0, 0.0))


def test_occupancy_grid_bytes_are_rosbags_own():
    from rosbags.typesys import Stores, get_typestore

    from mobot_cli.ros.map_files import occupancy_grid_cdr

    store = get_typestore(Stores.ROS2_JAZZY)
    cells = cells_with_corners()
    data = occupancy_grid_cdr(cells, 0.05, (-1.25, 2.5, 0.5), (3, 250), "world")
    msg = store.deserialize_cdr(data, "nav_msgs/msg/OccupancyGrid")
    assert (msg.header.frame_id, msg.header.stamp.sec, msg.header.stamp.nanosec) == ("world", 3, 250)
    assert (msg.info.width, msg.info.height, msg.info.resolution) == (5, 3, pytest.approx(0.05))
    assert (msg.info.origin.position.x, msg.info.origin.position.y) == (-1.25, 2.5)
    assert msg.info.origin.orientation.z == pytest.approx(np.sin(0.25))
    assert msg.data.tolist() == cells.reshape(-1).tolist()  # rows from the origin up, as map_server sends
    assert store.serialize_cdr(msg, "nav_msgs/msg/OccupancyGrid") == data
