"""A live spawn request to a RobotPlan, through the same RobotResolver scenario robots use.

Loading (xacro, checks, meshes, their bounds and their convex hulls: hulls.py) runs in a
loader process (worker.py), confined to the folders the request may read (assets/sandbox.py);
naming, the reference frame and the spawn itself happen on the world's thread, against the robots alive at that moment.
"""

from __future__ import annotations

import dataclasses
import math
import re
import xml.etree.ElementTree as ET
from pathlib import Path

from mobot_cli.assets import sandbox
from mobot_cli.assets.description.describe import resolve_description
from mobot_cli.assets.resources import ResourceResolver
from mobot_cli.common.meshfile import count_faces
from mobot_cli.common.transforms import compose_poses, quat_from_rpy
from mobot_cli.errors import DescriptionError, MobotError, ResourceError, SpawnError
from mobot_cli.live.hulls import hulled
from mobot_cli.live.protocol import Refusal, Result
from mobot_cli.live.schema import Spawn, normalize_namespace
from mobot_cli.plan import RobotPlan, SpawnPose
from mobot_cli.scenario.model import RobotSpec
from mobot_cli.scenario.robots import RobotResolver
from mobot_cli.sim.bullet.urdf_file import pybullet_file, urdf_path
from mobot_cli.sim.state import RobotState
from mobot_cli.timeline.loop import NameTaken, NotInWorld

DESCRIPTION_SUFFIXES = (".urdf", ".xacro", ".sdf")  # .sdf: a Gazebo model, as a scenario's description takes
UNSUPPORTED_SUFFIXES = (".world", ".dae", ".stl", ".obj", ".mjcf", ".xml")
# Far past any run: a live robot's spawn time is only known when it is spawned.
NO_END = 2**62
# The world's thread loads a spawned robot into PyBullet and checks it for collisions; past
# these sizes that would stall the world, so the loader refuses the robot first.
MAX_LINKS = 1000
MAX_URDF_CHARS = 16 * 1024 * 1024
MAX_NOTICES, MAX_NOTICE_CHARS = 50, 2000  # xacro messages from a client come back as notices
_FACES: dict[tuple[str, int, int], int] = {}  # faces of a mesh file, by path, mtime and size
_SDF_WORLD = re.compile(r"<world\b")
_ELEMENT = re.compile(r"<([A-Za-z_][\w.:-]*)")  # an element's opening tag, its name
_MISSING_ASSET = re.compile(r"mesh '.*' of link '.*' (cannot be found|resolves to .* not a readable file)"
                            r"|^included file '.*' cannot be read"
                            r"|(model|mesh) '[^']*' not found|'[^']*' not found\. Folders searched", re.DOTALL)  # SDF's


def load_plan(request: Spawn, rate_hz: int, bounds: tuple[int, int] | None = None) -> tuple[RobotPlan, list[str]]:
    """The robot of a spawn request, loaded confined and checked (not yet named or placed); plus notices.

    ``bounds`` (mesh faces, links; `mobot serve --max-faces/--max-links`) refuse a robot that
    would cost the world's thread too much to load, with LIMIT_EXCEEDED.
    """
    base_dir = Path(request.base_dir) if request.base_dir else Path.cwd()
    description, label, files, roots = request.description, None, (), []
    if request.urdf is not None:
        path = _text_file(request.urdf)
        label = "<sdf text>" if path.suffix == ".sdf" else "<urdf text>"
        description, files = str(path), (path,)
    else:
        roots.append(_package_of(_check_format(description, base_dir)))
    roots.extend(ResourceResolver(base_dir).roots)
    spec = RobotSpec(name=request.name, description=description, args=request.args, pose=request.pose,
                     hold=request.hold)
    resolver = RobotResolver(rate_hz, 0, NO_END, base_dir=base_dir)
    try:
        with sandbox.confined(roots, files):
            (plan,) = resolver.plans(spec, ())
    except MobotError as exc:
        message = str(exc) if label is None else str(exc).replace(description, label)
        raise Refusal(classify(exc), message) from None
    _check_size(plan)
    if bounds is not None:
        check_bounds(plan, *bounds)
    plan = dataclasses.replace(plan, urdf=hulled(plan.urdf))  # built here, not on the world's thread
    pybullet_file(plan.urdf)  # written here too: the world's thread finds the file PyBullet loads
    notices = resolver.notices if label is None else [n.replace(description, label) for n in resolver.notices]
    return plan, [_short(notice, MAX_NOTICE_CHARS) for notice in notices[:MAX_NOTICES]]


