"""A camera in every record: the run folder's PNG frames, the bag's Image and CameraInfo (read by
rosbags and by the mcap readers), byte-identical reruns, memory over a long camera run."""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from mobot_cli.cli import invoke
from mobot_cli.ros import camera_cdr
from mobot_cli.ros.definitions import CAMERA_INFO, COMPRESSED_IMAGE, IMAGE
from tests.sim.sensing.test_camera import scenario

REPO = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def camera_run(tmp_path_factory):
    folder = tmp_path_factory.mktemp("camera-run")
    path = scenario(folder, extra=", noise_stddev: 0.02", duration=1.0)
    text = path.read_text().replace("seed: 5\n", "seed: 5\nlog: {rate_hz: 10, formats: [csv, mcap]}\n")
    path.write_text(text)
    done = invoke(["run", str(path), "--out", str(folder / "out"), "--quiet"])
    assert done.exit_code == 0, done.stderr
    return path, folder / "out"


def test_the_run_folder_holds_png_frames_their_times_and_the_intrinsics(camera_run):
    _, out = camera_run
    folder = out / "sensors/r/front"
    frames = np.genfromtxt(folder / "frames.csv", delimiter=",", names=True)
    assert list(frames["step"]) == list(range(0, 241, 24)) and frames["t"][-1] == 1.0
    rgb = np.asarray(Image.open(folder / "rgb/000010.png"))
    depth = np.asarray(Image.open(folder / "depth/000010.png"))
    assert rgb.shape == (120, 160, 3) and rgb.dtype == np.uint8
    assert depth.dtype in (np.uint16, np.int32) and 2800 <= np.median(depth[depth > 0][:50]) <= 3600
    assert (depth[0] == 0).all()  # the sky: nothing within the far clip
    about = json.loads((folder / "camera.json").read_text())
    assert about["fx"] == pytest.approx(160 / (2 * math.tan(0.6))) and about["cx"] == 79.5
    assert about["topics"] == {"image": "/r/front/image_raw", "depth": "/r/front/depth/image_raw",
                               "camera_info": "/r/front/camera_info"}
    summary = json.loads((out / "summary.json").read_text())
    front = next(s for s in summary["robots"]["r"]["sensors"] if s["name"] == "front")
    assert (front["kind"], front["readings"], front["file"]) == ("rgbd", 11, "sensors/r/front/frames.csv")
    assert invoke(["check", str(out)]).exit_code == 0


def test_the_bag_images_and_camera_info_read_in_rosbags_and_the_mcap_readers(camera_run):
    import mcap.reader as mcap_reader
    import mcap_ros2.decoder as mcap_ros2
    from rosbags.rosbag2 import Reader
    from rosbags.typesys import Stores, get_typestore

    _, out = camera_run
    store = get_typestore(Stores.ROS2_HUMBLE)
    seen: dict[str, list] = {}
    with Reader(out / "bag") as reader:
        types = {c.topic: c.msgtype for c in reader.connections}
        for conn, _, raw in reader.messages():
            if conn.topic.startswith("/r/front/"):
                seen.setdefault(conn.topic, []).append(store.deserialize_cdr(raw, conn.msgtype))
    assert types["/r/front/image_raw"] == types["/r/front/depth/image_raw"] == IMAGE
    assert types["/r/front/camera_info"] == CAMERA_INFO
    assert [len(seen[t]) for t in sorted(seen)] == [11, 11, 11]
    info, image, depth = seen["/r/front/camera_info"][-1], seen["/r/front/image_raw"][-1], \
        seen["/r/front/depth/image_raw"][-1]
    fx = 160 / (2 * math.tan(0.6))
    assert (info.width, info.height, info.distortion_model) == (160, 120, "plumb_bob")
    assert np.allclose(info.k, [fx, 0, 79.5, 0, fx, 59.5, 0, 0, 1])
    assert np.allclose(info.p[[0, 2, 5, 6]], [fx, 79.5, fx, 59.5])
    assert info.header.frame_id == image.header.frame_id == "r/base_link_front_optical"
    assert (image.encoding, image.step, image.width, image.height) == ("rgb8", 480, 160, 120)
    assert (depth.encoding, depth.step) == ("32FC1", 640)
    pixels = np.frombuffer(bytes(image.data), np.uint8).reshape(120, 160, 3)
    metres = np.frombuffer(bytes(depth.data), "<f4").reshape(120, 160)
    assert np.array_equal(pixels, np.asarray(Image.open(out / "sensors/r/front/rgb/000010.png")))
    mm = np.asarray(Image.open(out / "sensors/r/front/depth/000010.png")).astype(float)
    assert np.isinf(metres[0]).all() and np.allclose(mm[np.isfinite(metres)] / 1000, metres[np.isfinite(metres)],
                                                     atol=0.0006)
    with (out / "bag/bag.mcap").open("rb") as f:
        reader = mcap_reader.make_reader(f, decoder_factories=[mcap_ros2.DecoderFactory()])
        decoded = [(channel.topic, message) for _, channel, _, message in reader.iter_decoded_messages()
                   if channel.topic.startswith("/r/")]
    infos = [m for t, m in decoded if t == "/r/front/camera_info"]
    assert len(infos) == 11 and list(infos[0].k) == list(info.k)
    last = [m for t, m in decoded if t == "/r/front/image_raw"][-1]
    assert bytes(last.data) == bytes(image.data)


