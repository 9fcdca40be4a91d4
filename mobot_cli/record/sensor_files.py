"""``DIR/sensors/<robot>/``: every sensor's readings in a file NumPy or pandas loads in one line.

* lidar: ``<sensor>.npy``, one row per scan of a structured dtype ``t`` (float64, s) and
  ``ranges`` (float32, (beams,) or (rows, beams) for a 3D lidar; +inf: no return), and
  ``<sensor>.json`` with the beam angles, range limits, frame and topic;
  ``scan = np.load("sensors/mobot/scan.npy"); scan["t"], scan["ranges"]``
  (``mmap_mode="r"`` reads a long run without loading it);
* range: ``<sensor>.csv``: t, range (m; range_max when nothing is in its field of view);
* imu: ``<sensor>.csv``: t, qx, qy, qz, qw, wx, wy, wz, ax, ay, az;
* contact: ``<sensor>.csv``: t, contacts, other, x, y, z, nx, ny, nz, depth, force, one row
  per contact point (a reading without contact is one row with contacts 0);
* camera, depth, rgbd: a folder ``<sensor>/`` of PNG frames (record/camera_files.py).

Files stream as readings come: rows are appended in chunks, flushed, and only then does the
.npy header (fixed size, written first) learn the new row count, so a killed run leaves
files that load up to their last complete chunk.
"""

from __future__ import annotations

import ast
import csv
import io
import json
import re
import struct
from pathlib import Path

import numpy as np

from mobot_cli.common.numbers import number
from mobot_cli.plan import Plan, RobotPlan, SensorSpec
from mobot_cli.record import camera_files
from mobot_cli.record.camera_files import CameraFrames
from mobot_cli.ros import sensor_topics
from mobot_cli.sim.sensing.lidar import angle_step, axis_angles
from mobot_cli.timeline.records import Reading, Sink

NPY_MAGIC = b"\x93NUMPY\x01\x00"
NPY_HEADER = 1024  # bytes, magic included: room for any row count and beam grid
FLUSH_EVERY = 50  # readings (5 s of a 10 Hz lidar), as the odometry CSV's rows: a killed run loses at most this many
FLUSH_BYTES = 4 << 20
RANGE_COLUMNS = ("t", "range")
IMU_COLUMNS = ("t", "qx", "qy", "qz", "qw", "wx", "wy", "wz", "ax", "ay", "az")
CONTACT_COLUMNS = ("t", "contacts", "other", "x", "y", "z", "nx", "ny", "nz", "depth", "force")
_UNSAFE = re.compile(r"[^A-Za-z0-9_.-]")


def file_stem(sensor: str) -> str:
    """A sensor's name as a file name."""
    return _UNSAFE.sub("_", sensor) or "sensor"


def sensor_file(key: str, spec: SensorSpec) -> str:
    """The run-folder path of a sensor's readings, relative to the folder."""
    if spec.kind in ("camera", "depth", "rgbd"):
        return f"sensors/{file_stem(key)}/{file_stem(spec.name)}/frames.csv"  # beside its frames
    return f"sensors/{file_stem(key)}/{file_stem(spec.name)}.{'npy' if spec.kind == 'lidar' else 'csv'}"


class NpyRows:
    """A lidar's .npy file of (t, ranges) rows that grows as scans come. Scans wait until the
    chunk is written, so that their ranges are read (and cast, sim/sensing/rig.py) a chunk at a time."""

    def __init__(self, path: Path, dtype: np.dtype):
        self.dtype, self.rows = dtype, 0
        self._times: list[float] = []
        self._scans: list = []
        self._buffered = 0
        self._header_text = repr({"descr": np.lib.format.dtype_to_descr(dtype), "fortran_order": False,
                                  "shape": (0,)}).rsplit("(0,)", 1)  # the row count goes between the parts
        self._file = path.open("wb")
        self._file.write(self._header(0))
        self._file.flush()

    def _header(self, rows: int) -> bytes:
        body = f"({rows},)".join(self._header_text).encode("latin1")
        room = NPY_HEADER - len(NPY_MAGIC) - 2 - 1
        if len(body) > room:
            raise ValueError(f"a .npy header of {len(body)} bytes does not fit in {room}")
        return NPY_MAGIC + struct.pack("<H", room + 1) + body.ljust(room) + b"\n"

    def append(self, t: float, scan) -> None:
        """One scan (sim.sensors.ScanData) read at ``t`` seconds."""
        self._times.append(t)
        self._scans.append(scan)
        self._buffered += self.dtype.itemsize
        if len(self._scans) >= FLUSH_EVERY or self._buffered >= FLUSH_BYTES:
            self.flush()

    def flush(self) -> None:
        """Write the waiting rows, then the header that counts them."""
        if not self._scans:
            return
        rows = np.empty(len(self._scans), self.dtype)  # the file's own layout: one write
        rows["t"] = self._times
        field = rows["ranges"]  # (scans, beams) for a 2D lidar, (scans, rows, beams) for a 3D one
        if field.ndim == 2:  # each scan's one row of ranges: all copied in one call, twice as fast
            np.concatenate([scan.ranges for scan in self._scans], out=field)
        else:
            for i, scan in enumerate(self._scans):
                field[i] = scan.ranges
        f = self._file
        f.write(rows.data)
        self.rows += len(rows)
        self._times, self._scans, self._buffered = [], [], 0
        f.flush()
        f.seek(0)
        f.write(self._header(self.rows))
        f.seek(0, io.SEEK_END)
        f.flush()

    def close(self) -> None:
        self.flush()
        self._file.close()


