"""Turn an expanded URDF into the text PyBullet should load.

* Mesh filenames become absolute paths. A mesh that cannot be found or read is an error,
  visual meshes included: DESIGN.md makes every missing resource an error, and a missing
  visual mesh nearly always means a wrong or incomplete package that the user should know
  about before trusting the run. With skip_missing (--skip-missing, as for worlds) the visual
  or collision that names it is left out instead, with one warning for all of them.
* COLLADA collision meshes reach PyBullet as OBJ files, converted as a world's are
  (assets/world/meshes.py: node transforms and <unit> applied, cached by content): PyBullet's
  own COLLADA reader cannot read some that Gazebo reads ("cannot extract mesh"), and then
  leaves the link without any collision shape, silently; RoverRobotics' wheels fell through
  the floor. Visual meshes stay as they are.
* Links without <inertial>, or with (near) zero mass or inertia, get 1 g and 1e-6 kg*m^2:
  PyBullet would silently give them 1 kg, which doubles a turtlebot's mass. Each one is
  reported as a notice.
* Gazebo friction (<gazebo reference="LINK"><mu1>/<mu2>, or the SDF form
  <gazebo reference="LINK"><collision><surface><friction><ode><mu>/<mu2>/<fdir1>) becomes
  PyBullet's <contact><lateral_friction>: the smaller of mu1 and mu2, because PyBullet's friction
  is isotropic and a robot should never get more grip than Gazebo gives it. Rollers are the
  exception: an <fdir1> with one mu at most ROLLER_RATIO of the other is a mecanum wheel's
  rollers (grip along fdir1 only), which min() would turn into a wheel without grip that never
  moves; it gets the larger mu, and drive detection reads it as a holonomic wheel
  (roller_links). Links without mu are left alone: the simulation layer (sim/bullet/world.py)
  gives them Gazebo's default, or caster friction, and treats a <lateral_friction> in the
  text as the author's choice.
"""

from __future__ import annotations

import math
import os
import xml.etree.ElementTree as ET
from pathlib import Path

from mobot_cli.assets.description.frames import LinkTree, floats, origin_frame
from mobot_cli.assets.resources import ResourceResolver
from mobot_cli.common.meshfile import collada_unit_of
from mobot_cli.common.transforms import Frame
from mobot_cli.errors import DescriptionError, Location, MobotError, Notice

TINY_MASS = 0.001  # kg, given to links without a usable <inertial>
TINY_INERTIA = 1e-6  # kg*m^2
MIN_MASS = 1e-6
MIN_INERTIA = 1e-9
# More links than this with the same problem get one notice listing them, not one each.
GROUP_NOTICES = 3
SKIP_HINT = "Or pass --skip-missing (or set skip_missing: true) to leave it out with a warning."


def resolve_meshes(robot: ET.Element, resolver: ResourceResolver, source: Path,
                   skip_missing: bool = False, notices: list[Notice] | None = None) -> dict[str, str | None]:
    """Rewrite every <mesh filename> to an absolute path; return each URI's path (None for one
    left out), in the order they come.

    With ``skip_missing`` a visual or collision whose mesh cannot be found is removed and
    named in one notice (added to ``notices``); otherwise it is a DescriptionError.
    """
    found: dict[str, str | None] = {}
    left_out: list[tuple[str, DescriptionError]] = []
    for link in robot.findall("link"):
        for kind in ("collision", "visual"):
            for element in link.findall(kind):
                mesh = element.find("geometry/mesh")
                if mesh is None:
                    continue
                uri = mesh.get("filename", "")
                try:
                    path = _mesh_path(uri, resolver, source, link.get("name", ""), kind)
                except DescriptionError as exc:
                    if not skip_missing or not uri:
                        raise
                    link.remove(element)
                    left_out.append((f"{kind} '{uri}' of link '{link.get('name', '')}'", exc))
                    found[uri] = None
                    continue
                mesh.set("filename", path)
                found[uri] = path
    if left_out and notices is not None:
        named = "; ".join(what for what, _ in left_out)
        notices.append(Notice(
            f"{len(left_out)} mesh{'es' if len(left_out) > 1 else ''} cannot be found and "
            f"{'are' if len(left_out) > 1 else 'is'} left out (skip_missing): {named}. "
            f"The first: {left_out[0][1].message}", Location(file=source)))
    return found


