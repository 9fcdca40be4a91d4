"""Sensors read from real descriptions (corpus, bundled, tests/assets/sensors) and bad <sensor> blocks."""

from __future__ import annotations

import math
import os
from pathlib import Path

import pytest

from mobot_cli.assets import load_robot
from mobot_cli.assets.description.sensors import DescribedSensor
from mobot_cli.errors import DescriptionError

HERE = Path(__file__).parent / "sensors"
ROOTS = ("turtlebot3", "husky", "jackal", "velodyne_simulator", "linorobot2", "gz_ros2_control")
NO_CONTROL = {"gazebo_controllers": "/dev/null"}  # husky/jackal name packages not in the corpus
YAW_90 = (0.0, 0.0, math.sqrt(0.5), math.sqrt(0.5))


@pytest.fixture
def corpus_path(corpus, monkeypatch) -> Path:
    monkeypatch.setenv("MOBOT_RESOURCE_PATH", os.pathsep.join(str(corpus / r) for r in ROOTS))
    return corpus


def by_name(robot) -> dict[str, DescribedSensor]:
    return {s.name: s for s in robot.sensors}


def sensor_notices(robot) -> list[str]:
    return [n.message for n in robot.notices if "sensor" in n.message]


def test_bundled_mobot_has_an_imu_and_a_360_beam_scan_when_asked():
    assert load_robot("mobot").sensors == ()  # opt-in: a robot without sensors pays nothing for them
    imu, = load_robot("mobot", {"imu": "true"}).sensors
    assert (imu.type, imu.link, imu.rate_hz, imu.topic, imu.frame_id) == \
        ("imu", "base_link", 120.0, "imu", "base_link")
    assert (imu.noise_stddev, imu.accel_noise_stddev) == (2e-4, 1.7e-2)
    lidar, imu_again = load_robot("mobot", {"lidar": "true", "imu": "true"}).sensors
    assert imu_again == imu
    assert (lidar.name, lidar.type, lidar.kind, lidar.link) == ("lidar", "ray", "lidar", "lidar_link")
    assert (lidar.samples, lidar.min_angle, lidar.max_angle) == (360, -3.14159, 3.14159)
    assert (lidar.vertical_samples, lidar.rate_hz, lidar.topic) == (1, 10.0, "scan")
    assert (lidar.range_min, lidar.range_max, lidar.range_resolution) == (0.12, 12.0, 0.01)
    assert lidar.noise_stddev == 0.01


def test_turtlebot3_burger_lds_and_imu(corpus_path):
    robot = load_robot(str(corpus_path / "turtlebot3/turtlebot3_description/urdf/"
                                         "turtlebot3_burger.urdf.xacro"))
    lds, imu = by_name(robot)["lds_lfcd_sensor"], by_name(robot)["imu"]
    assert (lds.type, lds.link, lds.rate_hz, lds.topic, lds.frame_id) == \
        ("ray", "base_scan", 5.0, "scan", "base_scan")
    assert (lds.samples, lds.resolution, lds.min_angle, lds.max_angle) == (360, 1.0, 0.0, 6.28319)
    assert (lds.range_min, lds.range_max, lds.range_resolution) == (0.12, 3.5, 0.015)
    assert (lds.noise_mean, lds.noise_stddev, lds.vertical_samples) == (0.0, 0.01, 1)
    # no <update_rate>: SDF's 0, every physics step; no sensor plugin: the usual topic
    assert (imu.link, imu.rate_hz, imu.topic, imu.frame_id) == ("imu_link", 0.0, "imu", "")
    assert sensor_notices(robot) == []
    spec = lds.spec(every=48)
    assert (spec.kind, spec.every, spec.horizontal.samples, spec.vertical.samples) == ("lidar", 48, 360, 1)
    assert imu.spec(every=1).horizontal is None and imu.spec(every=1).frame_id == "imu_link"


def test_turtlebot3_waffle_pi_camera_is_read(corpus_path):
    robot = load_robot(str(corpus_path / "turtlebot3/turtlebot3_description/urdf/"
                                         "turtlebot3_waffle_pi.urdf.xacro"))
    assert sorted(by_name(robot)) == ["Pi Camera", "imu", "lds_lfcd_sensor"]  # tests/assets/test_cameras.py
    assert sensor_notices(robot) == []


