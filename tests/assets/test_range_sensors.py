"""Sensors known by their plugin: range plugins on ray sensors, Gazebo's sonar, IMU model plugins."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from mobot_cli.assets import load_robot
from mobot_cli.cli import invoke
from mobot_cli.errors import DescriptionError, ScenarioError
from mobot_cli.scenario.prepare import prepare
from tests.sim.sensor_world import room_scenario

RANGER = Path(__file__).parent / "sensors" / "range.urdf"
ROBOT = """<?xml version="1.0"?>
<robot name="r">
  <link name="base_link"><collision><geometry><box size="0.2 0.2 0.1"/></geometry></collision></link>
  {blocks}
</robot>"""


def _robot(tmp_path: Path, blocks: str):
    path = tmp_path / "r.urdf"
    path.write_text(ROBOT.format(blocks=blocks))
    return load_robot(str(path))


def _ray(plugin: str, sensor_type: str = "ray") -> str:
    return (f'<gazebo reference="base_link"><sensor name="s" type="{sensor_type}"><ray><scan><horizontal>'
            "<samples>3</samples><min_angle>-0.2</min_angle><max_angle>0.2</max_angle></horizontal></scan>"
            f"<range><min>0.1</min><max>2</max></range></ray>{plugin}</sensor></gazebo>")


def test_range_plugins_make_ray_sensors_range_sensors_with_their_own_values():
    robot = load_robot(str(RANGER))
    sensors = {s.name: s for s in robot.sensors}
    assert {n: s.kind for n, s in sensors.items()} == {
        "ir_front": "range", "sonar_left": "range", "ir_noisy": "range", "sonar_back": "range",
        "sonar_cone": "range", "imu_controller": "imu"}
    ir, sonar, noisy, back = (sensors[n] for n in ("ir_front", "sonar_left", "ir_noisy", "sonar_back"))
    # gazebo_ros (ROS 2): radiation_type as given, the wider axis as field of view, no noise of its own
    assert (ir.radiation, ir.field_of_view, ir.reading_noise_stddev, ir.topic) == ("infrared", 0.0, 0.0, "ir/front")
    # gazebo_ros_range (ROS 1): <radiation>, <fov>, <gaussianNoise>; <fov> defaults to 0.05
    assert (sonar.radiation, sonar.field_of_view, sonar.topic, sonar.frame_id) == \
        ("ultrasound", 0.3, "sonar/left", "base_link")
    assert (sonar.samples, sonar.vertical_samples, sonar.range_min, sonar.range_max) == (5, 3, 0.03, 3.0)
    assert (noisy.radiation, noisy.field_of_view, noisy.reading_noise_stddev) == ("infrared", 0.05, 0.05)
    # hector's sonar: ultrasound, the narrower axis as field of view, its frameId
    assert (back.radiation, back.field_of_view, back.frame_id) == ("ultrasound", pytest.approx(0.1), "base_link")


def test_gazebo_sonar_is_a_cone_of_rays_turned_to_point_x_along_it():
    cone = {s.name: s for s in load_robot(str(RANGER)).sensors}["sonar_cone"]
    half = math.atan2(0.2, 3.0)
    assert (cone.type, cone.kind, cone.radiation) == ("sonar", "range", "ultrasound")
    assert (cone.range_min, cone.range_max) == (0.0, 3.0)
    assert (cone.samples, cone.vertical_samples) == (9, 9)
    assert (cone.min_angle, cone.max_angle, cone.field_of_view) == (pytest.approx(-half), pytest.approx(half),
                                                                    pytest.approx(2 * half))
    # pitched -90 deg (its -z forward), then turned +90 deg about y: x forward again
    assert cone.quat == pytest.approx((0.0, 0.0, 0.0, 1.0), abs=1e-9)


def test_hector_imu_plugin_is_read_as_an_imu_and_its_gps_is_left_out_by_name():
    robot = load_robot(str(RANGER))
    imu = {s.name: s for s in robot.sensors}["imu_controller"]
    assert (imu.type, imu.link, imu.rate_hz, imu.topic, imu.frame_id) == ("imu", "imu_link", 60.0, "imu/data", "")
    assert (imu.noise_stddev, imu.accel_noise_stddev) == (0.002, 0.03)
    (notice,) = [n.message for n in robot.notices if "left out" in n.message]
    assert notice == ("sensors of types mobot does not simulate are left out: "
                      "GPS plugin 'gps_controller' (libhector_gazebo_ros_gps.so)")


def test_gazebo_ros_imu_model_plugin_needs_its_body_as_gazebo_does(tmp_path):
    plugin = ('<gazebo><plugin name="imu" filename="libgazebo_ros_imu.so">{body}<topicName>/imu/raw</topicName>'
              "<gaussianNoise>0.01</gaussianNoise><updateRate>50</updateRate></plugin></gazebo>")
    (imu,) = _robot(tmp_path, plugin.format(body="<bodyName>base_link</bodyName>")).sensors
    assert (imu.kind, imu.link, imu.topic, imu.rate_hz, imu.noise_stddev, imu.accel_noise_stddev) == \
        ("imu", "base_link", "imu/raw", 50.0, 0.01, 0.01)
    robot = _robot(tmp_path, plugin.format(body=""))
    assert robot.sensors == ()
    assert any("IMU plugin 'imu' (no <bodyName>)" in n.message for n in robot.notices)
    # beside an imu <sensor> of the same link it is that IMU, read once (as turtlebot3's)
    sensor = '<gazebo reference="base_link"><sensor name="imu_sensor" type="imu"/></gazebo>'
    both = _robot(tmp_path, sensor + plugin.format(body="<bodyName>base_link</bodyName>"))
    assert [s.name for s in both.sensors] == ["imu_sensor"]


def test_a_ray_sensor_publishing_a_scan_stays_a_lidar_and_gpu_ray_may_be_a_range(tmp_path):
    scan = ('<plugin name="p" filename="libgazebo_ros_ray_sensor.so"><output_type>sensor_msgs/LaserScan'
            "</output_type></plugin>")
    (lidar,) = _robot(tmp_path, _ray(scan)).sensors
    assert (lidar.kind, lidar.radiation) == ("lidar", "")
    ranged = ('<plugin name="p" filename="libgazebo_ros_ray_sensor.so"><output_type>sensor_msgs/Range</output_type>'
              "</plugin>")
    (gpu,) = _robot(tmp_path, _ray(ranged, "gpu_ray")).sensors
    assert (gpu.kind, gpu.radiation, gpu.field_of_view, gpu.topic) == ("range", "infrared", pytest.approx(0.4), "range")


def test_a_radiation_type_gazebo_ros_refuses_is_a_located_error(tmp_path):
    bad = ('<plugin name="p" filename="libgazebo_ros_ray_sensor.so"><output_type>sensor_msgs/Range</output_type>'
           "<radiation_type>laser</radiation_type></plugin>")
    with pytest.raises(DescriptionError) as caught:
        _robot(tmp_path, _ray(bad))
    assert "sensor 's' has <radiation_type> 'laser'" in str(caught.value)
    assert caught.value.location.key == "gazebo.sensor.s.plugin.radiation_type"
    noise = '<plugin name="p" filename="libgazebo_ros_range.so"><gaussianNoise>lots</gaussianNoise></plugin>'
    with pytest.raises(DescriptionError, match="has <gaussianNoise> 'lots', which is not a finite number"):
        _robot(tmp_path, _ray(noise))


def test_inspect_shows_range_sensors(tmp_path):
    done = invoke(["inspect", str(RANGER)])
    assert done.exit_code == 0, done.stderr
    assert "  ir_noisy (ray, range) on base_link, topic ir/noisy, every step" in done.stdout
    assert "    infrared, 1 ray, field of view 0.050 rad, range 0.02..4 m, noise 0 + 0.05 m" in done.stdout


def test_a_scenario_changes_a_range_sensor_with_lidar_fields_but_not_imu_ones(tmp_path):
    robots = (f"  - name: r\n    description: {RANGER}\n    sensors:\n"
              "      ir_front: {range_max: 2.5, noise_stddev: 0.01}\n")
    plan = prepare(room_scenario(tmp_path, robots)).plan
    ir = {s.name: s for s in plan.robots[0].sensors}["ir_front"]
    assert (ir.kind, ir.range_max, ir.noise_stddev, ir.radiation) == ("range", 2.5, 0.01, "infrared")
    bad = f"  - name: r\n    description: {RANGER}\n    sensors:\n      ir_front: {{accel_noise_stddev: 0.1}}\n"
    with pytest.raises(ScenarioError, match="'accel_noise_stddev' applies to imu sensors, and this one is a range"):
        prepare(room_scenario(tmp_path, bad))


def test_an_sdf_model_carries_its_range_sensor_and_imu_plugin(tmp_path):
    path = tmp_path / "model.sdf"
    path.write_text("""<?xml version="1.0"?>