def readable_collisions(robot: ET.Element, source: Path) -> list[str]:
    """Point every COLLADA collision <mesh> at an OBJ of the same triangles (cached by the
    file's content); the OBJ files. A DescriptionError names a file nothing can read."""
    from mobot_cli.assets.world.meshes import collision_mesh

    converted: dict[str, str] = {}  # a robot's four wheels share one file
    for link in robot.findall("link"):
        for mesh in link.findall("collision/geometry/mesh"):
            filename = mesh.get("filename", "")
            if not filename.lower().endswith(".dae"):
                continue
            if filename not in converted:
                where = Location(file=source, key=f"link.{link.get('name', '')}")
                try:
                    converted[filename] = collision_mesh(Path(filename), where).path
                except MobotError as exc:
                    raise DescriptionError(f"collision mesh of link '{link.get('name', '')}': {exc.message}",
                                           location=where, hint=exc.hint) from None
            mesh.set("filename", converted[filename])
    return list(converted.values())


def mesh_path_or_none(uri: str, resolver: ResourceResolver, source: Path) -> str | None:
    """The file resolve_meshes would make of ``uri`` now; None where it would find none."""
    try:
        return _mesh_path(uri, resolver, source, "", "")
    except DescriptionError:
        return None


def _mesh_path(uri: str, resolver: ResourceResolver, source: Path, link: str, kind: str) -> str:
    where = f"the {kind} mesh '{uri}' of link '{link}'"
    if not uri:
        raise DescriptionError(f"a {kind} <mesh> of link '{link}' has no filename",
                               location=Location(file=source, key=f"link.{link}"),
                               hint="Add filename=\"package://PKG/meshes/...\".")
    try:
        path = resolver.resolve_uri(uri, source)
    except MobotError as exc:
        detail = exc.message.removeprefix(f"'{uri}' ")
        raise DescriptionError(f"{where} cannot be found: {detail}",
                               location=Location(file=source, key=f"link.{link}"),
                               hint=f"{exc.hint} {SKIP_HINT}".strip()) from None
    if not path.is_file() or not os.access(path, os.R_OK):
        raise DescriptionError(f"{where} resolves to {path}, which is not a readable file",
                               location=Location(file=source, key=f"link.{link}"),
                               hint=f"Check the file's permissions. {SKIP_HINT}")
    return str(path)


def fix_inertials(robot: ET.Element, source: Path) -> list[Notice]:
    """Give links without a usable <inertial> a tiny one; a notice per link, or one for many."""
    light: list[tuple[str, str]] = []  # (link, problem): given TINY_MASS
    stiff: list[tuple[str, str]] = []  # (link, diagonal): inertia raised
    bent: list[tuple[str, str]] = []  # (link, what was wrong and what it became): no body has such inertia
    for link in robot.findall("link"):
        name = link.get("name", "")
        inertial = link.find("inertial")
        mass, diagonal = inertial_values(inertial)
        if inertial is None:
            light.append((name, "has no <inertial>"))
        elif mass < MIN_MASS:
            light.append((name, f"has a near-zero mass ({mass:g} kg)"))
        elif min(diagonal) < MIN_INERTIA:
            # The mass is real; only the singular inertia would make the solver unstable.
            _raise_diagonal(inertial)
            stiff.append((name, " ".join(f"{d:g}" for d in diagonal)))
            continue
        else:
            fixed = _impossible_inertia(inertial)
            if fixed:
                bent.append((name, fixed))
            continue
        if inertial is not None:
            link.remove(inertial)
        link.insert(0, _tiny_inertial(inertial))
    tiny = (f"{TINY_MASS * 1000:g} g and {TINY_INERTIA:g} kg*m^2 (Gazebo lumps such links into "
            "their parent through fixed joints, or drops them)")
    raised = f"{TINY_INERTIA:g} kg*m^2 so PyBullet stays stable"
    return [*_grouped(light, source, lambda name, problem: f"link '{name}' {problem}: PyBullet "
                      f"would give it 1 kg, so mobot gives it {tiny}",
                      lambda names: f"{names} have no usable <inertial> (none, or a near-zero "
                      f"mass): PyBullet would give each 1 kg, so mobot gives each {tiny}"),
            *_grouped(stiff, source, lambda name, shown: f"link '{name}' has a near-zero inertia "
                      f"(diagonal {shown}): mobot raises it to {raised}",
                      lambda names: f"{names} have a near-zero inertia: mobot raises it to "
                      f"{raised}"),
            *_grouped(bent, source, lambda name, shown: f"link '{name}' has an inertia no rigid body can "
                      f"have ({shown}; each principal moment must be at most the sum of the other two): "
                      "PyBullet would tilt and spin it, so mobot uses the moments shown",
                      lambda names: f"{names} have inertias no rigid body can have (a principal moment "
                      "larger than the sum of the other two): PyBullet would tilt and spin them, so mobot "
                      "raises the smaller moments until they add up")]


