"""Movers in the run folder: movers.csv, /tf in the bag, the same bytes again with the same seed."""

from __future__ import annotations

import csv
from pathlib import Path

import yaml

from mobot_cli.cli import invoke

DATA = Path(__file__).resolve().parents[1] / "data"


def scenario(tmp_path: Path, seed: int = 3) -> Path:
    doc = {"version": 1, "name": "movers", "world": str(DATA / "actor_crossing.sdf"), "duration": 3.0, "seed": seed,
           "log": {"formats": ["csv", "mcap"]},
           "robots": [{"name": "r", "description": "mobot", "args": {"lidar": "true"}, "pose": {"x": -1.0, "y": 0.0}}],
           "movers": [{"name": "w_{i}", "count": 4, "region": [-3.0, 0.0, -2.0, 2.0]},
                      {"name": "cart", "shape": "box", "size": [0.5, 0.4, 0.8], "path": [[3.0, -1.0], [3.0, 1.0]],
                       "mode": "pingpong", "speed": 0.5, "at": 1.0}]}
    path = tmp_path / f"movers_{seed}.yaml"
    path.write_text(yaml.safe_dump(doc))
    return path


def run(path: Path, out: Path) -> Path:
    done = invoke(["run", str(path), "--out", str(out), "--quiet"])
    assert done.exit_code == 0, done.stderr
    return out


def test_movers_csv_bag_and_same_bytes_with_the_same_seed(tmp_path):
    a = run(scenario(tmp_path), tmp_path / "a")
    b = run(scenario(tmp_path), tmp_path / "b")
    for rel in ("movers.csv", "odom/r.csv", "sensors/r/lidar.npy"):
        assert (a / rel).read_bytes() == (b / rel).read_bytes(), rel
    other = run(scenario(tmp_path, seed=4), tmp_path / "c")
    assert (other / "movers.csv").read_bytes() != (a / "movers.csv").read_bytes()  # the walkers' goals are seeded
    with (a / "movers.csv").open() as f:
        rows = list(csv.DictReader(f))
    first = {r["name"] for r in rows if r["t"] == "0.000000"}
    assert first == {"walker", "w_0", "w_1", "w_2", "w_3"}  # the cart comes at 1 s
    cart = [r for r in rows if r["name"] == "cart"]
    assert float(cart[0]["t"]) == 1.0 and (float(cart[0]["x"]), float(cart[0]["y"])) == (3.0, -1.0)
    for r in rows:
        if r["name"].startswith("w_"):
            assert -3.5 < float(r["x"]) < 0.5 and -2.5 < float(r["y"]) < 2.5
    # the bag: world -> movers/<name> on /tf
    from rosbags.rosbag2 import Reader
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_HUMBLE)
    frames = {}
    with Reader(a / "bag") as reader:
        for connection, t, raw in reader.messages():
            if connection.topic == "/tf":
                for tf in store.deserialize_cdr(raw, connection.msgtype).transforms:
                    if tf.child_frame_id.startswith("movers/"):
                        assert tf.header.frame_id == "world"
                        frames[tf.child_frame_id] = (t, tf.transform.translation.x, tf.transform.translation.y)
    assert set(frames) == {"movers/walker", "movers/w_0", "movers/w_1", "movers/w_2", "movers/w_3", "movers/cart"}
    t, x, y = frames["movers/walker"]
    # 2.5 s of the 4 s north from (2, -2) to (2, 2), on Gazebo's spline: 4 (3 s^2 - 2 s^3) m, s = 0.625
    assert t == 3_000_000_000 and (x, y) == (2.0, 0.734375)
    assert (a / "trajectory.png").stat().st_size > 0


def test_movers_csv_rows_are_one_line_a_mover_as_printf_writes_them(tmp_path):
    """The rows written in one format a log row are the lines a per-mover ``%.6f`` would write,
    a negative zero written as 0; a name with '%' in it (a Gazebo actor's may) is written as it is."""
    from mobot_cli.record.movers_csv import MoversCsvSink
    from mobot_cli.timeline.records import Sample

    rows = [(0, {"w_0": (1.0, -2.5, 0.1), "50%_cart": (-0.0000001, 3.25, -3.1415926)}),
            (12, {"w_0": (1.0625, -2.4375, -0.0), "50%_cart": (1e-7, -1234.5678905, 2.0)}),
            (24, {"w_0": (-0.0000004, 0.0, 0.0)})]  # the cart went
    sink = MoversCsvSink(tmp_path, 240)
    for step, movers in rows:
        sink.write(Sample(step, {}, True, movers))
    sink.write(Sample(36, {}, True, None))  # not moved: no row
    sink.close()
    expected = ["t,name,x,y,yaw"]
    for step, movers in rows:
        for name, (x, y, yaw) in movers.items():
            line = f"{step / 240:.6f},{name},{x:.6f},{y:.6f},{yaw:.6f}"
            expected.append(line.replace("-0.000000", "0.000000"))
    assert (tmp_path / "movers.csv").read_text().splitlines() == expected
    assert "0.000000,50%_cart,0.000000,3.250000,-3.141593" in expected