<sdf version="1.7"><model name="m">
  <link name="base">
    <collision name="c"><geometry><box><size>0.2 0.2 0.1</size></box></geometry></collision>
    <sensor name="tof" type="gpu_lidar"><pose>0.1 0 0 0 0 0</pose>
      <lidar><scan><horizontal><samples>1</samples></horizontal></scan><range><min>0.05</min><max>2</max></range>
      </lidar>
      <plugin name="tof" filename="libgazebo_ros_ray_sensor.so"><ros><remapping>~/out:=tof</remapping></ros>
        <output_type>sensor_msgs/Range</output_type><radiation_type>ultrasound</radiation_type></plugin>
    </sensor>
  </link>
  <plugin name="imu" filename="libhector_gazebo_ros_imu.so"><gaussianNoise>0.02</gaussianNoise></plugin>
</model></sdf>""")
    tof, imu = load_robot(str(path)).sensors
    assert (tof.kind, tof.type, tof.radiation, tof.topic, tof.range_max, tof.xyz) == \
        ("range", "gpu_lidar", "ultrasound", "tof", 2.0, (0.1, 0.0, 0.0))
    assert (imu.kind, imu.link, imu.topic, imu.noise_stddev, imu.accel_noise_stddev) == \
        ("imu", "base", "imu", 0.02, 0.02)


def test_a_sonar_takes_its_plugins_noise_and_field_of_view(tmp_path):
    sonar = ('<gazebo reference="base_link"><sensor name="us" type="sonar"><pose>0 0 0 0 -1.5708 0</pose>'
             "<sonar><min>0.01</min><max>3</max><radius>0.5</radius></sonar>"
             '<plugin name="us" filename="libgazebo_plugins_sonar.so"><gaussianNoise>0.15</gaussianNoise>'
             "<topicName>/achilles/sonarLeft</topicName><fov>0.5</fov></plugin></sensor></gazebo>")
    (us,) = _robot(tmp_path, sonar).sensors
    assert (us.kind, us.reading_noise_stddev, us.field_of_view, us.topic) == ("range", 0.15, 0.5, "achilles/sonarLeft")
    assert us.max_angle == pytest.approx(math.atan2(0.5, 2.99))


@pytest.mark.parametrize("filename, name", [("libignition-gazebo-imu-system.so", "ignition::gazebo::systems::Imu"),
                                            ("gz-sim-imu-system", "gz::sim::systems::Imu")])
def test_gz_sim_imu_system_is_not_a_sensor_of_its_own(tmp_path, filename, name):
    """Leo rover's way: the gz-sim Imu system beside the imu <sensor> it serves; nothing left out."""
    system = f'<gazebo><plugin filename="{filename}" name="{name}"/></gazebo>'
    sensor = ('<gazebo reference="base_link"><sensor name="leo_imu" type="imu"><update_rate>100</update_rate>'
              '</sensor></gazebo>')
    robot = _robot(tmp_path, system + sensor)
    assert [(s.name, s.kind, s.rate_hz) for s in robot.sensors] == [("leo_imu", "imu", 100.0)]
    assert not any("left out" in n.message for n in robot.notices)