def test_turtlebot3_sdf_model_sensors_posed_in_the_urdf_link_frame(corpus):
    robot = load_robot(str(corpus / "turtlebot3_simulations/turtlebot3_gazebo/models/turtlebot3_burger"))
    lds, imu = by_name(robot)["hls_lfcd_lds"], by_name(robot)["tb3_imu"]
    assert (lds.type, lds.link, lds.topic, lds.frame_id, lds.rate_hz) == \
        ("gpu_lidar", "base_scan", "scan", "base_scan", 5.0)
    assert lds.xyz == pytest.approx((0.0, 0.0, 0.0), abs=1e-9)  # the sensor sits where the joint is
    assert (imu.topic, imu.rate_hz, imu.noise_stddev, imu.accel_noise_stddev) == ("imu", 200.0, 2e-4, 1.7e-2)
    assert imu.xyz == pytest.approx((0.032, 0.0, -0.068))  # SDF link origin, seen from the joint


def test_husky_imu_when_simulated_and_gps_left_out(corpus_path):
    robot = load_robot(str(corpus_path / "husky/husky_description/urdf/husky.urdf.xacro"),
                       {**NO_CONTROL, "is_sim": "true"})
    imu, = robot.sensors
    assert (imu.name, imu.link, imu.rate_hz, imu.topic) == ("imu_sensor", "imu_link", 100.0, "imu/data_raw")
    assert sensor_notices(robot) == ["sensors of types mobot does not simulate are left out: gps 'gps_sensor'"]
    assert load_robot(str(corpus_path / "husky/husky_description/urdf/husky.urdf.xacro"),
                      NO_CONTROL).sensors == ()


def test_jackal_front_laser_from_its_environment_switch(corpus_path, monkeypatch):
    monkeypatch.setenv("JACKAL_LASER", "1")  # jackal's accessories read environment variables
    robot = load_robot(str(corpus_path / "jackal/jackal_description/urdf/jackal.urdf.xacro"),
                       {**NO_CONTROL, "is_sim": "true"})
    laser = by_name(robot)["front_laser"]
    assert (laser.link, laser.topic, laser.frame_id, laser.rate_hz) == \
        ("front_laser", "front/scan", "front_laser", 50.0)
    assert (laser.samples, laser.min_angle, laser.max_angle) == (720, -2.35619, 2.35619)
    assert (laser.range_min, laser.range_max, laser.noise_stddev) == (0.1, 30.0, 0.001)
    assert by_name(robot)["imu_sensor"].topic == "imu/data_raw"


def test_velodyne_vlp16_macro_with_its_plugin_range_and_noise(corpus_path):
    robot = load_robot(str(HERE / "vlp16.urdf.xacro"))
    vlp, = robot.sensors
    assert (vlp.name, vlp.link, vlp.topic, vlp.frame_id, vlp.rate_hz) == \
        ("velodyne-VLP16", "velodyne", "velodyne_points", "velodyne", 10.0)
    assert (vlp.samples, vlp.vertical_samples) == (1875, 16)
    assert (vlp.min_angle, vlp.max_angle) == pytest.approx((-math.pi, math.pi))
    assert (vlp.vertical_min_angle, vlp.vertical_max_angle) == pytest.approx((-math.radians(15),
                                                                             math.radians(15)))
    # the sensor says 0.055..140 m without noise; velodyne's plugin keeps 0.9..130 m and adds 0.008
    assert (vlp.range_min, vlp.range_max, vlp.noise_stddev) == (0.9, 130.0, 0.008)
    assert vlp.spec(every=24).vertical.samples == 16


@pytest.mark.parametrize("name", ["2wd", "4wd"])
def test_linorobot2_laser_and_imu(corpus_path, name):
    robot = load_robot(str(corpus_path / f"linorobot2/linorobot2_description/urdf/robots/{name}.urdf.xacro"))
    laser, imu = by_name(robot)["laser_lidar"], by_name(robot)["imu_sensor"]
    assert (laser.type, laser.link, laser.topic, laser.frame_id, laser.rate_hz) == \
        ("gpu_ray", "laser", "scan", "laser", 10.0)
    assert (laser.samples, laser.min_angle, laser.max_angle, laser.range_min, laser.range_max) == \
        (360, -3.1416, 3.1416, 0.08, 12.0)
    # the remapping wins over the ROS 1 <topicName> and the sensor's __default_topic__
    assert (imu.link, imu.topic, imu.frame_id, imu.rate_hz) == ("imu_link", "imu/data", "imu_link", 20.0)
    assert sensor_notices(robot) == []  # its depth 'camera' is an RGB-D camera now (tests/assets/test_cameras.py)
    camera = by_name(robot)["camera"]
    assert (camera.kind, camera.frame_id, camera.width, camera.height) == ("rgbd", "camera_depth_link", 640, 480)


