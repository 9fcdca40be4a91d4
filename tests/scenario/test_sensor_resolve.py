"""A scenario's `sensors:`: the description's sensors changed, added, turned off, in whole steps."""

from __future__ import annotations

import math
import os
import textwrap
from pathlib import Path

import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from mobot_cli.errors import ScenarioError
from mobot_cli.plan import RayAxis
from mobot_cli.scenario.model import RobotSpec
from mobot_cli.scenario.prepare import prepare
from mobot_cli.scenario.robots import RobotResolver

REPO = Path(__file__).resolve().parents[2]
TURTLEBOT = "turtlebot3/turtlebot3_description/urdf/turtlebot3_burger.urdf.xacro"


def scenario(tmp_path: Path, body: str, physics: int = 240) -> Path:
    path = tmp_path / "s.yaml"
    path.write_text(f"version: 1\nduration: 2\nphysics: {{rate_hz: {physics}}}\n" + textwrap.dedent(body))
    return path


def sensors(plan, robot: int = 0) -> dict:
    return {s.name: s for s in plan.robots[robot].sensors}


def sensor_notices(plan) -> list[str]:
    return [n for n in plan.notices if "rate_hz" in n or "sensor" in n]


def test_bundled_mobot_plan_sensors_in_steps(tmp_path):
    plan = prepare(scenario(tmp_path, """\
        robots:
          - {name: mobot, args: {lidar: "true", imu: "true"}}
        """)).plan
    lidar, imu = plan.robots[0].sensors
    assert (lidar.name, lidar.kind, lidar.link, lidar.every, lidar.topic, lidar.frame_id) == \
        ("lidar", "lidar", "lidar_link", 24, "scan", "lidar_link")
    assert lidar.horizontal == RayAxis(360, -3.14159, 3.14159, 1.0)
    assert lidar.vertical == RayAxis(1, 0.0, 0.0, 1.0)
    assert (lidar.range_min, lidar.range_max, lidar.range_resolution, lidar.noise_stddev) == \
        (0.12, 12.0, 0.01, 0.01)
    assert (imu.name, imu.kind, imu.every, imu.topic, imu.horizontal, imu.range_max) == \
        ("imu", "imu", 2, "imu", None, 0.0)
    assert imu.source == lidar.source == plan.robots[0].source
    assert sensor_notices(plan) == []


def test_bundled_scenarios_have_no_sensor_notices():
    for path in sorted((REPO / "scenarios").glob("*.yaml")):
        plan = prepare(path).plan
        assert sensor_notices(plan) == [], path.name
        # The bundled robot's sensors are opt-in: only a robot given xacro args (house_patrol's lidar) has any.
        robots = yaml.safe_load(path.read_text())["robots"]
        opted = {r["name"] for r in robots if r.get("args") or r.get("description", "mobot") != "mobot"}
        assert all(not r.sensors or r.name in opted for r in plan.robots), path.name


def test_the_design_example(tmp_path):
    plan = prepare(scenario(tmp_path, """\
        robots:
          - name: mobot
            description: mobot
            args: {lidar: "true", imu: "true"}
            sensors:
              scan: {rate_hz: 10, samples: 360, range_max: 8.0, noise_stddev: 0.01}
              imu: {type: imu, link: base_link, rate_hz: 100}
        """)).plan
    scan, imu = sensors(plan)["lidar"], sensors(plan)["imu"]
    assert (scan.every, scan.horizontal.samples, scan.range_max, scan.noise_stddev) == (24, 360, 8.0, 0.01)
    assert (imu.every, imu.link) == (2, "base_link")  # the described imu, now at 100 Hz
    assert sensor_notices(plan) == [
        f"{tmp_path / 's.yaml'}:10, key 'robots.mobot.sensors.imu.rate_hz': rate_hz 100 is not a "
        "whole number of physics steps at 240 Hz: reading every 2 steps (120 Hz)"]