def test_the_cdr_packers_match_rosbags_serializer():
    from rosbags.typesys import Stores, get_typestore

    from tests.sim.sensing.test_camera import SensorSpec

    store = get_typestore(Stores.ROS2_JAZZY)
    spec = SensorSpec(name="c", kind="rgbd", link="l", every=1, width=4, height=3, field_of_view=1.0,
                      range_min=0.1, range_max=5.0, encoding="bgr8")
    pixels = np.arange(36, dtype=np.uint8).reshape(3, 4, 3)
    for data, encoding in ((pixels, "bgr8"), (np.full((3, 4), np.inf, np.float32), "32FC1")):
        msg = store.deserialize_cdr(camera_cdr.image((7, 9), "f", data, encoding), IMAGE)
        assert store.serialize_cdr(msg, IMAGE) == camera_cdr.image((7, 9), "f", data, encoding)
    info = camera_cdr.camera_info((7, 9), "f", spec)
    assert store.serialize_cdr(store.deserialize_cdr(info, CAMERA_INFO), CAMERA_INFO) == info


@pytest.mark.parametrize("compression", ["png", "jpeg"])
def test_log_images_compressed_puts_image_transports_compressed_images_in_the_bag(camera_run, tmp_path, compression):
    import io

    from rosbags.rosbag2 import Reader
    from rosbags.typesys import Stores, get_typestore

    path, raw_out = camera_run
    text = path.read_text().replace("formats: [csv, mcap]}", f"formats: [csv, mcap], images: {compression}}}")
    assert text != path.read_text()
    (path.parent / f"{compression}.yaml").write_text(text)  # beside the world file it names
    out = tmp_path / "out"
    done = invoke(["run", str(path.parent / f"{compression}.yaml"), "--out", str(out), "--quiet"])
    assert done.exit_code == 0, done.stderr
    assert f"images: {compression}" in (out / "scenario.yaml").read_text()  # the run folder says how to run it again
    store = get_typestore(Stores.ROS2_HUMBLE)
    with Reader(out / "bag") as reader:
        types = {c.topic: c.msgtype for c in reader.connections}
        images = [store.deserialize_cdr(raw, c.msgtype) for c, _, raw in reader.messages()
                  if c.topic == "/r/front/image_raw/compressed"]
    assert types["/r/front/image_raw/compressed"] == COMPRESSED_IMAGE and "/r/front/image_raw" not in types
    assert types["/r/front/depth/image_raw"] == IMAGE and types["/r/front/camera_info"] == CAMERA_INFO
    assert len(images) == 11 and images[-1].format == f"rgb8; {compression} compressed bgr8"
    picture = Image.open(io.BytesIO(bytes(images[-1].data)))
    assert picture.format == compression.upper() and picture.size == (160, 120)
    frame = np.asarray(Image.open(raw_out / "sensors/r/front/rgb/000010.png")).astype(int)
    error = np.abs(np.asarray(picture.convert("RGB")).astype(int) - frame)
    assert error.max() == 0 if compression == "png" else error.mean() < 3.0  # JPEG at quality 95
    if compression == "jpeg":  # smaller than the raw images even after the bag's zstd (noisy PNGs are not)
        assert (out / "bag/bag.mcap").stat().st_size < 0.8 * (raw_out / "bag/bag.mcap").stat().st_size