@pytest.mark.parametrize("model, topic", [("dolly_gazebo/models/dolly", "laser_scan"),
                                          ("dolly_ignition/models/dolly_ignition", "dolly/laser_scan")])
def test_dolly_laser(corpus, model, topic):
    laser, = load_robot(str(corpus / "dolly" / model)).sensors
    assert (laser.name, laser.link, laser.topic, laser.frame_id, laser.rate_hz) == \
        ("sensor_ray", "chassis", topic, "", 100.0)
    assert (laser.samples, laser.min_angle, laser.max_angle, laser.range_min, laser.range_max) == \
        (200, -1.0, 1.0, 0.05, 10.0)
    assert laser.xyz == pytest.approx((0.5, 0.0, 0.0))


def test_dolly_in_its_world_keeps_its_laser(corpus):
    from mobot_cli.assets.description.sdf import describe_world_robot
    from mobot_cli.assets.world.worldplan import load_world

    world = load_world(str(corpus / "dolly/dolly_gazebo/worlds/dolly_empty.world"), None)
    laser, = describe_world_robot(world.robot("Dolly"), None).sensors
    assert (laser.name, laser.topic, laser.samples) == ("sensor_ray", "laser_scan", 200)


def test_every_field_and_sdformat_defaults():
    robot = load_robot(str(HERE / "every_field.urdf.xacro"), {"rate": "12.5"})
    sensors = by_name(robot)
    assert list(sensors) == ["front_lidar", "puck", "plain", "imu_sensor", "bumper", "front_camera"]
    front = sensors["front_lidar"]
    assert (front.rate_hz, front.topic, front.frame_id) == (12.5, "front/scan", "laser_optical")
    assert front.xyz == (0.05, 0.0, 0.02) and front.quat == pytest.approx(YAW_90)
    assert (front.samples, front.resolution, front.min_angle, front.max_angle) == (720, 0.5, -2.0, 2.0)
    assert (front.range_min, front.range_max, front.range_resolution) == (0.1, 25.0, 0.005)
    assert (front.noise_mean, front.noise_stddev) == (0.001, 0.02)
    puck = sensors["puck"]  # gz-sim's spelling: <lidar>, <topic> (absolute), <gz_frame_id>
    assert (puck.type, puck.kind, puck.topic, puck.frame_id) == ("gpu_lidar", "lidar", "points_raw",
                                                                 "velodyne_frame")
    assert (puck.samples, puck.vertical_samples, puck.vertical_min_angle, puck.vertical_max_angle) == \
        (900, 16, -0.26, 0.26)
    plain = sensors["plain"]  # SDFormat's defaults
    assert (plain.rate_hz, plain.samples, plain.min_angle, plain.max_angle, plain.resolution) == \
        (0.0, 1, 0.0, 0.0, 1.0)
    assert (plain.range_min, plain.range_max, plain.range_resolution, plain.noise_stddev) == \
        (0.0, 4.0, 0.0, 0.0)
    assert (plain.topic, plain.frame_id, plain.xyz, plain.quat) == ("scan", "", (0.0, 0.0, 0.0),
                                                                    (0.0, 0.0, 0.0, 1.0))
    imu = sensors["imu_sensor"]  # ROS 1 names; the noisiest gyro axis; z's type none counts zero
    assert (imu.topic, imu.frame_id, imu.rate_hz) == ("imu/data", "imu_frame", 200.0)
    assert (imu.noise_mean, imu.noise_stddev, imu.accel_noise_stddev) == (0.0001, 0.003, 0.05)
    assert imu.xyz == (0.0, 0.0, 0.01) and imu.quat == pytest.approx(YAW_90)  # degrees="true"
    bumper = sensors["bumper"]
    assert (bumper.kind, bumper.link, bumper.topic, bumper.rate_hz) == ("contact", "base_link",
                                                                      "bumper_states", 50.0)
    assert bumper.collision == "front_bumper_collision_1"
    assert [n.message for n in robot.notices] == [
        "sensors of types mobot does not simulate are left out: navsat 'gnss'",
        "no drive wheels found: the robot will not move on commands"]