def test_every_field_changes(tmp_path):
    plan = prepare(scenario(tmp_path, """\
        robots:
          - name: mobot
            args: {lidar: "true", imu: "true"}
            sensors:
              scan:
                type: gpu_lidar
                link: base_link
                rate_hz: 20
                pose: {xyz: [0.1, 0, 0.2], rpy: [0, 0, 1.5707963267948966]}
                samples: 90
                min_angle: -1
                max_angle: 1
                vertical_samples: 8
                vertical_min_angle: -0.2
                vertical_max_angle: 0.3
                range_min: 0.5
                range_max: 30
                range_resolution: 0.02
                noise_mean: 0.001
                noise_stddev: 0.03
                topic: lidar/points
                frame_id: lidar_optical
              imu: {accel_noise_stddev: 0.2, pose: {xyz: [0, 0, 0.05], quat: [0, 0, 0, 2]}}
        """)).plan
    scan, imu = sensors(plan)["lidar"], sensors(plan)["imu"]
    assert (scan.link, scan.every, scan.topic, scan.frame_id) == ("base_link", 12, "lidar/points",
                                                                  "lidar_optical")
    assert scan.xyz == (0.1, 0.0, 0.2) and scan.quat == pytest.approx((0, 0, math.sqrt(0.5), math.sqrt(0.5)))
    assert scan.horizontal == RayAxis(90, -1.0, 1.0, 1.0) and scan.vertical == RayAxis(8, -0.2, 0.3, 1.0)
    assert (scan.range_min, scan.range_max, scan.range_resolution) == (0.5, 30.0, 0.02)
    assert (scan.noise_mean, scan.noise_stddev) == (0.001, 0.03)
    assert (imu.accel_noise_stddev, imu.noise_stddev, imu.xyz, imu.quat) == \
        (0.2, 2e-4, (0.0, 0.0, 0.05), (0.0, 0.0, 0.0, 1.0))


def test_adding_sensors(tmp_path):
    plan = prepare(scenario(tmp_path, """\
        robots:
          - name: mobot
            sensors:
              front/bumper: {type: contact, link: base_link}
              side-scan: {type: ray, link: base_link, samples: 1, range_max: 2, rate_hz: 30}
              chassis_bump: {type: contact, link: base_link, collision: base_link}
        """)).plan
    found = sensors(plan)
    assert list(found) == ["front_bumper", "side-scan", "chassis_bump"]
    bumper = found["front_bumper"]
    assert (bumper.kind, bumper.topic, bumper.collision, bumper.every, bumper.source) == \
        ("contact", "front/bumper", "", 1, "scenario")
    side = found["side-scan"]  # not a ROS name: the kind's topic; SDFormat's defaults elsewhere
    assert (side.topic, side.every, side.horizontal, side.range_min) == ("scan", 8, RayAxis(1, 0.0, 0.0),
                                                                         0.0)
    assert found["chassis_bump"].collision == "base_link_collision"


@pytest.mark.parametrize("off", ["false", "off", "{enabled: false}"])
def test_turning_a_sensor_off(tmp_path, off):
    text = f"robots:\n  - {{name: mobot, args: {{imu: 'true'}}, sensors: {{imu: {off}}}}}\n"
    plan = prepare(scenario(tmp_path, text)).plan
    assert plan.robots[0].sensors == ()


@pytest.mark.parametrize("on", ["true", "on", "{}", "{enabled: true}"])
def test_on_keeps_a_sensor_as_described(tmp_path, on):
    text = f"robots:\n  - {{name: mobot, args: {{imu: 'true'}}, sensors: {{imu: {on}}}}}\n"
    plan = prepare(scenario(tmp_path, text)).plan
    described = prepare(scenario(tmp_path, "robots:\n  - {name: mobot, args: {imu: 'true'}}\n")).plan
    assert plan.robots[0].sensors == described.robots[0].sensors


