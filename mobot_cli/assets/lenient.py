"""XML as Gazebo's parsers read it: what sdformat (tinyxml2) and Gazebo accept, mobot accepts.

Every robot description, xacro file and SDF world or model goes through ``gazebo_xml`` before
an XML parser sees it. Strict XML refuses two things those parsers read without a word, and
``gazebo_xml`` rewrites them without moving any line (errors keep their line numbers):

- ``--`` inside a comment (and a comment ending in ``--->``): the hyphens are spaced apart;
- a namespace prefix used without its ``xmlns:`` declaration (``gz:expressed_in``,
  ``ignition:``, ``xacro:``): the declaration is added to the root element, with the URI the
  files that declare it use, so a declared and an undeclared ``gz:`` read the same;
- an element or attribute name with ``::`` in it (gz-sim's own example worlds give a plugin
  ``<gz::system_priority>``): each ``::`` becomes ``__``, a name no reader of mobot's asks for.

``sdf_integer`` reads a whole number as sdformat does (its leading digits: 666.519 is 666).
"""

from __future__ import annotations

import re

# The URIs that files declaring these prefixes use (Gazebo's and xacro's documentation).
KNOWN_NAMESPACES = {
    "gz": "http://gazebosim.org/schema",
    "ignition": "http://ignitionrobotics.org/schema",
    "xacro": "http://www.ros.org/wiki/xacro",
}
GZ_NAMESPACE = KNOWN_NAMESPACES["gz"]
UNDECLARED = "urn:mobot:undeclared:"  # + prefix, for any other prefix used without a declaration

# A CDATA section or a comment, in the order they come (a "<!--" inside CDATA is no comment).
_HIDDEN = re.compile(r"<!\[CDATA\[.*?\]\]>|<!--(.*?)-->", re.DOTALL)
_PREFIXED_TAG = re.compile(r"</?([A-Za-z_][\w.-]*):[A-Za-z_][\w.-]*")
_PREFIXED_ATTRIBUTE = re.compile(r"\s([A-Za-z_][\w.-]*):[A-Za-z_][\w.-]*\s*=\s*[\"']")
_DECLARED = re.compile(r"\bxmlns:([A-Za-z_][\w.-]*)\s*=")
_ROOT_TAG = re.compile(r"<([A-Za-z_][\w.:-]*)")
_LEADING_INTEGER = re.compile(r"\s*([+-]?\d+)")
# A tag's or an attribute's name with "::" in it (tinyxml2 takes any name characters).
_DOUBLE_COLON_NAME = re.compile(r"(</?|\s)([A-Za-z_][\w.:-]*::[\w.:-]*)(?=[\s/>=])")


def gazebo_xml(text: str) -> str:
    """``text`` with what Gazebo's parsers accept and strict XML refuses made strict, lines kept."""
    if "<!--" in text:
        text = _HIDDEN.sub(_comment, text)
    if "::" in text:
        text = _double_colons(text)
    if ":" in text:
        text = _declare_prefixes(text)
    return text


def gazebo_xml_bytes(data: bytes) -> bytes:
    """``gazebo_xml`` for the bytes of a file (UTF-8; the bytes unchanged when nothing needs it)."""
    if b"<!--" not in data and b":" not in data:
        return data
    text = data.decode("utf-8", errors="surrogateescape")
    fixed = gazebo_xml(text)
    return data if fixed == text else fixed.encode("utf-8", errors="surrogateescape")


def _comment(match: re.Match) -> str:
    body = match.group(1)
    if body is None or "-" not in body:  # CDATA, or a comment strict XML reads as it is
        return match.group(0)
    body = re.sub(r"-(?=-)", "- ", body)
    return f"<!--{body}{' ' if body.endswith('-') else ''}-->"


def _double_colons(text: str) -> str:
    """Names with "::" outside comments, CDATA and attribute values, "::" made "__" (same length)."""
    hidden = [m.span() for m in _HIDDEN.finditer(text)]
    out, last = [], 0
    for match in _DOUBLE_COLON_NAME.finditer(text):
        start = match.start(2)
        if any(a <= start < b for a, b in hidden) or _in_value(text, start):
            continue
        out += [text[last:start], match.group(2).replace("::", "__")]
        last = match.end(2)
    return "".join(out) + text[last:] if out else text


def _in_value(text: str, at: int) -> bool:
    """Whether ``at`` is inside a quoted attribute value of the tag it is in (or in text, not a tag)."""
    tag = text.rfind("<", 0, at)
    if tag < 0 or text.rfind(">", 0, at) > tag:
        return True  # element text, not a name
    quotes = text[tag:at]
    return quotes.count('"') % 2 == 1 or quotes.count("'") % 2 == 1


def _declare_prefixes(text: str) -> str:
    visible = _HIDDEN.sub(lambda m: " " * len(m.group(0)), text)  # comments and CDATA declare nothing
    used = {m.group(1) for m in _PREFIXED_TAG.finditer(visible)}
    used |= {m.group(1) for m in _PREFIXED_ATTRIBUTE.finditer(visible)}
    missing = sorted(used - set(_DECLARED.findall(visible)) - {"xml", "xmlns"})
    if not missing:
        return text
    root = _first_element(visible)
    if root is None:
        return text
    declarations = "".join(f' xmlns:{prefix}="{KNOWN_NAMESPACES.get(prefix, UNDECLARED + prefix)}"'
                           for prefix in missing)
    return text[:root] + declarations + text[root:]


def _first_element(visible: str) -> int | None:
    """Where the root element's name ends (declarations go right after it)."""
    for match in _ROOT_TAG.finditer(visible):
        if visible[match.start() + 1] not in "?!":
            return match.end()
    return None


def sdf_integer(text: str) -> tuple[int, bool] | None:
    """A whole number as sdformat reads one (its leading digits), and whether anything followed
    them (666.519 gives (666, True)); None when the text does not start with a number."""
    match = _LEADING_INTEGER.match(text)
    if match is None:
        return None
    return int(match.group(1)), bool(text[match.end():].strip())