def test_sdf_model_sensor_poses_collisions_and_topics():
    robot = load_robot(str(HERE / "model.sdf"))
    sensors = by_name(robot)
    laser = sensors["laser"]
    # SDF: lidar_link at z 0.3, the sensor 0.1 ahead turned 90 degrees; the URDF frame of
    # lidar_link is its joint's, 5 cm higher: the sensor is 5 cm below it.
    assert laser.xyz == pytest.approx((0.1, 0.0, -0.05)) and laser.quat == pytest.approx(YAW_90)
    assert (laser.topic, laser.samples, laser.rate_hz) == ("scan", 270, 12.0)
    imu = sensors["imu"]  # on the root link: the model frame, where the chassis sits 0.1 up
    assert imu.xyz == pytest.approx((0.05, 0.0, 0.1)) and imu.topic == "imu" and imu.rate_hz == 0.0
    bumper = sensors["bumper"]  # the SDF collision name, as Gazebo names its URDF twin
    assert (bumper.collision, bumper.topic, bumper.rate_hz) == ("bumper_box_collision_1", "bumper", 40.0)


def test_default_topics_make_way_for_each_other(tmp_path):
    path = write(tmp_path, LIDAR.format(name="a", extra="") + LIDAR.format(name="b", extra="")
                 + IMU.format(name="c") + IMU.format(name="d"))
    assert [(s.name, s.topic) for s in load_robot(str(path)).sensors] == \
        [("a", "scan"), ("b", "b"), ("c", "imu"), ("d", "d")]


def test_warm_load_keeps_sensors(tmp_path, monkeypatch):
    monkeypatch.setenv("MOBOT_CACHE_DIR", str(tmp_path / "cache"))
    cold = load_robot(str(HERE / "every_field.urdf.xacro"))
    warm = load_robot(str(HERE / "every_field.urdf.xacro"))
    assert warm.sensors == cold.sensors and warm.links == cold.links
    assert isinstance(warm.sensors[0].quat, tuple) and warm.links[0].collisions == \
        ("base_link_collision", "front_bumper_collision_1")


# --- bad <sensor> blocks: errors naming the file and the sensor -----------------------------

LIDAR = """<gazebo reference="base_link"><sensor name="{name}" type="ray">{extra}<ray><scan>
  <horizontal><samples>10</samples><min_angle>-1</min_angle><max_angle>1</max_angle></horizontal>
  </scan><range><min>0.1</min><max>5</max></range></ray></sensor></gazebo>"""
IMU = """<gazebo reference="base_link"><sensor name="{name}" type="imu"/></gazebo>"""


def write(tmp_path: Path, sensors: str) -> Path:
    path = tmp_path / "robot.urdf"
    path.write_text(f"""<robot name="r"><link name="base_link">
      <inertial><mass value="1"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial>
      <collision><geometry><box size="0.2 0.2 0.2"/></geometry></collision></link>{sensors}</robot>""")
    return path


def lidar(**parts: str) -> str:
    values = {"samples": "10", "min_angle": "-1", "max_angle": "1", "min": "0.1", "max": "5", **parts}
    return ("""<gazebo reference="base_link"><sensor name="scanner" type="ray"><ray><scan><horizontal>"""
            f"<samples>{values['samples']}</samples><min_angle>{values['min_angle']}</min_angle>"
            f"<max_angle>{values['max_angle']}</max_angle></horizontal></scan><range>"
            f"<min>{values['min']}</min><max>{values['max']}</max></range></ray></sensor></gazebo>")