def test_keys_by_name_topic_and_last_segment(corpus, tmp_path, monkeypatch):
    monkeypatch.setenv("MOBOT_RESOURCE_PATH", str(corpus / "turtlebot3"))
    for key in ("scan", "lds_lfcd_sensor"):
        plan = prepare(scenario(tmp_path, f"""\
            robots:
              - name: tb3
                description: {corpus / TURTLEBOT}
                sensors: {{{key}: {{rate_hz: 10, range_max: 8}}, imu: {{rate_hz: 200}}}}
            """)).plan
        lds, imu = sensors(plan)["lds_lfcd_sensor"], sensors(plan)["imu"]
        assert (lds.every, lds.range_max, lds.range_min, lds.horizontal.samples) == (24, 8.0, 0.12, 360)
        assert (lds.topic, lds.frame_id) == ("scan", "base_scan")
        assert imu.every == 1
    assert sensor_notices(plan) == [
        f"{tmp_path / 's.yaml'}:7, key 'robots.tb3.sensors.imu.rate_hz': rate_hz 200 is not a whole "
        "number of physics steps at 240 Hz: reading every 1 steps (240 Hz)"]


TWO_LIDARS = """<robot name="two"><link name="base_link">
  <inertial><mass value="1"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial>
  <collision><geometry><box size="0.2 0.2 0.2"/></geometry></collision></link>
  {0}</robot>"""
LIDAR = """<gazebo reference="base_link"><sensor name="{0}" type="ray"><update_rate>10</update_rate>
  <ray><scan><horizontal><samples>10</samples><min_angle>-1</min_angle><max_angle>1</max_angle></horizontal>
  </scan><range><max>5</max></range></ray><plugin name="p" filename="libgazebo_ros_ray_sensor.so">
  <ros><remapping>~/out:={1}/scan</remapping></ros></plugin></sensor></gazebo>"""


@pytest.fixture
def two_lidars(tmp_path) -> Path:
    path = tmp_path / "two.urdf"
    path.write_text(TWO_LIDARS.format(LIDAR.format("front_lidar", "front") + LIDAR.format("rear_lidar", "rear")))
    return path


def test_a_key_naming_two_sensors_is_an_error(tmp_path, two_lidars):
    body = f"robots:\n  - {{name: r, description: {two_lidars}, sensors: {{scan: {{rate_hz: 5}}}}}}\n"
    with pytest.raises(ScenarioError) as err:
        prepare(scenario(tmp_path, body))
    assert str(err.value) == (
        f"{tmp_path / 's.yaml'}:5, key 'robots.r.sensors.scan': 'scan' names 2 sensors of "
        "'two': 'front_lidar' (topic front/scan), 'rear_lidar' (topic rear/scan). Use a "
        "sensor's name or its whole topic as the key.")
    body = f"robots:\n  - {{name: r, description: {two_lidars}, sensors: {{rear/scan: {{rate_hz: 5}}}}}}\n"
    assert [s.every for s in prepare(scenario(tmp_path, body)).plan.robots[0].sensors] == [24, 48]


def test_two_keys_for_one_sensor_is_an_error(tmp_path, two_lidars):
    body = (f"robots:\n  - {{name: r, description: {two_lidars}, sensors: "
            "{front/scan: {rate_hz: 5}, front_lidar: false}}\n")
    with pytest.raises(ScenarioError, match="'front_lidar' names sensor 'front_lidar', as 'front/scan' does"):
        prepare(scenario(tmp_path, body))


def test_set_changes_and_adds_sensors(tmp_path):
    path = scenario(tmp_path, "robots:\n  - {name: mobot, args: {lidar: 'true', imu: 'true'}}\n")
    plan = prepare(path, ["robots.mobot.sensors.scan.rate_hz=5",
                          "robots.mobot.sensors.bump={type: contact, link: base_link}",
                          "robots.mobot.sensors.imu=off"]).plan
    assert [(s.name, s.every) for s in plan.robots[0].sensors] == [("lidar", 48), ("bump", 1)]
    with pytest.raises(ScenarioError) as err:
        prepare(path, ["robots.mobot.sensors.scan.samples=0"])
    assert str(err.value) == ("--set robots.mobot.sensors.scan.samples=0, key 'robots.mobot.sensors.scan."
                              "samples': Input should be greater than or equal to 1, got 0. Give a whole "
                              "number of rays from 1 to 100000.")


