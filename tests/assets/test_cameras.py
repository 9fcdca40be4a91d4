"""Cameras read from descriptions (URDF <gazebo><sensor>, SDF models, the corpus) and from a
scenario's sensors: (added, changed, refused with a located error)."""

from __future__ import annotations

import math
import os
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from mobot_cli.assets import load_robot
from mobot_cli.cli import invoke
from mobot_cli.errors import DescriptionError

URDF = """<?xml version="1.0"?>
<robot name="eyes">
  <link name="base_link"><inertial><mass value="1"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0"
    iyz="0"/></inertial><collision><geometry><box size="0.2 0.2 0.1"/></geometry></collision></link>
  <gazebo reference="base_link">
    <sensor type="camera" name="front">
      <update_rate>20</update_rate>
      <pose>0.1 0 0.2 0 0.1 0</pose>
      <camera><horizontal_fov>1.2</horizontal_fov>
        <image><width>64</width><height>48</height><format>B8G8R8</format></image>
        <clip><near>0.05</near><far>12</far></clip>
        <noise><type>gaussian</type><mean>0.0</mean><stddev>0.007</stddev></noise></camera>
      <plugin name="cam" filename="libgazebo_ros_camera.so"><camera_name>front_cam</camera_name>
        <frame_name>front_optical</frame_name></plugin>
    </sensor>
    <sensor type="depth_camera" name="down">
      <camera><optical_frame_id>down_optical</optical_frame_id></camera>
      <topic>down/image_raw</topic>
    </sensor>
    <sensor type="rgbd_camera" name="rgbd"><camera><image><format>BAYER_RGGB8</format></image></camera></sensor>
    BAD
  </gazebo>
</robot>
"""


def robot(tmp_path: Path, bad: str = ""):
    path = tmp_path / "eyes.urdf"
    path.write_text(URDF.replace("BAD", bad))
    return load_robot(str(path))


def test_camera_blocks_give_size_format_fov_clip_noise_topic_and_optical_frame(tmp_path):
    desc = robot(tmp_path)
    front, down, rgbd = desc.sensors
    assert (front.kind, front.width, front.height, front.image_format) == ("camera", 64, 48, "B8G8R8")
    assert (front.horizontal_fov, front.clip_near, front.clip_far, front.noise_stddev) == (1.2, 0.05, 12.0, 0.007)
    assert (front.rate_hz, front.topic, front.frame_id, front.xyz) == (20.0, "front_cam", "front_optical",
                                                                       (0.1, 0.0, 0.2))
    spec = front.spec(12)
    assert (spec.encoding, spec.field_of_view, spec.range_min, spec.range_max) == ("bgr8", 1.2, 0.05, 12.0)
    # gz: depth only, optical_frame_id, the topic the images go to; SDFormat's defaults elsewhere
    assert (down.kind, down.frame_id, down.topic, down.width, down.height) == ("depth", "down_optical", "down", 320,
                                                                               240)
    assert (down.horizontal_fov, down.clip_near, down.clip_far, down.rate_hz) == (1.047, 0.1, 100.0, 0.0)
    assert (rgbd.kind, rgbd.topic, rgbd.spec(1).encoding) == ("rgbd", "rgbd", "rgb8")
    assert any("'BAYER_RGGB8': mobot renders it as rgb8" in n.message for n in desc.notices)
    assert not any("do not simulate" in n.message and "camera" in n.message for n in desc.notices)


@pytest.mark.parametrize(("block", "message", "key"), [
    ("<sensor type='camera' name='c'><camera><image><width>0</width></image></camera></sensor>",
     "has an image width of 0 pixels", "camera.image.width"),
    ("<sensor type='camera' name='c'><camera><horizontal_fov>3.5</horizontal_fov></camera></sensor>",
     "horizontal field of view of 3.5 rad", "camera.horizontal_fov"),
    ("<sensor type='camera' name='c'><camera><clip><near>2</near><far>1</far></clip></camera></sensor>",
     "far clip 1 m, not beyond its near clip 2 m", "camera.clip.far"),
    ("<sensor type='camera' name='c'><camera><clip><near>x</near></clip></camera></sensor>",
     "<near> 'x', which is not a finite number", "camera.clip.near"),
])
def test_bad_camera_blocks_are_located_errors(tmp_path, block, message, key):
    with pytest.raises(DescriptionError) as caught:
        robot(tmp_path, block)
    assert message in caught.value.message and caught.value.location.key.endswith(key)