class _CsvRows:
    """A CSV file flushed every few readings (whole rows only, as the odom CSV)."""

    def __init__(self, path: Path, columns: tuple[str, ...]):
        self._file = path.open("w", encoding="utf-8", newline="", buffering=1 << 20)
        self._csv = csv.writer(self._file, lineterminator="\n")
        self._csv.writerow(columns)
        self._readings = 0

    def write(self, rows: list[list[str]]) -> None:
        self._csv.writerows(rows)
        self._readings += 1
        if self._readings % FLUSH_EVERY == 0:
            self._file.flush()

    def close(self) -> None:
        self._file.close()


def scan_dtype(spec: SensorSpec) -> np.dtype:
    """Rows of a lidar's file: time and the ranges of one scan."""
    h = spec.horizontal.samples if spec.horizontal is not None else 1
    v = spec.vertical.samples if spec.vertical is not None else 1
    return np.dtype([("t", "<f8"), ("ranges", "<f4", (h,) if v <= 1 else (v, h))])


def describe(key: str, robot: RobotPlan, spec: SensorSpec, physics_rate_hz: int) -> dict:
    """What the .json beside a lidar's .npy says: beams, limits, frame, topic."""
    out = {"robot": key, "sensor": spec.name, "kind": spec.kind, "link": spec.link,
           "topic": sensor_topics.topic(robot, spec), "frame_id": sensor_topics.sensor_frame(robot, spec).frame,
           "rate_hz": sensor_topics.rate_hz(spec, physics_rate_hz),
           "range_min": spec.range_min, "range_max": spec.range_max,
           "angle_min": spec.horizontal.min_angle if spec.horizontal else 0.0,
           "angle_max": spec.horizontal.max_angle if spec.horizontal else 0.0,
           "angle_increment": angle_step(spec.horizontal),
           "angles": axis_angles(spec.horizontal).tolist()}
    if spec.vertical is not None and spec.vertical.samples > 1:
        out.update(vertical_angle_min=spec.vertical.min_angle, vertical_angle_max=spec.vertical.max_angle,
                   vertical_angles=axis_angles(spec.vertical).tolist())
    return out


class SensorFilesSink(Sink):
    """Writes every reading to ``DIR/sensors/<robot>/``, opening a sensor's file at its first."""

    def __init__(self, plan: Plan, out_dir: Path):
        self.rate = plan.physics.rate_hz
        self.out_dir = out_dir
        self.files: dict[tuple[str, str], NpyRows | _CsvRows | CameraFrames] = {}
        self.robots: dict[str, RobotPlan] = {}

    def spawned(self, step: int, key: str, robot: RobotPlan) -> None:
        self.robots[key] = robot

    def reading(self, key: str, reading: Reading) -> None:
        spec = reading.sensor
        target = self.files.get((key, spec.name))
        if target is None:
            target = self.files[(key, spec.name)] = self._open(key, spec)
        t = reading.step / self.rate
        data = reading.data
        if spec.kind == "lidar":
            target.append(t, data)
        elif spec.kind == "range":
            target.write([[number(t), number(data.range)]])
        elif spec.kind in ("camera", "depth", "rgbd"):
            target.append(reading.step, t, data)
        elif spec.kind == "imu":
            target.write([[number(v) for v in (t, *data.orientation, *data.angular_velocity,
                                                *data.linear_acceleration)]])
        else:
            target.write(_contact_rows(t, data.contacts))

    def _open(self, key: str, spec: SensorSpec) -> NpyRows | _CsvRows | CameraFrames:
        path = self.out_dir / sensor_file(key, spec)
        if spec.kind in ("camera", "depth", "rgbd"):
            return CameraFrames(path.parent, camera_files.describe(key, self.robots[key], spec, self.rate))
        path.parent.mkdir(parents=True, exist_ok=True)
        if spec.kind == "lidar":
            # Written whole at the first reading, not fsynced (summary.json is the record that is).
            path.with_suffix(".json").write_text(
                json.dumps(describe(key, self.robots[key], spec, self.rate), indent=2) + "\n", encoding="utf-8")
            return NpyRows(path, scan_dtype(spec))
        columns = {"range": RANGE_COLUMNS, "imu": IMU_COLUMNS}.get(spec.kind, CONTACT_COLUMNS)
        return _CsvRows(path, columns)

    def close(self) -> None:
        for target in self.files.values():
            target.close()


def _contact_rows(t: float, contacts) -> list[list[str]]:
    if not contacts:
        return [[number(t), "0"] + [""] * (len(CONTACT_COLUMNS) - 2)]
    return [[number(t), str(len(contacts)), c.other, *(number(v) for v in (*c.position, *c.normal)),
             number(c.depth), number(c.force)] for c in contacts]


def read_header_rows(path: Path) -> int:
    """The row count a sensor .npy's header states (what a reader of a killed run gets)."""
    with path.open("rb") as f:
        head = f.read(NPY_HEADER)
    if not head.startswith(NPY_MAGIC):
        return 0
    (length,) = struct.unpack("<H", head[8:10])
    return int(ast.literal_eval(head[10:10 + length].decode("latin1"))["shape"][0])