def test_compressed_images_in_every_encoding_serialize_as_rosbags_does():
    import io

    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_JAZZY)
    rgb = np.arange(36, dtype=np.uint8).reshape(3, 4, 3)
    for pixels, encoding in ((rgb, "rgb8"), (rgb[:, :, ::-1], "bgr8"), (rgb[:, :, 0], "mono8")):
        data = camera_cdr.compressed((7, 9), "f", pixels, encoding, "png")
        msg = store.deserialize_cdr(data, COMPRESSED_IMAGE)
        assert store.serialize_cdr(msg, COMPRESSED_IMAGE) == data
        decoded = np.asarray(Image.open(io.BytesIO(bytes(msg.data))))
        assert np.array_equal(decoded, rgb[:, :, 0] if encoding == "mono8" else rgb)  # bgr8 stored as a colour PNG
        assert msg.format == f"{encoding}; png compressed {'mono8' if encoding == 'mono8' else 'bgr8'}"


def test_a_rerun_writes_the_same_bytes(camera_run, tmp_path):
    path, out = camera_run
    assert invoke(["run", str(path), "--out", str(tmp_path / "again"), "--quiet"]).exit_code == 0
    for name in ("rgb/000003.png", "depth/000003.png", "frames.csv", "camera.json"):
        assert (out / "sensors/r/front" / name).read_bytes() == (tmp_path / "again/sensors/r/front" / name).read_bytes()
    assert (out / "bag/bag.mcap").read_bytes() == (tmp_path / "again/bag/bag.mcap").read_bytes()


LONG_RUN = """
import resource
import sys
from mobot_cli.api.simulation import Simulation
def rss():
    return int(open('/proc/self/statm').read().split()[1]) * resource.getpagesize()
with Simulation.open(sys.argv[1], out=sys.argv[2]) as sim:
    sim.image('r')
    sizes = []  # resident set size after each simulated second
    for second in range(300):
        sim.step(240)
        sizes.append(rss())
    print(sizes[29], sizes[-1], sim._world._sensing.cameras.rendered)
"""


def test_memory_stays_flat_over_a_300_s_camera_run(tmp_path):
    """300 s simulated, kinematic, a 64 x 48 RGB-D camera at 10 Hz recorded to the run folder and
    read through the API: 3,000 frames; resident memory after 300 s is that after 30 s."""
    path = scenario(tmp_path, engine="kinematic", duration=300.0)
    path.write_text(path.read_text().replace("width: 160, height: 120", "width: 64, height: 48"))
    done = subprocess.run([sys.executable, "-c", LONG_RUN, str(path), str(tmp_path / "out")], capture_output=True,
                          text=True, timeout=600, cwd=REPO)
    assert done.returncode == 0, done.stderr
    early, late, rendered = (int(v) for v in done.stdout.split())
    assert rendered == 3000
    assert late - early < 8 << 20, f"grew {(late - early) / 1e6:.1f} MB from 30 s to 300 s"
    # t = 0, 0.1, ..., 300 s: the last frame is taken as the run closes
    assert len(list((tmp_path / "out/sensors/r/front/rgb").iterdir())) == 3001