def test_turtlebot3_waffle_has_its_realsense_as_an_rgbd_camera(corpus, monkeypatch):
    monkeypatch.setenv("MOBOT_RESOURCE_PATH", str(corpus / "turtlebot3"))
    desc = load_robot(str(corpus / "turtlebot3/turtlebot3_description/urdf/turtlebot3_waffle.urdf.xacro"),
                      skip_missing=True)  # the corpus lacks its meshes
    camera, = (s for s in desc.sensors if s.kind in ("camera", "depth", "rgbd"))
    assert (camera.name, camera.kind, camera.width, camera.height) == ("realsense_R200", "rgbd", 1920, 1080)
    # gazebo_ros_openni_kinect: <cameraName>, <frameName>, <updateRate> (the sensor has no rate)
    assert (camera.topic, camera.frame_id, camera.rate_hz) == ("camera", "camera_rgb_optical_frame", 30.0)
    assert (camera.clip_near, camera.clip_far, camera.horizontal_fov) == (0.03, 100.0, 1.3439)
    pi = load_robot(str(corpus / "turtlebot3/turtlebot3_description/urdf/turtlebot3_waffle_pi.urdf.xacro"))
    camera = next(s for s in pi.sensors if s.kind == "camera")
    assert (camera.name, camera.width, camera.height, camera.topic) == ("Pi Camera", 640, 480, "camera")


def test_gz_waffle_model_camera_from_sdf(corpus):
    desc = load_robot(str(corpus / "turtlebot3_simulations/turtlebot3_gazebo/models/turtlebot3_waffle/model.sdf"))
    camera = next(s for s in desc.sensors if s.name == "camera")
    assert (camera.kind, camera.topic, camera.frame_id, camera.rate_hz) == ("camera", "camera", "camera_rgb_frame",
                                                                            30.0)
    assert (camera.noise_stddev, camera.clip_far, camera.horizontal_fov) == (0.007, 300.0, 1.02974)


SCENARIO = """version: 1
name: cams
world: empty
duration: 0.2
robots:
  - name: r
    description: mobot
    args: {camera: 'true'}
    sensors:
SENSORS"""


def run(tmp_path: Path, sensors: str):
    path = tmp_path / "s.yaml"
    path.write_text(SCENARIO.replace("SENSORS", sensors))
    return invoke(["check", str(path), "--json"])


def test_a_scenario_changes_the_bundled_camera_and_adds_one(tmp_path):
    done = invoke(["run", str(_write(tmp_path, "      camera: {width: 32, height: 24, rate_hz: 10}\n"
                                               "      back: {type: camera, link: base_link, width: 16, height: 8, "
                                               "pose: {rpy: [0, 0, 3.14159]}}\n")),
                   "--out", str(tmp_path / "out"), "--quiet"])
    assert done.exit_code == 0, done.stderr
    frames = tmp_path / "out/sensors/r"
    assert len(list((frames / "camera/rgb").iterdir())) == 3 and len(list((frames / "camera/depth").iterdir())) == 3
    # added with SDFormat's defaults but what it sets; every physics step without a rate
    assert len(list((frames / "back/rgb").iterdir())) == 49 and not (frames / "back/depth").exists()


def _write(tmp_path: Path, sensors: str) -> Path:
    path = tmp_path / "s.yaml"
    path.write_text(SCENARIO.replace("SENSORS", sensors))
    return path


def test_scenario_camera_values_out_of_range_are_located(tmp_path):
    done = run(tmp_path, "      camera: {clip_near: 20.0}\n")
    assert done.exit_code == 2 and "far clip 10 m, not beyond its near clip 20 m" in done.stderr
    assert "sensors.camera.clip_near" in done.stderr
    done = run(tmp_path, "      camera: {samples: 10}\n")
    assert done.exit_code == 2 and "'samples' applies to lidar sensors" in done.stderr


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(width=st.one_of(st.integers(-10, 5000), st.floats(allow_nan=True), st.text(max_size=4)),
       fov=st.one_of(st.floats(allow_nan=True, allow_infinity=True), st.integers(-5, 5)))
