"""Reading run folders back: how a run ended (``mobot check DIR``) and its paths (``mobot plot``).

A run folder is complete when summary.json says ``ok`` and every file it promises is there.
summary.json is written last and atomically, so a run killed mid-way has none; its CSV files
end at their last flush and its bag at its last MCAP chunk, which this module measures (and
``repair_run`` makes readable again, see bag_repair).
"""

from __future__ import annotations

import struct
from pathlib import Path
from typing import Any

from mobot_cli.errors import ExitCode, cannot_write
from mobot_cli.record.reader import RunFolder, RunFolderError, is_run_folder, is_sweep_folder  # noqa: F401
from mobot_cli.record.summary import SUMMARY, RunRecord, Status
from mobot_cli.ros.bag_repair import needs_repair, repair_bag

MCAP_MAGIC = b"\x89MCAP0\r\n"
_CHUNK, _RECORD = 0x06, struct.Struct("<BQ")


def run_status(folder: Path) -> dict[str, Any]:
    """How the run in ``folder`` ended: status ok / failed / incomplete / fault, and why."""
    run = RunFolder.open(folder)
    result: dict[str, Any] = {"kind": "run", "path": str(folder), "problems": [],
                              "csv": csv_extents(run), "bag": bag_status(run), "sensors": sensor_extents(run)}
    try:
        record = run.summary()
    except RunFolderError:
        record = None
    if record is None:
        result["problems"].append("summary.json is not a record mobot wrote" if (folder / SUMMARY).exists()
                                  else "no summary.json: the run was killed, or is still running")
        return _verdict(result, "incomplete")
    result.update(scenario=record.scenario, sim_time=record.sim_time, robots=sorted(record.robots),
                  run_status=record.status.value)
    if record.status != Status.OK:
        error = f": {record.error}" if record.error else ""
        result["problems"].append(f"summary.json says '{record.status.value}'{error}")
        return _verdict(result, "fault" if record.status == Status.FAULT else "incomplete")
    result["problems"] += _missing(run, record, result)
    if result["problems"]:
        return _verdict(result, "incomplete")
    failed = record.failed_expectations
    if failed:
        result["problems"].append(f"{failed} expectation(s) failed")
        return _verdict(result, "failed")
    return _verdict(result, "ok")


def _verdict(result: dict[str, Any], status: str) -> dict[str, Any]:
    codes = {"ok": ExitCode.OK, "failed": ExitCode.EXPECTATION_FAILED, "incomplete": ExitCode.BAD_INPUT,
             "fault": ExitCode.SIMULATION_FAULT}
    result.update(status=status, ok=status == "ok", exit_code=int(codes[status]))
    return result


def _missing(run: RunFolder, record: RunRecord, result: dict[str, Any]) -> list[str]:
    """What a complete run folder must hold but this one lacks."""
    folder = run.path
    problems = []
    for name, limit in (("scenario.yaml", run.limits.scenario), ("trajectory.png", run.limits.sensors)):
        try:
            if not (folder / name).is_file() or run.checked(name, limit) is None:
                problems.append(f"{name} is missing")
        except RunFolderError as exc:  # a symlink out, or too large to read back
            problems.append(exc.message)
    if (folder / "odom").is_dir():
        problems += [f"odom/{robot}.csv is missing" for robot in record.robots
                     if not (folder / "odom" / f"{robot}.csv").is_file()]
    problems += [f"{sensor.file} is missing" for robot in record.robots.values() for sensor in robot.sensors
                 if sensor.readings and not (folder / sensor.file).is_file()]
    problems += [f"odom/{robot}.csv has {extent['partial_rows']} damaged row(s)"
                 for robot, extent in result["csv"].items() if extent["partial_rows"]]
    bag = result["bag"]
    if bag is not None and not bag["complete"]:
        problems.append("bag/ has no metadata.yaml: it was not closed")
    elif bag is not None and bag["file"] and not bag.get("footer"):
        problems.append(f"bag/{bag['file']} ends before its footer: it is damaged or cut short")
    return problems