def _grouped(links: list[tuple[str, str]], source: Path, one, many) -> list[Notice]:
    """A notice per link, or one listing them all when there are more than GROUP_NOTICES."""
    if len(links) <= GROUP_NOTICES:
        return [Notice(one(name, detail), Location(file=source, key=f"link.{name}"))
                for name, detail in links]
    names = f"{len(links)} links ({', '.join(name for name, _ in links)})"
    return [Notice(many(names), Location(file=source))]


def _impossible_inertia(inertial: ET.Element) -> str:
    """Mend an inertia tensor no rigid body has (not positive definite, or a principal moment over
    the sum of the other two: osrf's create model, izz 1.53 against ixx + iyy 0.12): its products
    dropped and the smaller moments raised until each is at most the sum of the others, as a
    body of that mass could have. "" when it was possible; else what it was and became."""
    import numpy as np

    inertia = inertial.find("inertia")
    if inertia is None:
        return ""
    value = {k: floats(inertia.get(k), 1, (0.0,))[0] for k in ("ixx", "iyy", "izz", "ixy", "ixz", "iyz")}
    tensor = np.array([[value["ixx"], value["ixy"], value["ixz"]], [value["ixy"], value["iyy"], value["iyz"]],
                       [value["ixz"], value["iyz"], value["izz"]]])
    if not np.isfinite(tensor).all():
        return ""
    moments = np.linalg.eigvalsh(tensor)  # ascending
    slack = 1e-6 * float(moments[-1])
    if moments[0] > 0.0 and moments[2] <= moments[0] + moments[1] + slack:
        return ""
    diagonal = [value["ixx"], value["iyy"], value["izz"]]
    top = max(range(3), key=lambda k: diagonal[k])
    rest = [k for k in range(3) if k != top]
    short = diagonal[top] - sum(diagonal[k] for k in rest)
    for k in rest:
        diagonal[k] += max(short, 0.0) / 2.0
    for key, new in zip(("ixx", "iyy", "izz"), diagonal):
        inertia.set(key, f"{new:.9g}")
    for key in ("ixy", "ixz", "iyz"):
        inertia.set(key, "0")
    was = ", ".join(f"{k} {value[k]:g}" for k in ("ixx", "iyy", "izz"))
    products = any(abs(value[k]) > 0.0 for k in ("ixy", "ixz", "iyz"))
    principal = ", ".join(f"{m:.4g}" for m in moments)
    now = ", ".join(f"{k} {v:.6g}" for k, v in zip(("ixx", "iyy", "izz"), diagonal))
    return (f"{was}{' and products of inertia' if products else ''}, principal moments {principal}; now {now}"
            + (", products 0" if products else ""))


def _raise_diagonal(inertial: ET.Element) -> None:
    inertia = inertial.find("inertia")
    if inertia is None:
        inertia = ET.SubElement(inertial, "inertia", ixy="0", ixz="0", iyz="0")
    for key in ("ixx", "iyy", "izz"):
        if floats(inertia.get(key), 1, (0.0,))[0] < MIN_INERTIA:
            inertia.set(key, f"{TINY_INERTIA:g}")