def _text_file(text: str) -> Path:
    """URDF, xacro or SDF text as a file named by its content (xacro and the checks read files)."""
    if _root_tag(text) == "sdf":  # a Gazebo model: the same path as a .sdf file (description.sdf)
        if _SDF_WORLD.search(text):
            raise Refusal(Result.UNSUPPORTED_FORMAT, "the text is an SDF world, not a model: a live world "
                          "spawns robots (`mobot serve WORLD` loads a world)")
        return urdf_path(text, folder="spawned", suffix=".sdf")
    return urdf_path(text, folder="spawned")  # xacro is detected from the text


def _root_tag(text: str) -> str:
    """The name of the document's first element, past its declaration, comments and DOCTYPE:
    a forward scan (a client's text may be megabytes)."""
    i = 0
    while True:
        while i < len(text) and text[i].isspace():
            i += 1
        for opening, closing in (("<?", "?>"), ("<!--", "-->")):
            if text.startswith(opening, i):
                end = text.find(closing, i)
                i = len(text) if end < 0 else end + len(closing)
                break
        else:
            if not text.startswith("<!DOCTYPE", i):
                break
            end = text.find(">", i)
            subset = text.find("[", i, end if end >= 0 else len(text))
            if subset >= 0:  # an internal subset: up to its "]", then the ">"
                close = text.find("]", subset)
                end = -1 if close < 0 else text.find(">", close)
            i = len(text) if end < 0 else end + 1
    match = _ELEMENT.match(text, i)
    return match.group(1) if match else ""


def _check_format(description: str, base_dir: Path) -> Path:
    """The description's file; NO_RESOURCE when nothing is there, UNSUPPORTED_FORMAT when not URDF/xacro."""
    try:
        path = resolve_description(description, base_dir, ResourceResolver(base_dir))
    except ResourceError as exc:
        raise Refusal(Result.NO_RESOURCE, str(exc)) from None
    if path.name.lower().endswith(UNSUPPORTED_SUFFIXES) or not path.name.endswith(DESCRIPTION_SUFFIXES):
        raise Refusal(Result.UNSUPPORTED_FORMAT, f"{path} is not a robot description: mobot spawns "
                      ".urdf, .urdf.xacro, .xacro and SDF model (.sdf, a model folder) descriptions")
    return path


def _package_of(path: Path) -> Path:
    """The package (nearest folder with a package.xml) holding a description; else, for a
    Gazebo model folder (a model.config beside it), the folder of models holding it, whose
    siblings its model:// URIs name; else its folder."""
    for folder in path.parents:
        if (folder / "package.xml").is_file():
            return folder
    if path.name.endswith(".sdf") and (path.parent / "model.config").is_file():
        return path.parent.parent
    return path.parent


def _check_size(plan: RobotPlan) -> None:
    """The world's thread loads and collision-checks the robot: refuse one too big to do it briskly."""
    links = plan.urdf.count("<link")
    if len(plan.urdf) > MAX_URDF_CHARS or links > MAX_LINKS:
        raise Refusal(Result.RESOURCE_PARSE_ERROR, f"the expanded robot has {links} links and "
                      f"{len(plan.urdf)} characters; a live spawn takes at most {MAX_LINKS} links and "
                      f"{MAX_URDF_CHARS} characters")


