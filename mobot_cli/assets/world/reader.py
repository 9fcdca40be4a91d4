"""Gazebo SDF worlds and models read with lxml: includes resolved, nested models flattened.

A model comes out as its links and joints with every pose composed into the frame of the
top-level model (SDF 1.7 frame semantics: ``relative_to``, ``<frame>``, ``expressed_in``;
an empty ``frame=''`` as SDF 1.4-1.6 worlds write it means the default frame). Only what a
headless simulation needs is kept: collision geometry, inertials, joints and plugins.
Lights, GUI, scene, physics and plugins of the world are counted, not interpreted.
"""

from __future__ import annotations

from collections import Counter
from pathlib import Path

import numpy as np

from mobot_cli.assets.world import paths as sdf_paths
from mobot_cli.assets.world.frames import Scope, is_number, key_of, relative_to, truthy
from mobot_cli.assets.world.geometry import parse_shape
from mobot_cli.assets.world.model import Inertial, Joint, Link, Model, World
from mobot_cli.assets.world.pose import IDENTITY, Matrix, inverse, parse_pose, stream_numbers
from mobot_cli.errors import Location, Notice, WorldError

MAX_INCLUDE_DEPTH = 32


class SdfReader:
    """Reads one world or model file and everything it includes."""

    def __init__(self, top: Path, paths: sdf_paths.SdfPaths, skip_missing: bool = False):
        self.top = Path(top).resolve()
        self.paths = paths
        self.skip_missing = skip_missing
        self.notices: list[Notice] = []
        self.ignored: Counter = Counter()
        self.missing_visuals: list[tuple[str, Location]] = []
        self.left_out: list[sdf_paths.LeftOut] = []  # includes and meshes skipped as missing
        self._stack: list[Path] = []

    def warn(self, message: str, location: Location) -> None:
        """Record a notice (printed by the CLI)."""
        self.notices.append(Notice(message, location))

    # --- worlds -------------------------------------------------------------------------

    def world(self) -> World:
        """The world of the top file; every model placed, includes resolved."""
        root = self.paths.parse(self.top)
        world = root.find("world")
        if world is None:
            found = root.find("model")
            raise WorldError(f"{self.top.name} holds no <world>"
                             + (" but a <model>: it is a robot or model file" if found is not None else ""),
                             location=Location(file=self.top, line=root.sourceline),
                             hint="Give a .world or .sdf file with <world>; spawn a model file as a "
                                  "robot's description instead.")
        self._stack = [self.top]
        models: list[Model] = []
        names: set[str] = set()
        actors: list = []
        for child in world:
            if not isinstance(child.tag, str):
                continue
            model = None
            if child.tag == "model":
                model = self.model(child, self.top, world_level=True)
            elif child.tag == "include":
                model = self._world_include(child, actors)
            elif child.tag == "actor":
                self._actor(child, self.top, actors)
            elif child.tag != "state":
                self.ignored[child.tag] += 1
            if model is None:
                continue
            if model.name in names:  # Gazebo classic loads both; mobot's entities need unique names
                renamed = next(f"{model.name}_{n}" for n in range(1, len(names) + 2)
                               if f"{model.name}_{n}" not in names)
                self.warn(f"two models are named '{model.name}': this one is renamed '{renamed}' "
                          "(Gazebo classic loads both under one name)", model.location)
                model.name = renamed
            names.add(model.name)
            models.append(model)
        step = world.findtext("physics/max_step_size")
        result = World(name=world.get("name", self.top.stem), models=models, ignored=self.ignored,
                       max_step_size=float(step) if is_number(step) else None, actors=actors)
        result.state_poses = self._apply_state(world, models)
        self.notices[:0] = self.paths.notices  # xacro's, for a world written as xacro
        self.notices.extend(sdf_paths.left_out_notices(self.left_out, self.paths.roots, self.top))
        return result

    def _actor(self, element, file: Path, actors: list) -> None:
        """A world's <actor>: played as a mover (assets/world/actors.py), or counted as ignored."""
        from mobot_cli.assets.world.actors import read_actor

        actor, notice = read_actor(element, file, lambda pose: self.pose(pose, file))
        if actor is None:
            self.ignored["actor"] += 1
        self.warn(notice, key_of(element, file))
        if actor is not None:
            actors.append(actor)

    def _world_include(self, include, actors: list) -> Model | None:
        target = self.include_target(include, self.top)
        if target is None:
            return None
        kind, element, file = target
        if kind == "actor":
            self._actor(element, file, actors)
            return None
        if kind != "model":
            self.ignored[kind] += 1
            return None
        return self._included_model(include, element, file, world_level=True)

    def _apply_state(self, world, models: list[Model]) -> int:
        """Gazebo classic moves models to the poses in the world's first <state>; so do we."""
        state = world.find("state")
        if state is None:
            return 0
        by_name = {m.name: m for m in models}
        applied = 0
        for element in state.findall("model"):
            model = by_name.get(element.get("name", ""))
            pose = element.find("pose")
            if model is None or pose is None:
                continue
            model.pose = self.pose(pose, self.top)
            applied += 1
        return applied

    # --- models ------------------------------------------------------------------------

    def model_file(self) -> Model:
        """The first <model> of the top file (a robot's description)."""
        root = self.paths.parse(self.top)
        element = root.find("model")
        if element is None:
            what = "a <world>" if root.find("world") is not None else "no <model>"
            raise WorldError(f"{self.top.name} holds {what}, not a model",
                             location=Location(file=self.top, line=root.sourceline),
                             hint="A robot description in SDF is a file with one <model>.")
        self._stack = [self.top]
        model = self.model(element, self.top, world_level=True)
        model.pose = IDENTITY.copy()  # a spawned model goes where the scenario puts it
        self.notices[:0] = self.paths.notices
        self.notices.extend(sdf_paths.left_out_notices(self.left_out, self.paths.roots, self.top))
        return model

    def model(self, element, file: Path, world_level: bool, top: Model | None = None,
              base: Matrix = IDENTITY, prefix: str = "", static: bool = False,
              extra_plugins: tuple = ()) -> Model:
        """Parse a <model>; nested ones add their links and joints to ``top`` under ``base``."""
        name = element.get("name", "")
        if not name:
            raise WorldError("a <model> has no name", location=key_of(element, file),
                             hint="Give it name=\"...\".")
        static = static or truthy(element.findtext("static"))
        if top is None:
            top = Model(name=name, pose=self.pose(element.find("pose"), file),
                        location=key_of(element, file))
        scope = Scope(self, element, file)
        for link in element.findall("link"):
            self._link(link, file, top, base, scope, prefix, static)
        for child in element:
            if child.tag == "model":
                nested = base @ scope.frame(child.get("name", ""), child)
                self.model(child, file, False, top, nested, f"{prefix}{child.get('name')}::", static)
            elif child.tag == "include":
                target = self.include_target(child, file)
                if target is not None and target[0] == "model":
                    _, included, inc_file = target
                    inc_name = child.findtext("name", "").strip() or included.get("name", "")
                    if child.find("pose") is None:  # the included model's own pose applies
                        nested = base @ self.pose(included.find("pose"), inc_file)
                    else:
                        nested = base @ scope.frame(inc_name, child)
                    self._nested_include(child, included, inc_file, top, nested,
                                         f"{prefix}{inc_name}::", static)
                elif target is not None:
                    self.ignored[target[0]] += 1
        for joint in element.findall("joint"):
            top.joints.append(self._joint(joint, file, base, scope, prefix))
        top.plugins.extend([*element.findall("plugin"), *extra_plugins])
        return top

    def _included_model(self, include, element, file: Path, world_level: bool) -> Model:
        self._stack.append(file)
        try:
            model = self.model(element, file, world_level,
                               static=truthy(include.findtext("static")),
                               extra_plugins=tuple(include.findall("plugin")))
        finally:
            self._stack.pop()
        name = include.findtext("name", "").strip()
        model.name = name or model.name
        model.location = key_of(include, self._stack[-1])
        if include.find("pose") is not None:
            model.pose = self.pose(include.find("pose"), self._stack[-1])
        return model

    def _nested_include(self, include, element, file: Path, top: Model, base: Matrix,
                        prefix: str, static: bool) -> None:
        self._stack.append(file)
        try:
            static = static or truthy(include.findtext("static"))
            self.model(element, file, False, top, base, prefix, static,
                       extra_plugins=tuple(include.findall("plugin")))
        finally:
            self._stack.pop()

    def _link(self, link, file: Path, top: Model, base: Matrix, scope: "Scope", prefix: str,
              static: bool) -> None:
        name = link.get("name", "")
        pose = scope.frame(name, link)
        top.links.append(Link(name=prefix + name, pose=base @ pose,
                              collisions=self._shapes(link, "collision", file, scope, pose),
                              visuals=self._shapes(link, "visual", file, scope, pose),
                              inertial=self._inertial(link, file), location=key_of(link, file),
                              sensors=[(sensor, self._local(sensor, file, scope, pose))
                                       for sensor in link.findall("sensor")]))
        if not static:
            top.dynamic_links += 1

    def _shapes(self, link, tag: str, file: Path, scope: "Scope", pose: Matrix) -> list:
        """The link's <collision> or <visual> shapes, posed in the link frame."""
        shapes = []
        for element in link.findall(tag):
            shape = parse_shape(self, element, file, collision=tag == "collision")
            if shape is not None:
                shape.pose = self._local(element, file, scope, pose)
                shapes.append(shape)
        return shapes

    def _local(self, element, file: Path, scope: "Scope", link_pose: Matrix) -> Matrix:
        """A collision's or visual's pose relative to its link (relative_to honoured)."""
        pose_el = element.find("pose")
        relative = relative_to(pose_el)
        local = self.pose(pose_el, file)
        if not relative:
            return local
        return inverse(link_pose) @ scope.frame(relative, element) @ local

    def _inertial(self, link, file: Path) -> Inertial:
        element = link.find("inertial")
        if element is None:
            return Inertial()
        mass = self.number(element, "mass", file, 1.0)
        inertia = tuple(self.number(element, f"inertia/{k}", file, d) for k, d in
                        (("ixx", 1.0), ("ixy", 0.0), ("ixz", 0.0), ("iyy", 1.0), ("iyz", 0.0),
                         ("izz", 1.0)))
        return Inertial(mass=mass, pose=self.pose(element.find("pose"), file), inertia=inertia,
                        given=True)

    def _joint(self, joint, file: Path, base: Matrix, scope: "Scope", prefix: str) -> Joint:
        where = key_of(joint, file)
        parent = joint.findtext("parent", "").strip()
        child = joint.findtext("child", "").strip()
        if not parent or not child:
            raise WorldError(f"joint '{joint.get('name')}' lacks <parent> or <child>",
                             location=where, hint="Name both links the joint connects.")
        frame = base @ scope.frame(joint.get("name", ""), joint)
        axis_el = joint.find("axis")
        xyz = np.array([0.0, 0.0, 1.0])
        rotation = frame[:3, :3]
        limits = (-1e16, 1e16, -1.0, -1.0)
        dynamics = spring = (0.0, 0.0)
        if axis_el is not None:
            xyz = np.array(self.vector(axis_el, "xyz", file, (0.0, 0.0, 1.0)))
            expressed = (axis_el.find("xyz").get("expressed_in", "") if axis_el.find("xyz") is not None
                         else "")
            if truthy(axis_el.findtext("use_parent_model_frame")) or expressed == "__model__":
                rotation = base[:3, :3]
            elif expressed:
                rotation = (base @ scope.frame(expressed, axis_el))[:3, :3]
            limits = tuple(self.number(axis_el, f"limit/{k}", file, d) for k, d in
                           (("lower", -1e16), ("upper", 1e16), ("effort", -1.0), ("velocity", -1.0)))
            dynamics = (self.number(axis_el, "dynamics/damping", file, 0.0),
                        self.number(axis_el, "dynamics/friction", file, 0.0))
            spring = (self.number(axis_el, "dynamics/spring_stiffness", file, 0.0),
                      self.number(axis_el, "dynamics/spring_reference", file, 0.0))
        norm = float(np.linalg.norm(xyz))
        if norm < 1e-9:
            raise WorldError(f"joint '{joint.get('name')}' has a zero axis", location=where,
                             hint="Give <axis><xyz> a direction, e.g. 0 0 1.")
        axis = tuple(float(v) for v in rotation @ (xyz / norm))

        def scoped(link: str) -> str:
            return link if link == "world" else prefix + _canonical(scope, link)

        return Joint(name=prefix + joint.get("name", ""), type=joint.get("type", ""),
                     parent=scoped(parent), child=scoped(child), pose=frame, axis=axis,
                     limits=limits, dynamics=dynamics, location=where, spring=spring)  # type: ignore[arg-type]

    # --- includes ----------------------------------------------------------------------

    def include_target(self, include, file: Path):
        """(kind, element, file) of what an <include> names; None when skipped."""
        uri_el = include.find("uri")
        where = key_of(uri_el if uri_el is not None else include, file)
        uri = (uri_el.text or "").strip() if uri_el is not None else ""
        if not uri:
            raise WorldError("<include> has no <uri>", location=where,
                             hint="Add <uri>model://NAME</uri>.")
        target = self.paths.include_file(uri, file, where, self)
        if target is None:
            return None
        if target in self._stack:
            chain = " -> ".join(p.name if p.name != "model.sdf" else f"{p.parent.name}/{p.name}"
                                for p in [*self._stack[self._stack.index(target):], target])
            raise WorldError(f"include cycle: {chain}", location=where,
                             hint="A model must not include itself, directly or indirectly.")
        if len(self._stack) > MAX_INCLUDE_DEPTH:
            raise WorldError(f"includes nest deeper than {MAX_INCLUDE_DEPTH} levels",
                             location=where, hint="Look for an include cycle.")
        root = self.paths.parse(target)
        for kind in ("model", "light", "actor"):
            element = root.find(kind)
            if element is not None:
                return kind, element, target
        raise WorldError(f"'{uri}' ({target}) holds no <model>", location=where,
                         hint="An include must name a model folder or a model's SDF file.")

    # --- values ------------------------------------------------------------------------

    def pose(self, element, file: Path) -> Matrix:
        """A <pose> element as a transform (identity when absent); located errors."""
        if element is None:
            return IDENTITY.copy()
        quat = element.get("rotation_format", "") == "quat_xyzw"
        text = (element.text or "").strip()
        try:
            return parse_pose(text, truthy(element.get("degrees")), quat)
        except ValueError as exc:
            parts = stream_numbers(text)
            if parts is not None and len(parts) != len(text.split()):  # numbers run together
                try:
                    matrix = parse_pose(" ".join(parts), truthy(element.get("degrees")), quat)
                except ValueError:
                    pass
                else:
                    self.warn(f"pose '{text}' runs numbers together; read as Gazebo reads it: "
                              f"'{' '.join(parts)}'", key_of(element, file))
                    return matrix
            raise WorldError(f"pose '{text}' {exc}",
                             location=key_of(element, file),
                             hint="A pose is 'x y z roll pitch yaw' in metres and radians.") from None

    def number(self, parent, path: str, file: Path, default: float) -> float:
        """A number at ``path`` below ``parent``; the default when absent."""
        element = parent.find(path)
        if element is None or not (element.text or "").strip():
            return default
        if not is_number(element.text):
            raise WorldError(f"<{element.tag}> '{element.text.strip()}' is not a number",
                             location=key_of(element, file), hint="Write a plain decimal number.")
        return float(element.text)

    def vector(self, parent, path: str, file: Path, default: tuple[float, ...]) -> tuple[float, ...]:
        """Space-separated numbers at ``path`` (as many as ``default`` has)."""
        element = parent.find(path)
        if element is None or not (element.text or "").strip():
            return default
        parts = element.text.split()
        if len(parts) != len(default) or not all(is_number(p) for p in parts):
            raise WorldError(f"<{element.tag}> '{element.text.strip()}' is not {len(default)} numbers",
                             location=key_of(element, file),
                             hint=f"Write {len(default)} numbers separated by spaces.")
        return tuple(float(p) for p in parts)


def _canonical(scope, name: str) -> str:
    """A joint's parent or child as a link: a nested model stands for its canonical link (SDF 1.8:
    its ``canonical_link``, else its first link), as ``MODEL::LINK``; anything else as written."""
    element = scope.elements.get(name)
    if element is None or element.tag != "model":
        return name
    canonical = element.get("canonical_link") or next((link.get("name") for link in element.findall("link")), None)
    return f"{name}::{canonical}" if canonical else name