def test_description_rates_against_the_physics_rate(tmp_path):
    slow = prepare(scenario(tmp_path, "robots:\n  - {name: mobot, args: {imu: 'true'}}\n", physics=100)).plan
    assert slow.robots[0].sensors[0].every == 1
    assert sensor_notices(slow) == ["robot 'mobot': sensor 'imu' of mobot.urdf.xacro at 120 Hz is above "
                                    "physics.rate_hz 100: it reads every step"]
    fast = prepare(scenario(tmp_path, "robots:\n  - {name: mobot, args: {imu: 'true'}}\n", physics=1000)).plan
    assert fast.robots[0].sensors[0].every == 8
    assert sensor_notices(fast) == ["robot 'mobot': sensor 'imu' of mobot.urdf.xacro at 120 Hz is not a "
                                    "whole number of physics steps at 1000 Hz: reading every 8 steps (125 Hz)"]


@pytest.mark.parametrize("count", [3, 5])
def test_many_description_sensors_between_whole_steps_make_one_warning(tmp_path, count):
    """TurtleBot 4 has 14 sensors at 62 Hz: one warning lists them all, not 14 lines (up to three
    get a line each, as one does)."""
    lidars = "".join(LIDAR.format(f"l{i}", f"l{i}").replace("<update_rate>10<", "<update_rate>62<")
                     for i in range(count))
    path = tmp_path / "many.urdf"
    path.write_text(TWO_LIDARS.format(lidars))
    plan = prepare(scenario(tmp_path, f"robots:\n  - {{name: r, description: {path}}}\n")).plan
    assert [s.every for s in plan.robots[0].sensors] == [4] * count
    said = [n for n in plan.notices if "whole number of physics steps" in n]
    if count == 3:
        assert said == [f"robot 'r': sensor 'l{i}' of many.urdf at 62 Hz is not a whole number of physics steps "
                        "at 240 Hz: reading every 4 steps (60 Hz)" for i in range(3)]
    else:
        assert said == ["robot 'r': 5 sensors of many.urdf read at rates that are not a whole number of physics "
                        "steps at 240 Hz, each every whole number of steps instead: "
                        + ", ".join(f"'l{i}' 62 Hz -> 60 Hz" for i in range(5))]


def test_fleets_and_spawned_robots_get_their_sensors(tmp_path):
    plan = prepare(scenario(tmp_path, """\
        robots:
          - name: m_{i}
            count: 2
            poses: [[0, 0, 0], [1, 0, 0]]
            args: {imu: "true"}
            sensors: {imu: {rate_hz: 60}}
        events:
          - {at: 1.0, spawn: {name: late, args: {imu: "true"}, sensors: {imu: false}}}
        """)).plan
    assert [r.sensors[0].every for r in plan.robots] == [4, 4]
    assert plan.events[0].spawn.sensors == ()


def test_a_live_spawn_error_has_no_location(tmp_path):
    ctx = RobotResolver(240, 120, 2400, base_dir=tmp_path)
    spec = RobotSpec.model_validate({"name": "r", "args": {"imu": "true"}, "sensors": {"imu": {"rate_hz": 500}}})
    with pytest.raises(ScenarioError) as err:
        ctx.plans(spec, ("robots", 0))
    assert str(err.value) == "rate_hz 500 is above physics.rate_hz 240. A sensor reads at most once per physics step."


