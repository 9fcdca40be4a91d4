"""Load a robot description (bundled name, URDF, xacro or SDF model) into a RobotDescription.

A `description:` value names a file (resolve_description); xacro is expanded (description.xacro),
an SDF model converted (description.sdf), and the URDF text then checked and cached
(description.robot).
"""

from __future__ import annotations

import os
import re
from pathlib import Path
from typing import Mapping

from mobot_cli.assets.description.robot import RobotDescription, describe_expansion
from mobot_cli.assets.description.sdf import expand_sdf
from mobot_cli.assets.description.xacro import expand_file
from mobot_cli.assets.resources import ResourceResolver, bundled_dir, model_sdf
from mobot_cli.errors import Location, MobotError, Notice, ResourceError, did_you_mean

_SUFFIXES = (".urdf", ".xacro", ".sdf")
# A comment is matched first and left as it is: a mesh named in a comment is not loaded.
_MESH_ATTR = re.compile(r"<!--.*?-->|(<mesh\b[^>]*?\bfilename\s*=\s*)([\"'])(.*?)\2", re.DOTALL)


def bundled_robot_names() -> tuple[str, ...]:
    """Names usable as `description:`, one per folder of the bundled robots/."""
    root = bundled_dir("robots")
    if not root.is_dir():
        return ()
    return tuple(sorted(p.name for p in root.iterdir() if _bundled_file(p) is not None))


def _bundled_file(folder: Path) -> Path | None:
    for suffix in (".urdf.xacro", ".xacro", ".urdf"):
        candidate = folder / "urdf" / f"{folder.name}{suffix}"
        if candidate.is_file():
            return candidate
    return None


def resolve_description(description: str, base_dir: Path | None,
                        resolver: ResourceResolver) -> Path:
    """The file a `description:` value names: a bundled name, a path or a package:// URI."""
    text = str(description).strip()
    if "://" in text:
        return _model_file(resolver.resolve_uri(text, None))
    if text.endswith(_SUFFIXES) or "/" in text or os.sep in text:
        path = Path(text).expanduser()
        if not path.is_absolute():
            path = Path(base_dir or Path.cwd()) / path
        path = _model_file(path)
        if not path.is_file():
            raise ResourceError(f"robot description file {path} does not exist",
                                location=Location(file=path),
                                hint="Relative paths are relative to the scenario's folder.")
        return path.resolve()
    names = bundled_robot_names()
    if text in names:
        return _bundled_file(bundled_dir("robots") / text).resolve()  # type: ignore[union-attr]
    raise ResourceError(
        f"'{text}' is neither a bundled robot nor a .urdf/.xacro file",
        hint=(did_you_mean(text, names) + " " if names else "")
        + "Give a bundled name or a path to a .urdf, .urdf.xacro or .xacro file.")


def load_robot(description: str, args: Mapping[str, str] | None = None,
               base_dir: Path | None = None, skip_missing: bool = False) -> RobotDescription:
    """Load, check and cache a robot description for the simulation.

    With ``skip_missing``, visuals and collisions whose meshes are missing are left out with a
    warning instead of being an error.
    """
    resolver = ResourceResolver(base_dir)
    source = resolve_description(description, base_dir, resolver)
    if source.name.endswith((".sdf", ".sdf.xacro")):  # a Gazebo model: converted to URDF, then the same path
        expansion = expand_sdf(source, resolver, skip_missing, args)
    else:
        expansion = expand_file(source, args or {}, resolver)
    return describe_expansion(source, expansion, resolver, skip_missing)


def _model_file(path: Path) -> Path:
    """A Gazebo model folder stands for the SDF file its model.config names."""
    if Path(path).is_dir() and (Path(path) / "model.config").is_file():
        return model_sdf(Path(path))
    return Path(path)


def expand_to_text(description: str, args: Mapping[str, str] | None = None,
                   base_dir: Path | None = None, skip_missing: bool = False,
                   notices: list[Notice] | None = None) -> str:
    """The expanded URDF as `mobot xacro` prints it: xacro output, mesh paths made absolute.

    With ``skip_missing`` a mesh that cannot be found stays as written, named in one notice
    (added to ``notices``) instead of being an error; xacro's own warnings are added there too.
    """
    resolver = ResourceResolver(base_dir)
    source = resolve_description(description, base_dir, resolver)
    expansion = expand_file(source, args or {}, resolver)
    missing: list[str] = []

    def absolute(match: re.Match) -> str:
        if match.group(1) is None:  # a comment
            return match.group(0)
        try:
            path = resolver.resolve_uri(match.group(3), source)
        except MobotError:
            if not skip_missing:
                raise
            missing.append(match.group(3))
            return match.group(0)
        return f"{match.group(1)}{match.group(2)}{path}{match.group(2)}"

    text = _MESH_ATTR.sub(absolute, expansion.text)
    if notices is not None:
        notices.extend(expansion.notices)
        if missing:
            notices.append(Notice(
                f"{len(missing)} mesh{'es' if len(missing) > 1 else ''} cannot be found and "
                f"{'are' if len(missing) > 1 else 'is'} left as written (skip_missing; a run leaves "
                f"their visuals and collisions out): {', '.join(dict.fromkeys(missing))}",
                Location(file=source)))
    return text