def csv_extents(run: RunFolder) -> dict[str, dict[str, Any]]:
    """Per odom CSV: how many whole rows it holds and the time of the last one."""
    out = {}
    for path in run.odometry():
        header, rows = run.csv_rows(path)
        whole = [row for row in rows if len(row) == 16 and all(_time(v) is not None for v in row)]
        out[path.stem] = {"rows": len(whole), "last_t": _time(whole[-1][0]) if whole else None,
                          "partial_rows": len(rows) - len(whole)}
    return out


def sensor_extents(run: RunFolder) -> dict[str, dict[str, Any]]:
    """Per sensor file (``sensors/<robot>/<sensor>.npy`` or ``.csv``): whole readings or rows in it,
    and the time of the last one."""
    out: dict[str, dict[str, Any]] = {}
    for path in run.listing("sensors", "*/*.npy"):
        import numpy as np

        checked = run.checked(path, run.limits.sensors)
        try:
            rows = np.load(checked, mmap_mode="r", allow_pickle=False)
            out[path.as_posix()] = {"rows": len(rows), "last_t": _time(rows["t"][-1]) if len(rows) else None}
        except (OSError, ValueError, KeyError, IndexError, TypeError):
            out[path.as_posix()] = {"rows": 0, "last_t": None}
    for path in run.listing("sensors", "*/*.csv"):
        _, rows = run.csv_rows(path)
        whole = [row for row in rows if len(row) > 1]
        out[path.as_posix()] = {"rows": len(whole), "last_t": _time(whole[-1][0]) if whole else None}
    return out


def _time(value) -> float | None:
    """A row's time, or None when the last row is damaged (text, NaN)."""
    try:
        t = float(value)
    except (TypeError, ValueError):
        return None
    return t if t == t and abs(t) != float("inf") else None


def bag_status(run: RunFolder) -> dict[str, Any] | None:
    """Whether a bag folder was closed, and how far its MCAP file can be read."""
    bag = run.bag_folder()
    if bag is None:
        return None
    files = sorted(bag.glob("*.mcap"))
    status: dict[str, Any] = {"complete": (bag / "metadata.yaml").is_file(), "file": files[0].name if files else None}
    if files:
        status.update(mcap_chunks(files[0]))
    status["repairable"] = needs_repair(bag) and status.get("chunks", 0) > 0
    return status


def repair_run(folder: Path) -> dict[str, Any]:
    """Make the bag of a killed run readable (``mobot check DIR --repair``): what it now holds,
    or why there was nothing to do."""
    bag = RunFolder.open(folder).bag_folder()
    if bag is None:
        return {"done": False, "why": "the run has no bag"}
    if not needs_repair(bag):
        return {"done": False, "why": "the bag was closed: it needs no repair"}
    try:
        repaired = repair_bag(bag)
    except OSError as exc:
        raise cannot_write(exc.filename or bag, exc) from None
    if not repaired.messages:
        return {"done": False, "why": f"bag/{bag.name}.mcap holds no complete chunk: nothing to keep"}
    return {"done": True, "file": f"bag/{bag.name}.mcap", **repaired.as_dict()}


def mcap_chunks(path: Path) -> dict[str, Any]:
    """Complete chunks of an MCAP file, read front to back, and the last message time in them."""
    chunks, end_ns, footer = 0, None, False
    with path.open("rb") as f:
        if f.read(len(MCAP_MAGIC)) != MCAP_MAGIC:
            return {"chunks": 0, "last_t": None, "footer": False}
        size = path.stat().st_size
        while True:
            head = f.read(_RECORD.size)
            if len(head) < _RECORD.size:
                break
            opcode, length = _RECORD.unpack(head)
            start = f.tell()
            if start + length > size:
                break  # a record cut short by the kill
            if opcode == _CHUNK and length >= 16:
                _, end_ns = struct.unpack("<QQ", f.read(16))
                chunks += 1
            footer = footer or opcode == 0x02
            f.seek(start + length)
    return {"chunks": chunks, "last_t": end_ns / 1e9 if end_ns is not None else None, "footer": footer}
