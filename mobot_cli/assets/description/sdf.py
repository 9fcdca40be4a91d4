"""SDF robots for the robot path: a model file as a `description:`, a world's model by name.

Both become URDF text (world.to_urdf.model_to_urdf) and then take the same path as every URDF
robot: checks, inertial fixes, friction, drive detection, the robot cache.
"""

from __future__ import annotations

from pathlib import Path
from typing import Mapping

from mobot_cli.assets.description.robot import RobotDescription, describe_expansion
from mobot_cli.assets.description.xacro import Expansion
from mobot_cli.assets.resources import ResourceResolver
from mobot_cli.errors import DescriptionError, Location, Notice, WorldError


def expand_sdf(source: Path, resolver: ResourceResolver, skip_missing: bool = False,
               args: Mapping[str, str] | None = None) -> Expansion:
    """The URDF text of the first <model> in an SDF file (an .sdf.xacro expanded with ``args``
    first), with what changed as notices."""
    from mobot_cli.assets.world.paths import SdfPaths
    from mobot_cli.assets.world.reader import SdfReader
    from mobot_cli.assets.world.to_urdf import model_to_urdf

    paths = SdfPaths(source, resolver, dict(args or {}))
    reader = SdfReader(source, paths, skip_missing)
    try:
        model = reader.model_file()
        if model.static:
            raise DescriptionError(f"model '{model.name}' is <static>: it cannot move as a robot",
                                   location=model.location,
                                   hint="Put static models in a world file; a robot needs joints.")
        urdf, notices = model_to_urdf(model, source)
    except WorldError as exc:  # the same problems, reported as a robot description's
        raise DescriptionError(exc.message, location=exc.location, hint=exc.hint) from None
    if reader.missing_visuals:
        uris = sorted({uri for uri, _ in reader.missing_visuals})
        notices.append(Notice(f"visual meshes not found, left out (they do not affect the "
                              f"simulation): {', '.join(uris)}", Location(file=source)))
    return Expansion(text=urdf, files=(Path(source).resolve(), *paths.files),
                     notices=tuple([*reader.notices, *notices]))


def describe_world_robot(robot, base_dir: Path | None) -> RobotDescription:
    """The RobotDescription of a world's robot model (world.loaded.WorldRobot)."""
    expansion = Expansion(text=robot.urdf, files=(Path(robot.source),),
                          notices=tuple(Notice(n) for n in robot.notices))
    return describe_expansion(Path(robot.source), expansion, ResourceResolver(base_dir))