def test_resolved_scenario_writes_the_scenario_sensors_and_round_trips(tmp_path):
    first = prepare(scenario(tmp_path, """\
        robots:
          - name: mobot
            args: {lidar: "true", imu: "true"}
            sensors:
              scan: {rate_hz: 7, samples: 180, pose: {xyz: [0, 0, 0.01], rpy: [0, 0, 0.5]}}
              imu: off
              bump: {type: contact, link: base_link, collision: base_link}
        """))
    assert ("\n  sensors:\n"
            "    scan:\n"
            "      rate_hz: 7.0588235294117645\n"
            "      pose:\n"
            "        xyz: [0.0, 0.0, 0.01]\n"
            "        rpy: [0.0, 0.0, 0.5]\n"
            "      samples: 180\n"
            "    imu: false\n"
            "    bump: {type: contact, link: base_link, collision: base_link}\n"
            "  commands: []\n") in first.resolved_yaml
    again_path = tmp_path / "resolved.yaml"
    again_path.write_text(first.resolved_yaml)
    again = prepare(again_path)
    assert again.plan.robots == first.plan.robots
    assert again.resolved_yaml == first.resolved_yaml


def test_scenarios_without_sensors_resolve_without_a_sensors_key():
    assert "sensors" not in prepare(REPO / "scenarios" / "fleet.yaml").resolved_yaml


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(rate=st.floats(min_value=0.01, max_value=240.0), physics=st.sampled_from([60, 240, 1000]))
def test_any_rate_becomes_whole_steps_and_reloads_to_the_same(tmp_path, rate, physics):
    """An accepted rate reads every nearest whole number of steps; the resolved rate keeps it."""
    if rate > physics:
        return
    os.makedirs(tmp_path, exist_ok=True)
    path = scenario(tmp_path,
                    f"robots:\n  - {{name: mobot, args: {{imu: 'true'}}, sensors: {{imu: {{rate_hz: {rate!r}}}}}}}\n",
                    physics=physics)
    first = prepare(path)
    every = first.plan.robots[0].sensors[0].every
    assert every >= 1 and abs(every - physics / rate) <= 0.5 + 1e-9  # the nearest whole step
    again = tmp_path / "again.yaml"
    again.write_text(first.resolved_yaml)
    assert prepare(again).plan.robots == first.plan.robots


def test_the_docs_sensors_example(tmp_path):
    page = (REPO / "docs" / "sensors.md").read_text()
    section = page[page.index("## Where sensors come from"):]
    example = next(b for b in section.split("```yaml\n")[1:] if "sensors:" in b).split("```")[0]
    path = tmp_path / "s.yaml"
    path.write_text(example if example.startswith("version:") else "version: 1\nduration: 2\n" + example)
    plan = prepare(path).plan
    assert [(s.name, s.kind, s.every) for s in plan.robots[0].sensors] == \
        [("lidar", "lidar", 24), ("imu", "imu", 2), ("bumper", "contact", 1)]  # 10 Hz, 120 Hz, every step
    assert plan.robots[0].sensors[0].range_max == 8.0


FIELDS = ["enabled", "type", "link", "rate_hz", "pose", "samples", "min_angle", "max_angle", "vertical_samples",
          "vertical_min_angle", "vertical_max_angle", "range_min", "range_max", "range_resolution", "noise_mean",
          "noise_stddev", "accel_noise_stddev", "collision", "topic", "frame_id", "xyz", "rpy", "quat"]
WORDS = ["scan", "imu", "lidar", "ray", "contact", "base_link", "lidar_link", "caster", "off", "on", "a/b",
         "base_link_collision", "", " ", "/scan", "-x", "x" * 300]
LEAF = st.one_of(st.floats(), st.integers(-10**6, 10**6), st.booleans(), st.none(), st.sampled_from(WORDS),
                 st.text(max_size=8))
VALUE = st.recursive(LEAF, lambda inner: st.lists(inner, max_size=4) | st.dictionaries(
    st.sampled_from(FIELDS), inner, max_size=3), max_leaves=8)
ENTRY = st.one_of(VALUE, st.dictionaries(st.sampled_from(FIELDS), VALUE, max_size=5))


