"""The sensor messages mobot's ROS 2 node sends (PointCloud2, Imu, gazebo_msgs/ContactsState),
checked without a network: the bytes equal rosbags' serializer and cyclonedds' IDL for the
same values, their DDS type names are ROS 2's, and their type hashes are the ones ROS ships."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mobot_cli.plan import RayAxis, SensorSpec
from mobot_cli.ros import sensor_cdr
from mobot_cli.ros.definitions import CONTACTS_STATE, IMU, POINT_CLOUD2
from mobot_cli.ros2 import names
from mobot_cli.sim.sensing.lidar import Beams
from mobot_cli.sim.sensing.readings import Contact
from tests.record.test_sensor_records import _typestore
from tests.sim.sensor_world import lidar

pytest.importorskip("cyclonedds")
from mobot_cli.ros2 import idl  # noqa: E402 - needs cyclonedds
from mobot_cli.ros2.publisher import type_hash  # noqa: E402

finite = st.floats(min_value=-1e6, max_value=1e6, allow_nan=False)
vector = st.tuples(finite, finite, finite)
stamps = st.tuples(st.integers(0, 2**31 - 1), st.integers(0, 999_999_999))
# The hashes in the type descriptions ROS 2 ships (share/sensor_msgs/msg/*.json of the Jazzy
# 5.3.6 and Kilted wheels); gazebo_msgs has no Jazzy build, so its hash is rosbags' alone.
SHIPPED = {"sensor_msgs/msg/Imu": "RIHS01_7d9a00ff131080897a5ec7e26e315954b8eae3353c3f995c55faf71574000b5b",
           "sensor_msgs/msg/PointCloud2": "RIHS01_9198cabf7da3796ae6fe19c4cb3bdd3525492988c70522628af5daa124bae2b5",
           "sensor_msgs/msg/LaserScan": "RIHS01_64c191398013af96509d518dac71d5164f9382553fce5c1f8cca5be7924bd828"}


@pytest.fixture(scope="module")
def store():
    return _typestore()


def _header(store, stamp, frame):
    t = store.types
    return t["std_msgs/msg/Header"](stamp=t["builtin_interfaces/msg/Time"](sec=stamp[0], nanosec=stamp[1]),
                                    frame_id=frame)


def _idl_header(stamp, frame):
    return idl.Header(idl.Time(*stamp), frame)


def _diagonal(value):
    return [value, 0.0, 0.0, 0.0, value, 0.0, 0.0, 0.0, value]


@settings(max_examples=40, deadline=None)
@given(stamp=stamps, quat=st.tuples(finite, finite, finite, finite), gyro=vector, accel=vector,
       gyro_noise=st.floats(0, 10), accel_noise=st.floats(0, 10))
def test_imu_bytes_equal_rosbags_and_cyclonedds(store, stamp, quat, gyro, accel, gyro_noise, accel_noise):
    spec = SensorSpec(name="imu", kind="imu", link="base_link", every=2, noise_stddev=gyro_noise,
                      accel_noise_stddev=accel_noise)
    ours = sensor_cdr.imu(stamp, "r1/imu_link", spec, quat, gyro, accel)
    t = store.types
    V, Q = t["geometry_msgs/msg/Vector3"], t["geometry_msgs/msg/Quaternion"]
    msg = t[IMU](header=_header(store, stamp, "r1/imu_link"), orientation=Q(x=quat[0], y=quat[1], z=quat[2], w=quat[3]),
                 orientation_covariance=np.zeros(9), angular_velocity=V(x=gyro[0], y=gyro[1], z=gyro[2]),
                 angular_velocity_covariance=np.array(_diagonal(gyro_noise ** 2)),
                 linear_acceleration=V(x=accel[0], y=accel[1], z=accel[2]),
                 linear_acceleration_covariance=np.array(_diagonal(accel_noise ** 2)))
    assert ours == bytes(store.serialize_cdr(msg, IMU))
    theirs = idl.Imu(_idl_header(stamp, "r1/imu_link"), idl.Quaternion(*quat), [0.0] * 9, idl.Vector3(*gyro),
                     _diagonal(gyro_noise ** 2), idl.Vector3(*accel), _diagonal(accel_noise ** 2)).serialize()
    assert ours == theirs


@settings(max_examples=25, deadline=None)
@given(stamp=stamps, ranges=st.lists(st.one_of(st.floats(0.1, 30.0), st.just(float("inf"))), min_size=12,
                                     max_size=12))
def test_point_cloud2_bytes_equal_rosbags_and_cyclonedds(store, stamp, ranges):
    spec = lidar("velodyne", samples=4, lo=-1.0, hi=1.0, vertical=RayAxis(3, -0.2, 0.2), range_max=30.0)
    grid = np.array(ranges, dtype=np.float32).reshape(3, 4)
    ours = sensor_cdr.point_cloud2(stamp, "r1/velodyne", grid, Beams.of(spec))
    keep = np.isfinite(grid.reshape(-1))
    points = np.zeros((int(keep.sum()), 4), dtype="<f4")
    points[:, :3] = Beams.of(spec).directions[keep] * grid.reshape(-1)[keep, None].astype(float)
    data = points.reshape(-1).view(np.uint8)
    t = store.types
    fields = [t["sensor_msgs/msg/PointField"](name=n, offset=o, datatype=7, count=1)
              for n, o in (("x", 0), ("y", 4), ("z", 8), ("intensity", 12))]
    msg = t[POINT_CLOUD2](header=_header(store, stamp, "r1/velodyne"), height=1, width=len(points), fields=fields,
                          is_bigendian=False, point_step=16, row_step=16 * len(points), data=data, is_dense=True)
    assert ours == bytes(store.serialize_cdr(msg, POINT_CLOUD2))
    theirs = idl.PointCloud2(_idl_header(stamp, "r1/velodyne"), 1, len(points),
                             [idl.PointField(n, o, 7, 1) for n, o in (("x", 0), ("y", 4), ("z", 8), ("intensity", 12))],
                             False, 16, 16 * len(points), data.tolist(), True).serialize()
    assert ours == theirs
    decoded = idl.PointCloud2.deserialize(ours)
    assert np.array_equal(np.frombuffer(bytes(decoded.data), "<f4").reshape(-1, 4), points)


@settings(max_examples=40, deadline=None)
@given(stamp=stamps, frame=st.text("abc/_", max_size=9), lo=st.floats(-3.2, 0), hi=st.floats(0.01, 3.2),
       ranges=st.lists(st.one_of(st.floats(0.125, 30.0, width=32), st.just(float("inf"))), min_size=1, max_size=40))
def test_laser_scan_bytes_equal_rosbags_and_cyclonedds(store, stamp, frame, lo, hi, ranges):
    spec = lidar(samples=len(ranges), lo=lo, hi=hi if len(ranges) > 1 else lo, range_min=0.12, range_max=30.0)
    ours = sensor_cdr.laser_scan(stamp, frame, spec, np.array(ranges, dtype=np.float32))
    step = (spec.horizontal.max_angle - lo) / (len(ranges) - 1) if len(ranges) > 1 else 0.0
    values = dict(angle_min=lo, angle_max=spec.horizontal.max_angle, angle_increment=step, time_increment=0.0,
                  scan_time=0.0, range_min=0.12, range_max=30.0)
    msg = store.types["sensor_msgs/msg/LaserScan"](
        header=_header(store, stamp, frame), ranges=np.array(ranges, dtype=np.float32),
        intensities=np.zeros(len(ranges), dtype=np.float32), **{k: np.float32(v) for k, v in values.items()})
    assert ours == bytes(store.serialize_cdr(msg, "sensor_msgs/msg/LaserScan"))
    assert ours == idl.LaserScan(_idl_header(stamp, frame), ranges=ranges, intensities=[0.0] * len(ranges),
                                 **values).serialize()


contacts = st.lists(st.builds(Contact, st.sampled_from(["wall", "robot 'b'"]), vector, vector,
                              st.floats(0, 0.01), st.floats(0, 100)), max_size=5)


@settings(max_examples=40, deadline=None)
@given(stamp=stamps, touching=contacts)
def test_contacts_state_bytes_equal_rosbags_and_cyclonedds(store, stamp, touching):
    ours = sensor_cdr.contacts_state(stamp, "world", "r1::base_link::bumper", touching)
    t = store.types
    V, W = t["geometry_msgs/msg/Vector3"], t["geometry_msgs/msg/Wrench"]
    groups: dict[str, list[Contact]] = {}
    for c in touching:
        groups.setdefault(c.other, []).append(c)
    states, idl_states = [], []
    for other, points in groups.items():
        forces = [tuple(c.force * n for n in c.normal) for c in points]
        total = tuple(float(v) for v in np.sum(forces, axis=0))
        states.append(t["gazebo_msgs/msg/ContactState"](
            info=f"r1::base_link::bumper touches {other}", collision1_name="r1::base_link::bumper",
            collision2_name=other, wrenches=[W(force=V(x=f[0], y=f[1], z=f[2]), torque=V(x=0.0, y=0.0, z=0.0))
                                             for f in forces],
            total_wrench=W(force=V(x=total[0], y=total[1], z=total[2]), torque=V(x=0.0, y=0.0, z=0.0)),
            contact_positions=[V(x=p[0], y=p[1], z=p[2]) for p in (c.position for c in points)],
            contact_normals=[V(x=n[0], y=n[1], z=n[2]) for n in (c.normal for c in points)],
            depths=np.array([c.depth for c in points], dtype=np.float64)))
        zero = idl.Vector3(0.0, 0.0, 0.0)
        idl_states.append(idl.ContactState(
            f"r1::base_link::bumper touches {other}", "r1::base_link::bumper", other,
            [idl.Wrench(idl.Vector3(*f), zero) for f in forces], idl.Wrench(idl.Vector3(*total), zero),
            [idl.Vector3(*c.position) for c in points], [idl.Vector3(*c.normal) for c in points],
            [c.depth for c in points]))
    msg = t[CONTACTS_STATE](header=_header(store, stamp, "world"), states=states)
    assert ours == bytes(store.serialize_cdr(msg, CONTACTS_STATE))
    assert ours == idl.ContactsState(_idl_header(stamp, "world"), idl_states).serialize()


def test_sensor_types_have_ros2_dds_names_and_the_shipped_hashes(store):
    for msgtype in (POINT_CLOUD2, IMU, CONTACTS_STATE, "sensor_msgs/msg/LaserScan"):
        assert idl.TYPES[msgtype].__idl__.idl_transformed_typename == names.dds_type(msgtype)
        assert type_hash(msgtype) == store.hash_rihs01(msgtype), msgtype
        assert type_hash(msgtype) == SHIPPED.get(msgtype, type_hash(msgtype))
    assert names.dds_type(POINT_CLOUD2) == "sensor_msgs::msg::dds_::PointCloud2_"
    assert names.dds_type(CONTACTS_STATE) == "gazebo_msgs::msg::dds_::ContactsState_"
