"""The BARN worlds a user points to: which folder, which world numbers, their reference paths,
and the scenario that drives a robot from BARN's start to its goal in them.

The worlds are not shipped with mobot: `mobot barn DIR` takes the folder holding
``world_0.world`` ... ``world_299.world`` and ``path_files/path_N.npy`` (in a clone of
github.com/Daffan/the-barn-challenge: ``jackal_helper/worlds/BARN``; the clone's root works too).
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

from mobot_cli.errors import Location, ResourceError, UsageError
from mobot_cli.sweep.barn_score import GOAL, GOAL_RADIUS, START, TIMEOUT, WORLDS, optimal_time, reference_length

ROBOT = "jackal"  # the robot's name in every BARN run (BARN's model is 'jackal')
SETTLE = 0.5  # s before the goal starts
MARGIN = 10.0  # s of simulation beyond 100 s, for a robot that is slow to start moving
CLONE_SUBDIR = Path("jackal_helper/worlds/BARN")


@dataclass(frozen=True)
class BarnWorld:
    """One BARN world: its number, file and reference path length (m)."""

    number: int
    file: Path
    path_length: float

    @property
    def optimal_time(self) -> float:
        return optimal_time(self.path_length)


def find_folder(folder: Path) -> Path:
    """The folder holding world_N.world: ``folder`` itself, or a clone's jackal_helper/worlds/BARN."""
    if not folder.exists():
        raise UsageError("BARN folder not found", location=Location(file=folder),
                         hint="Give the folder holding world_0.world ... world_299.world and path_files/ "
                              "(jackal_helper/worlds/BARN in a clone of github.com/Daffan/the-barn-challenge).")
    if not folder.is_dir():
        raise UsageError("not a folder", location=Location(file=folder),
                         hint="Give the folder holding the BARN worlds, not a file in it.")
    for candidate in (folder, folder / CLONE_SUBDIR):
        if (candidate / "world_0.world").is_file() or any(candidate.glob("world_*.world")):
            return candidate
    raise UsageError("no BARN worlds (world_N.world) in this folder", location=Location(file=folder),
                     hint="Give the folder holding world_0.world ... world_299.world (jackal_helper/worlds/BARN "
                          "in a clone of github.com/Daffan/the-barn-challenge).")


def parse_numbers(text: str) -> list[int]:
    """'0-299', '0,6,12' or '0-9,100' as world numbers, in the order given, each once."""
    where = Location(file=f"--worlds {text}")
    numbers: list[int] = []
    for item in (part.strip() for part in text.split(",")):
        low, dash, high = item.partition("-")
        try:
            first, last = (int(low), int(high)) if dash else (int(item), int(item))
        except ValueError:
            raise UsageError(f"'{item}' is not a world number or a range", location=where,
                             hint="e.g. --worlds 0-299, --worlds 0,6,12 or --worlds 0-9,100") from None
        if first > last:
            raise UsageError(f"range {item} runs backwards", location=where, hint=f"Write {last}-{first}.")
        for n in (first, last):
            if not 0 <= n < WORLDS:
                raise UsageError(f"world {n} is out of range: BARN's static worlds are 0..{WORLDS - 1}",
                                 location=where, hint="e.g. --worlds 0-299")
        numbers += [n for n in range(first, last + 1) if n not in numbers]
    return numbers


def load_worlds(folder: Path, numbers: list[int]) -> list[BarnWorld]:
    """Each world's file and reference path length; a located error for a missing or bad file."""
    worlds = []
    for n in numbers:
        world = folder / f"world_{n}.world"
        if not world.is_file():
            raise ResourceError(f"BARN world {n} is missing: no such file", location=Location(file=world),
                                hint="Download all 300 worlds, or choose others with --worlds.")
        worlds.append(BarnWorld(n, world.resolve(), reference_length(read_path(_path_file(folder, n)))))
    return worlds


def _path_file(folder: Path, n: int) -> Path:
    candidates = [folder / "path_files" / f"path_{n}.npy", folder / f"path_{n}.npy",
                  folder.parent / "path_files" / f"path_{n}.npy"]
    for candidate in candidates:
        if candidate.is_file():
            return candidate
    raise ResourceError(f"the reference path of BARN world {n} is missing: no such file",
                        location=Location(file=candidates[0]),
                        hint="BARN's score needs each world's path_files/path_N.npy beside the worlds.")


def read_path(file: Path) -> list[tuple[int, int]]:
    """A path file's grid cells: an (N, 2) array of whole numbers in NumPy's .npy format."""
    import numpy as np

    try:
        cells = np.load(file, allow_pickle=False)
    except (OSError, ValueError) as exc:
        raise ResourceError(f"cannot read BARN path file: {exc}", location=Location(file=file),
                            hint="A path file is an (N, 2) NumPy array of grid cells (.npy).") from None
    if cells.ndim != 2 or cells.shape[1] != 2 or len(cells) == 0 or cells.dtype.kind not in "iu":
        raise ResourceError(f"a BARN path file holds an (N, 2) array of whole numbers, this one a "
                            f"{cells.dtype} array of shape {cells.shape}", location=Location(file=file))
    return [(int(a), int(b)) for a, b in cells]


@dataclass(frozen=True)
class Driver:
    """How the robot is driven: its description, engine, speed limits and the goal's settings
    that newer mobots add (planner, local), passed through as given."""

    robot: str = "jackal_like"
    engine: str = "kinematic"
    max_linear: float = 0.5  # m/s, as BARN's DWA baseline (base_local_planner_params.yaml)
    max_angular: float = 1.57  # rad/s, likewise
    extra: tuple[tuple[str, str], ...] = ()  # (goal setting, value): planner, local
    lidar: bool = True  # False: the robot's lidar (topic .../scan) off, for drivers that do not read it


def scenario_text(first: BarnWorld, driver: Driver) -> str:
    """The base scenario of every BARN run (a sweep sets ``world`` per run), as YAML text."""
    goal = {"goto": {"x": GOAL[0], "y": GOAL[1], "tolerance": GOAL_RADIUS}, "timeout": TIMEOUT + MARGIN,
            "max_linear": driver.max_linear, "max_angular": driver.max_angular,
            "localization": "ground_truth", **dict(driver.extra)}
    lines = [
        "# mobot barn: BARN's start, goal and rules (github.com/Daffan/the-barn-challenge run.py)",
        "version: 1",
        "name: barn",
        f"world: {json.dumps(str(first.file))}",
        f"duration: {SETTLE + TIMEOUT + MARGIN:g}",
        "seed: 0",
        f"settle: {SETTLE:g}",
        f"physics: {{engine: {driver.engine}}}",
        "robots:",
        f"  - name: {ROBOT}",
        f"    description: {json.dumps(driver.robot)}",
        f"    pose: {{x: {START[0]:g}, y: {START[1]:g}, yaw: {START[2]:g}}}",
        *([] if driver.lidar else ["    sensors: {scan: false}"]),
        "    commands:",
        f"      - {json.dumps({'at': SETTLE, **goal})}",
    ]
    return "\n".join(lines) + "\n"