@settings(max_examples=80, derandomize=True, deadline=None, database=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
@given(entries=st.dictionaries(st.sampled_from(WORDS) | st.text(max_size=6), ENTRY, max_size=3))
def test_any_sensors_mapping_loads_or_is_refused_with_one_paragraph(tmp_path, entries):
    """Fuzzed sensors: entries resolve, or fail as a located MobotError; never another exception."""
    import yaml

    from mobot_cli.errors import MobotError

    os.makedirs(tmp_path, exist_ok=True)
    document = {"version": 1, "duration": 1, "robots": [{"name": "mobot", "args": {"lidar": "true"},
                                                         "sensors": entries}]}
    path = tmp_path / "fuzz.yaml"
    path.write_text(yaml.safe_dump(document))
    try:
        first = prepare(path)
    except MobotError as exc:
        assert "\n" not in str(exc) and str(path) in str(exc)
        return
    again = tmp_path / "again.yaml"
    again.write_text(first.resolved_yaml)
    assert prepare(again).plan.robots == first.plan.robots


def test_a_world_robot_takes_sensors_too(corpus, tmp_path):
    world = corpus / "dolly/dolly_gazebo/worlds/dolly_empty.world"
    plan = prepare(scenario(tmp_path, f"world: {world}\nrobots:\n"
                                      "  - {name: Dolly, sensors: {laser_scan: {rate_hz: 48}}}\n")).plan
    laser, = plan.robots[0].sensors
    assert (laser.name, laser.topic, laser.link, laser.every, laser.horizontal.samples) == \
        ("sensor_ray", "laser_scan", "chassis", 5, 200)


SONARS = """<?xml version="1.0"?>
<robot name="sonars">
  <link name="base_link">
    <inertial><mass value="5"/><inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/></inertial>
    <collision><origin xyz="0 0 0.1"/><geometry><box size="0.4 0.3 0.2"/></geometry></collision>
  </link>
  {sonars}
</robot>
"""
SONAR = """<link name="{name}_link"/>
  <joint name="{name}_joint" type="fixed"><parent link="base_link"/><child link="{name}_link"/>
    <origin xyz="0.2 {y} 0.1"/></joint>
  <gazebo reference="{name}_link"><sensor type="ray" name="{name}"><update_rate>10</update_rate>
    <ray><scan><horizontal><samples>5</samples><min_angle>-0.1</min_angle><max_angle>0.1</max_angle></horizontal>
    </scan><range><min>0.02</min><max>3</max></range></ray>
    <plugin name="{name}_plugin" filename="libgazebo_ros_ray_sensor.so">
      <ros><remapping>~/out:=sonar_base</remapping></ros><output_type>sensor_msgs/Range</output_type>
    </plugin></sensor></gazebo>"""


def test_description_sensors_on_one_topic_get_numbered_topics(tmp_path):
    """A sonar array on one topic, each sonar with its frame (PAL's PMB2), as Gazebo allows: the
    first keeps the topic, the others get numbered ones, said; a topic the scenario gives twice
    is still an error."""
    sonars = "\n  ".join(SONAR.format(name=f"sonar_{k}", y=y) for k, y in ((1, 0.1), (2, 0.0), (3, -0.1)))
    (tmp_path / "sonars.urdf").write_text(SONARS.format(sonars=sonars))
    plan = prepare(scenario(tmp_path, """\
        robots:
          - {name: r, description: sonars.urdf}
        """)).plan
    found = sensors(plan)
    assert [(s.kind, s.topic) for s in found.values()] == [("range", "sonar_base"), ("range", "sonar_base_2"),
                                                          ("range", "sonar_base_3")]
    said = [n for n in plan.notices if "publish on" in n]
    assert len(said) == 2 and "'sonar_2' publishes on 'sonar_base_2'" in said[0]
    with pytest.raises(ScenarioError, match="both publish on 'sonar_base'"):
        prepare(scenario(tmp_path, """\
            robots:
              - name: r
                description: sonars.urdf
                sensors: {sonar_2: {topic: sonar_base}}
            """))