def inertial_values(inertial: ET.Element | None) -> tuple[float, tuple[float, float, float]]:
    """(mass, (ixx, iyy, izz)) of an <inertial>, zeros where absent."""
    if inertial is None:
        return 0.0, (0.0, 0.0, 0.0)
    mass_el, inertia = inertial.find("mass"), inertial.find("inertia")
    mass = floats(mass_el.get("value") if mass_el is not None else None, 1, (0.0,))[0]
    diagonal = tuple(floats(inertia.get(k) if inertia is not None else None, 1, (0.0,))[0]
                     for k in ("ixx", "iyy", "izz"))
    return mass, diagonal  # type: ignore[return-value]


def _tiny_inertial(old: ET.Element | None) -> ET.Element:
    inertial = ET.Element("inertial")
    origin = old.find("origin") if old is not None else None
    if origin is not None:
        inertial.append(origin)
    ET.SubElement(inertial, "mass", value=f"{TINY_MASS:g}")
    ET.SubElement(inertial, "inertia", ixx=f"{TINY_INERTIA:g}", ixy="0", ixz="0",
                  iyy=f"{TINY_INERTIA:g}", iyz="0", izz=f"{TINY_INERTIA:g}")
    return inertial


# One mu at most this fraction of the other, with an <fdir1>: rollers (gz's mecanum wheels use 1 and 0).
ROLLER_RATIO = 0.1


def _mu_values(block: ET.Element) -> tuple[dict[str, float], bool]:
    """mu1/mu2 (URDF's <mu1>/<mu2>, SDF's <mu>/<mu2> under collision/surface/friction/ode) of one
    <gazebo reference> block, and whether it gives an <fdir1>."""
    found: dict[str, float] = {}
    fdir = False
    for parent in (block, block.find("collision/surface/friction/ode")):
        if parent is None:
            continue
        for tag, key in (("mu1", "mu1"), ("mu", "mu1"), ("mu2", "mu2")):
            element = parent.find(tag)
            if element is not None and key not in found:
                text = (element.text or "").strip() or element.get("value", "")
                value = floats(text, 1, (math.nan,))[0]
                if not math.isnan(value):
                    found[key] = value
        fdir = fdir or parent.find("fdir1") is not None
    return found, fdir


def is_roller(values: dict[str, float], fdir: bool) -> bool:
    """Whether mu values (two of them) and an <fdir1> (given or not) are a roller's."""
    if not fdir or len(values) < 2:
        return False
    low, high = sorted(values.values())
    return high > 0.0 and low <= ROLLER_RATIO * high


def _surfaces(robot: ET.Element) -> dict[str, tuple[dict[str, float], bool]]:
    """Link name -> its mu values and whether an <fdir1> is given, over all its <gazebo> blocks."""
    out: dict[str, tuple[dict[str, float], bool]] = {}
    for gazebo in robot.findall("gazebo"):
        reference = gazebo.get("reference")
        if not reference:
            continue
        values, fdir = _mu_values(gazebo)
        before, had = out.get(reference, ({}, False))
        out[reference] = ({**before, **values}, had or fdir)  # a later block wins, as the last one did
    return out


def gazebo_friction(robot: ET.Element) -> dict[str, float]:
    """Link name -> friction from <gazebo reference> mu1/mu2 (text or value= forms): the smaller,
    or for rollers (see roller_links) the larger."""
    return {link: max(values.values()) if is_roller(values, fdir) else min(values.values())
            for link, (values, fdir) in _surfaces(robot).items() if values}


def roller_links(robot: ET.Element) -> frozenset[str]:
    """Links whose Gazebo friction is anisotropic as mecanum rollers are: an <fdir1>, and one mu
    at most ROLLER_RATIO of the other (gz-sim's mecanum example: mu 1, mu2 0, fdir1 at 45 deg)."""
    return frozenset(link for link, (values, fdir) in _surfaces(robot).items() if is_roller(values, fdir))