BAD = {
    "samples 0": (lidar(samples="0"), "ray.scan.horizontal.samples",
                  "sensor 'scanner' has 0 horizontal samples. Give <horizontal><samples> a whole "
                  "number from 1 to 100000."),
    "min above max": (lidar(min_angle="1.5"), "ray.scan.horizontal.max_angle",
                      "sensor 'scanner' has horizontal angles from 1.5 to 1 rad. Make "
                      "<horizontal><max_angle> greater than the min angle (equal only with one sample)."),
    "min equals max": (lidar(min_angle="1"), "ray.scan.horizontal.max_angle",
                       "sensor 'scanner' has horizontal angles from 1 to 1 rad. Make "
                       "<horizontal><max_angle> greater than the min angle (equal only with one sample)."),
    "no range max": (lidar(max=""), "ray.range.max",
                     "sensor 'scanner' has range max 0 m, not beyond its range min 0.1 m. Give "
                     "<range><max> the farthest distance it measures."),
    "samples text": (lidar(samples="many"), "ray.scan.horizontal.samples",
                     "sensor 'scanner' has <samples> 'many', which is not a finite number. Write a "
                     "plain number."),
    "unknown type": ('<gazebo reference="base_link"><sensor name="s" type="lazer"/></gazebo>', "",
                     "sensor 's' has unknown type 'lazer'. Did you mean 'lidar'?"),
    "no name": ('<gazebo reference="base_link"><sensor type="imu"/></gazebo>', "",
                "a <sensor> of type 'imu' has no name. Give it name=\"...\", unique within the robot."),
    "no reference": ('<gazebo><sensor name="s" type="imu"/></gazebo>', "",
                     "sensor 's' is in a <gazebo> block without a reference. Put it in "
                     "<gazebo reference=\"LINK\">."),
    "missing link": ('<gazebo reference="base_lnk"><sensor name="s" type="imu"/></gazebo>', "",
                     "sensor 's' is on link 'base_lnk', which the robot does not have. Did you mean "
                     "'base_link'?"),
    "twice": (IMU.format(name="s") + IMU.format(name="s"), "",
              "two sensors are named 's' (on links 'base_link' and 'base_link'). Give every sensor "
              "of a robot its own name."),
    "bad pose": ('<gazebo reference="base_link"><sensor name="s" type="imu"><pose>1 2 3</pose>'
                 '</sensor></gazebo>', "pose",
                 "sensor 's' has <pose> '1 2 3'. A pose is 'x y z roll pitch yaw' in metres and radians."),
    "negative rate": ('<gazebo reference="base_link"><sensor name="s" type="imu"><update_rate>-5'
                      '</update_rate></sensor></gazebo>', "update_rate",
                      "sensor 's' has a negative rate (-5 Hz). Give <update_rate> a rate in Hz "
                      "(0: every physics step)."),
    "negative noise": ('<gazebo reference="base_link"><sensor name="s" type="imu"><imu><angular_velocity>'
                       '<x><noise type="gaussian"><stddev>-1</stddev></noise></x></angular_velocity>'
                       '</imu></sensor></gazebo>', "noise.stddev",
                       "sensor 's' has a negative noise standard deviation (-1). Give <noise><stddev> "
                       "a value of 0 or more."),
    "no such collision": ('<gazebo reference="base_link"><sensor name="s" type="contact"><contact>'
                          '<collision>base_link_colision</collision></contact></sensor></gazebo>',
                          "contact.collision",
                          "sensor 's' counts contacts of collision 'base_link_colision', which link "
                          "'base_link' does not have. Did you mean 'base_link_collision'? Gazebo "
                          "names a link's collisions LINK_collision, LINK_collision_1, ..."),
}


@pytest.mark.parametrize("case", BAD, ids=list(BAD))
def test_bad_sensor_block_is_an_error_naming_file_and_sensor(tmp_path, case):
    block, key, message = BAD[case]
    path = write(tmp_path, block)
    with pytest.raises(DescriptionError) as err:
        load_robot(str(path))
    sensor = message.split("'")[1] if message.startswith("sensor") else \
        ("imu" if case == "no name" else "s")
    where = f"gazebo.sensor.{sensor}" + (f".{key}" if key else "")
    assert str(err.value) == f"{path.resolve()}, key '{where}': {message}"


def test_contact_collision_by_written_and_lumped_names(tmp_path):
    block = ('<gazebo reference="base_link"><sensor name="{n}" type="contact"><contact>'
             '<collision>{c}</collision></contact></sensor></gazebo>')
    path = write(tmp_path, block.format(n="a", c="base_link")
                 + block.format(n="b", c="base_footprint_fixed_joint_lump__base_link_collision")
                 + block.format(n="c", c="__default__"))
    assert [s.collision for s in load_robot(str(path)).sensors] == \
        ["base_link_collision", "base_link_collision", ""]


def test_a_single_beam_may_have_equal_angles(tmp_path):
    scanner, = load_robot(str(write(tmp_path, lidar(samples="1", min_angle="0", max_angle="0")))).sensors
    assert (scanner.samples, scanner.min_angle, scanner.max_angle) == (1, 0.0, 0.0)
