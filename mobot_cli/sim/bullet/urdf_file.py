"""URDF text to a file PyBullet can load, and the few URDF facts the simulation needs.

PyBullet reads a URDF file line by line into an 8,192-byte buffer (BulletUrdfImporter::loadURDF)
and appends a newline to every piece: a longer line is cut, and a cut inside a tag name, a
number or a name breaks the file at random ("XMLElement name=iner"). It also ends a line at a
carriage return and drops the rest of it. ``pybullet_text`` writes what PyBullet reads so that
neither can happen: one element per line, long text wrapped at its spaces, a start tag too long
for a line broken between its attributes.
"""

from __future__ import annotations

import functools
import re
import xml.etree.ElementTree as ET
from pathlib import Path

from mobot_cli.errors import DescriptionError

# Every line of what PyBullet reads stays below this many bytes: half its buffer.
LINE_LIMIT = 4096
# A value or word longer than this cannot be written with its tag and indentation in a line.
VALUE_LIMIT = LINE_LIMIT - 256
WRAP = LINE_LIMIT // 4  # long text is wrapped at its spaces into lines about this long
# Top-level elements PyBullet's URDF parser reads (UrdfParser::loadUrdf); it never looks at the
# others (<gazebo>, <transmission>, <ros2_control>, ...), which mobot reads from its own copy.
PYBULLET_READS = frozenset({"link", "joint", "material", "deformable", "reduced_deformable"})
_ATTRIBUTE = re.compile(r' [^\s="]+="[^"]*"')


class UnwritableURDF(DescriptionError):
    """A name or value PyBullet would read is longer than a line it can read."""


def urdf_path(text: str, folder: str = "urdf", suffix: str = ".urdf") -> Path:
    """A file holding ``text``, named by its content hash (and ``suffix``), written once and atomically.

    The folder is bounded (``prune``): every distinct text a live client sends makes a file.
    """
    import hashlib

    from mobot_cli.common import cache

    data = text.encode("utf-8")
    digest = hashlib.sha256(data).hexdigest()[:32]
    # A hit is checked against its name; the cache off or faulty, the file goes to a private
    # temporary folder instead (a cache only costs time). Parallel sweep workers may write it too.
    return cache.load_file(folder, f"{digest}{suffix}", digest) or \
        cache.store_file(folder, f"{digest}{suffix}", data, bounded=True)


def pybullet_file(urdf: str, known: dict[str, Path] | None = None) -> Path:
    """The file PyBullet loads for URDF text: ``pybullet_text`` of it, written by ``urdf_path``.
    ``known``: the files found so far (a fleet's robots share their text), kept up to date."""
    if known is None:
        return urdf_path(pybullet_text(urdf))
    path = known.get(urdf)
    if path is None or not path.is_file():  # a file pruned from the cache meanwhile is written again
        if len(known) >= 64:
            known.clear()
        path = known[urdf] = urdf_path(pybullet_text(urdf))
    return path


def fits(text: str) -> bool:
    """True when PyBullet reads ``text`` as written: no line of LINE_LIMIT bytes or more, no CR."""
    return "\r" not in text and max(map(len, text.encode("utf-8").split(b"\n"))) < LINE_LIMIT


def pybullet_text(text: str) -> str:
    """``text`` as PyBullet can read it (``text`` itself when it already can).

    Whitespace between elements and inside long text is all that changes, except that a
    top-level element PyBullet does not read is left out when a value in it cannot be written
    in a line. UnwritableURDF when a value PyBullet reads cannot be.
    """
    if fits(text):
        return text
    root = ET.fromstring(text)
    for child in [root, *root]:
        problem = _long_value(child, below=child is not root)
        if problem is None:
            continue
        if child is root or child.tag in PYBULLET_READS:
            raise UnwritableURDF(f"{problem} in <{child.tag} name=\"{child.get('name', '')[:60]}\"> is "
                                 f"longer than mobot can write in a line PyBullet reads whole ({VALUE_LIMIT} bytes)",
                                 hint="Shorten the value: PyBullet cuts URDF lines at 8,191 bytes.")
        root.remove(child)  # PyBullet never reads it; mobot reads the description's own text
    for element in root.iter():
        element.text, element.tail = _wrapped(element.text), _wrapped(element.tail)
    ET.indent(root, space=" ")
    lines = []
    for line in ET.tostring(root, encoding="unicode").split("\n"):
        lines.extend(_split_tag(line) if len(line.encode("utf-8")) >= LINE_LIMIT else [line])
    out = '<?xml version="1.0"?>\n' + "\n".join(lines) + "\n"
    if not fits(out):  # cannot happen after the checks above; never hand PyBullet a cut file
        raise UnwritableURDF("the URDF cannot be written in lines PyBullet reads whole",
                             hint="Report this with the description: it is a mobot bug.")
    return out


def _long_value(element: ET.Element, below: bool = True) -> str | None:
    """What in ``element`` (or below) cannot be written in one line, after numbers are tidied."""
    budget = VALUE_LIMIT
    for item in element.iter() if below else [element]:
        for key, value in item.attrib.items():
            if len(_escaped(value)) < budget:
                continue
            tidy = " ".join(value.split())
            if len(_escaped(tidy)) < budget and _numbers(tidy):
                item.set(key, tidy)  # spaces between numbers: PyBullet reads them the same
                continue
            return f"attribute {key}= of <{item.tag}> ({len(value.encode('utf-8'))} bytes)"
        for text in (item.text, item.tail):
            if text and any(len(_escaped(word)) >= budget for word in text.split()):
                return f"a word of {max(len(w) for w in text.split())} characters in the text of <{item.tag}>"
    return None


def _numbers(text: str) -> bool:
    try:
        [float(v) for v in text.split()]
    except ValueError:
        return False
    return True


def _escaped(text: str) -> bytes:
    return text.replace("&", "&amp;").replace("<", "&lt;").replace('"', "&quot;").encode("utf-8")


def _wrapped(text: str | None) -> str | None:
    """Long text broken into lines at its whitespace (PyBullet reads no URDF element's text)."""
    if text is None:
        return None
    text = text.replace("\r", "\n")
    if len(text) < WRAP:
        return text
    parts = re.split(r"(\s+)", text)  # word, space, word, ...: spaces at the odd places
    out, width = ["" if text.startswith("\n") else "\n"], 0  # long text starts on a line of its own
    for i, part in enumerate(parts):
        if i % 2 and "\n" not in part and width + len(part) + len(parts[i + 1]) >= WRAP:
            out.append("\n")
            width = 0
            continue
        out.append(part)
        width = len(part) - part.rfind("\n") - 1 if "\n" in part else width + len(part)
    return "".join(out)


def _split_tag(line: str) -> list[str]:
    """A start tag too long for a line, one attribute per line (XML allows any space there)."""
    indent = line[:len(line) - len(line.lstrip())] + "  "
    return [piece for piece in _ATTRIBUTE.sub(lambda m: "\n" + indent + m.group(0)[1:], line).split("\n")]


@functools.lru_cache(maxsize=64)
def links_with_friction(text: str) -> frozenset[str]:
    """Names of links whose URDF sets ``<contact><lateral_friction>`` (their author chose it);
    kept for the next spawn of the same text (a sweep's runs and a fleet's robots spawn the same
    robot again and again)."""
    root = ET.fromstring(text)
    return frozenset(
        link.get("name", "")
        for link in root.findall("link")
        if link.find("contact/lateral_friction") is not None
    )