def test_any_camera_values_give_a_plan_or_a_located_error(tmp_path, width, fov):
    text = f"      camera: {{width: {width!r}, horizontal_fov: {fov!r}}}\n".replace("'", '"')
    done = run(tmp_path, text)
    if done.exit_code == 0:  # a whole number of pixels (1.0 and "12" are, as pydantic reads numbers)
        assert float(width).is_integer() and 1 <= float(width) <= 4096 and 0 < fov < math.pi
    else:
        assert done.exit_code == 2 and "Traceback" not in done.stderr and "s.yaml" in done.stderr


def test_bundled_mobot_camera_is_opt_in():
    assert not any(s.kind == "rgbd" for s in load_robot("mobot").sensors)
    camera, = load_robot("mobot", {"camera": "true"}).sensors
    assert (camera.kind, camera.topic, camera.frame_id, camera.rate_hz) == ("rgbd", "camera", "camera_optical_frame",
                                                                            15.0)
    assert os.path.basename(str(camera)) != ""


DEPTH_URDF = """<?xml version="1.0"?>
<robot name="deep">
  <link name="base_link"><inertial><mass value="5"/><inertia ixx="0.1" iyy="0.1" izz="0.1" ixy="0" ixz="0"
    iyz="0"/></inertial><collision><geometry><box size="0.3 0.3 0.1"/></geometry></collision></link>
  <gazebo reference="base_link">
    <sensor type="depth" name="gz_depth"><update_rate>10</update_rate><pose>0 0 0.4 0 0 0</pose>
      <camera><image><width>160</width><height>120</height></image><horizontal_fov>1.2</horizontal_fov>
        <clip><near>0.05</near><far>20</far></clip>
        <depth_camera><clip><near>0.5</near><far>FAR</far></clip></depth_camera></camera></sensor>
    <sensor type="depth" name="classic_depth"><pose>0 0 0.4 0 0 0</pose>
      <camera><depth_camera><clip><near>0.5</near><far>1.0</far></clip></depth_camera></camera>
      <plugin name="kinect" filename="libgazebo_ros_openni_kinect.so"/></sensor>
  </gazebo>
</robot>
"""


def test_a_depth_sensor_is_what_its_gazebo_makes_of_it(tmp_path):
    path = tmp_path / "deep.urdf"
    path.write_text(DEPTH_URDF.replace("FAR", "2.5"))
    gz, classic = load_robot(str(path)).sensors
    # gz-sim reads type depth as a depth camera with its own depth clip; Gazebo classic's ROS
    # plugins publish the image and the depth, cut off by their own parameters
    assert (gz.kind, gz.depth_near, gz.depth_far, gz.spec(24).depth_clip) == ("depth", 0.5, 2.5, (0.5, 2.5))
    assert (gz.spec(24).range_min, gz.spec(24).range_max) == (0.05, 20.0)  # the camera's clip renders it
    assert (classic.kind, classic.depth_far, classic.spec(24).depth_clip) == ("rgbd", 0.0, None)


@pytest.mark.parametrize("far, box_seen", [(2.5, False), (5.0, True)])
def test_the_depth_clip_cuts_the_depth_image_as_gz_does(tmp_path, far, box_seen):
    import numpy as np

    from mobot_cli.api import Simulation
    from tests.sim.sensing.test_camera import BOX_SDF, FACE_X

    (tmp_path / "box.sdf").write_text(BOX_SDF)
    (tmp_path / "deep.urdf").write_text(DEPTH_URDF.replace("FAR", str(far)))
    path = tmp_path / "s.yaml"
    path.write_text("version: 1\nworld: box.sdf\nduration: 1\nsettle: 0.0\nrobots:\n  - name: r\n"
                    "    description: deep.urdf\n    pose: {x: 0.0, y: 0.0}\n"
                    "    sensors: {classic_depth: false}\n")
    with Simulation.open(path) as sim:
        sim.step(24)
        image = sim.image("r", "gz_depth")
    assert image.rgb is None
    depth = image.depth
    centre = depth[40:55, 55:80]  # the box's face, 2.8 m ahead, above and left of the centre
    if box_seen:
        assert np.allclose(centre, FACE_X, atol=0.05)
    else:
        assert np.isposinf(centre).all()  # beyond the depth clip's 2.5 m: +inf, as gz-sensors gives
    finite = depth[np.isfinite(depth)]
    assert finite.size and finite.min() >= 0.5 and finite.max() <= far