def check_bounds(plan: RobotPlan, max_faces: int, max_links: int) -> None:
    """LIMIT_EXCEEDED for a robot with more links, or mesh faces, than the server allows."""
    root = ET.fromstring(plan.urdf)
    links = len(root.findall("link"))
    if links > max_links:
        raise Refusal(Result.LIMIT_EXCEEDED, f"the robot has {links} links; this world takes at most "
                      f"{max_links} a robot (`mobot serve --max-links`)")
    faces = 0
    for mesh in root.iter("mesh"):
        filename = mesh.get("filename", "")
        try:
            faces += _faces(filename)
        except OSError:
            continue  # a missing mesh is the loader's to report, not a cost
        if faces > max_faces:
            raise Refusal(Result.LIMIT_EXCEEDED, f"the robot's meshes have more than {max_faces} faces "
                          f"(reached at {Path(filename).name}); this world takes at most {max_faces} a "
                          "robot (`mobot serve --max-faces`): simplify its collision and visual meshes")


def _faces(filename: str) -> int:
    path = Path(filename.removeprefix("file://"))
    stat = path.stat()
    key = (str(path), stat.st_mtime_ns, stat.st_size)
    if key not in _FACES:  # a warm loader spawns the same robot again without re-reading its meshes
        _FACES[key] = count_faces(str(path))
    return _FACES[key]



def _short(text: str, limit: int) -> str:
    return text if len(text) <= limit else text[:limit] + f"... ({len(text)} characters)"


def classify(exc: MobotError) -> Result:
    """The simulation_interfaces result for an error raised while loading or placing a robot."""
    if isinstance(exc, NameTaken):
        return Result.NAME_NOT_UNIQUE
    if isinstance(exc, NotInWorld):
        return Result.NOT_FOUND
    if isinstance(exc, ResourceError):  # the description was found, so this is an include or mesh
        return Result.MISSING_ASSETS
    if isinstance(exc, DescriptionError):
        return Result.MISSING_ASSETS if _MISSING_ASSET.search(exc.message) else Result.RESOURCE_PARSE_ERROR
    if isinstance(exc, SpawnError):
        return Result.INVALID_POSE
    return Result.OPERATION_FAILED


def final_name(request: Spawn, taken: set[str]) -> str:
    """The requested name, or with --allow-renaming the first free of name_0, name_1, ...

    ``taken`` holds the robots and the world's static models: entity names are unique, as in Gazebo.
    """
    if request.name not in taken:
        return request.name
    if not request.allow_renaming:
        raise Refusal(Result.NAME_NOT_UNIQUE, f"'{request.name}' is already the name of a robot or model "
                      "in the world; pick another name, or allow renaming (--allow-renaming)")
    n = 0
    while f"{request.name}_{n}" in taken:
        n += 1
    return f"{request.name}_{n}"


def named(plan: RobotPlan, name: str, namespace: str | None, namespaces: dict[str, str]) -> RobotPlan:
    """The plan under its final name and namespace (default /<name>), refused if the namespace is taken."""
    ns = normalize_namespace(namespace) if namespace is not None else f"/{name}"
    if ns in namespaces:
        raise Refusal(Result.NAMESPACE_INVALID, f"namespace '{ns}' is already used by robot "
                      f"'{namespaces[ns]}': two robots in one namespace would share topics and TF frames")
    return dataclasses.replace(plan, name=name, namespace=ns, frame_prefix=ns.lstrip("/") + "/")


def in_frame(pose: SpawnPose, ref: RobotState) -> SpawnPose:
    """A pose given relative to a robot's base link (its pose now) to the world frame."""
    q_ref = quat_from_rpy(ref.true_roll, ref.true_pitch, ref.true_yaw)
    local = (pose.xyz[0], pose.xyz[1], 0.0 if pose.z_auto else pose.xyz[2])
    xyz, quat = compose_poses(((ref.true_x, ref.true_y, ref.true_z), q_ref), (local, pose.quat))
    return SpawnPose(xyz=xyz, quat=quat, z_auto=pose.z_auto)


def pose_fields(state: RobotState) -> dict[str, float]:
    """A robot's world pose as reply fields (ground truth of its base link)."""
    return {"x": _num(state.true_x), "y": _num(state.true_y), "z": _num(state.true_z),
            "roll": _num(state.true_roll), "pitch": _num(state.true_pitch), "yaw": _num(state.true_yaw)}


def _num(value: float) -> float | None:
    return round(value, 6) + 0.0 if math.isfinite(value) else None