def apply_friction(robot: ET.Element) -> dict[str, float]:
    """Put Gazebo's mu into links as <contact><lateral_friction>; return link -> friction."""
    from_gazebo = gazebo_friction(robot)
    for link in robot.findall("link"):
        mu = from_gazebo.get(link.get("name", ""))
        if mu is None:
            continue
        contact = link.find("contact")
        if contact is None:
            contact = ET.SubElement(link, "contact")
        lateral = contact.find("lateral_friction")
        if lateral is None:
            lateral = ET.SubElement(contact, "lateral_friction")
        lateral.set("value", f"{mu:g}")
    return from_gazebo


def collision_bounds(tree: LinkTree, source: Path,
                     notices: list[Notice]) -> tuple[float, float, float, float, float, float]:
    """(xmin, xmax, ymin, ymax, zmin, zmax) of all collision geometry in the root frame."""
    points: list[tuple[float, float, float]] = []
    for name, link in tree.links.items():
        link_frame = tree.frame(name)
        for collision in link.findall("collision"):
            frame = link_frame.compose(origin_frame(collision))
            points.extend(_geometry_points(frame, collision.find("geometry"), source, notices))
    if not points:
        return (0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    xs, ys, zs = zip(*points)
    # Rounded to a nanometre: sin/cos noise (0.09999999999999999) helps nobody reading it.
    return tuple(round(v, 9) + 0.0 for v in (min(xs), max(xs), min(ys), max(ys), min(zs), max(zs)))


def _geometry_points(frame: Frame, geometry: ET.Element | None, source: Path,
                     notices: list[Notice]) -> list[tuple[float, float, float]]:
    if geometry is None:
        return []
    box, cyl = geometry.find("box"), geometry.find("cylinder")
    sphere, mesh = geometry.find("sphere"), geometry.find("mesh")
    if box is not None:
        sx, sy, sz = floats(box.get("size"), 3, (0.0, 0.0, 0.0))
        return [frame.point((i * sx / 2, j * sy / 2, k * sz / 2))
                for i in (-1, 1) for j in (-1, 1) for k in (-1, 1)]
    if cyl is not None:
        r = floats(cyl.get("radius"), 1, (0.0,))[0]
        half = floats(cyl.get("length"), 1, (0.0,))[0] / 2
        # 32 points per rim: within 0.5 % of the true extent, good enough for a footprint.
        return [frame.point((r * math.cos(a), r * math.sin(a), h))
                for a in (2 * math.pi * i / 32 for i in range(32)) for h in (-half, half)]
    if sphere is not None:
        r = floats(sphere.get("radius"), 1, (0.0,))[0]
        cx, cy, cz = frame.point((0.0, 0.0, 0.0))
        return [(cx - r, cy - r, cz - r), (cx + r, cy + r, cz + r)]
    if mesh is not None:
        return _mesh_points(frame, mesh, source, notices)
    return []


def _mesh_points(frame: Frame, mesh: ET.Element, source: Path,
                 notices: list[Notice]) -> list[tuple[float, float, float]]:
    # Only collision meshes on a cold load get here; trimesh is imported for them alone.
    # trimesh ignores COLLADA <unit>: scaled by it here, as PyBullet loads the mesh.
    from mobot_cli.common.meshfile import load_quietly

    unit = collada_unit_of(mesh.get("filename", ""))
    scale = tuple(v * unit for v in floats(mesh.get("scale"), 3, (1.0, 1.0, 1.0)))
    try:
        loaded = load_quietly(mesh.get("filename"), force="mesh")
        (x0, y0, z0), (x1, y1, z1) = loaded.bounds
    except Exception as exc:  # noqa: BLE001 - a footprint is informative only
        notices.append(Notice(f"footprint ignores mesh {mesh.get('filename')}: {exc}",
                              Location(file=source)))
        return []
    return [frame.point((x * scale[0], y * scale[1], z * scale[2]))
            for x in (x0, x1) for y in (y0, y1) for z in (z0, z1)]
