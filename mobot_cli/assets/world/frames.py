"""The named frames of an SDF <model> (SDF 1.7 semantics: relative_to, attached_to, MODEL::FRAME)."""

from __future__ import annotations

from pathlib import Path

from mobot_cli.assets.world.pose import IDENTITY, Matrix
from mobot_cli.errors import Location, WorldError


def truthy(text: str | None) -> bool:
    """SDF booleans: 1/true (any case)."""
    return (text or "").strip().lower() in ("1", "true")


def key_of(element, file: Path) -> Location:
    """Location of an element: its file, line and a readable path of names."""
    parts = []
    node = element
    while node is not None and node.tag not in ("sdf", "world"):
        name = node.get("name")
        parts.append(f"{node.tag}[{name}]" if name else str(node.tag))
        node = node.getparent()
    return Location(file=file, line=element.sourceline, key=".".join(reversed(parts)) or None)



JOINT = "\0joint:"  # key of a joint whose name a link, model or frame of the same model also has


class Scope:
    """Named frames of one <model>: links, nested models, includes, joints and <frame>s."""

    def __init__(self, reader, model, file: Path):
        self.reader, self.file = reader, file
        self.elements = {}
        for child in model:
            if child.tag in ("link", "model", "frame", "joint"):
                self._add(child.get("name", ""), child)
            elif child.tag == "include":
                self.elements[child.findtext("name", "").strip() or "__include__"] = child
        self._done: dict[str, Matrix] = {}
        self._busy: set[str] = set()

    def _add(self, name: str, element) -> None:
        """Name a frame; a joint sharing a link's name (SDF < 1.7 allows it) keeps a key of its own."""
        held = self.elements.get(name)
        if held is not None and "joint" in (held.tag, element.tag) and held.tag != element.tag:
            joint, other = (element, held) if element.tag == "joint" else (held, element)
            self.elements[JOINT + name], self.elements[name] = joint, other
            return
        self.elements[name] = element

    def frame(self, name: str, element=None) -> Matrix:
        """Pose of the named frame (or of ``element``) relative to the model frame."""
        if name in ("", "__model__"):
            return IDENTITY
        if element is not None and self.elements.get(JOINT + name) is element:
            name = JOINT + name
        if name in self._done:
            return self._done[name]
        if "::" in name and name not in self.elements:
            return self._nested(name)
        element = self.elements.get(name, element)
        if element is None:
            raise WorldError(f"no frame, link or joint named '{name}' in this model",
                             hint="relative_to, attached_to and expressed_in name frames of the "
                                  "same model.")
        shown = name.removeprefix(JOINT)
        if name in self._busy:
            raise WorldError(f"frames refer to each other in a cycle through '{shown}'",
                             location=key_of(element, self.file),
                             hint="relative_to and attached_to must form a tree.")
        self._busy.add(name)
        pose_el = element.find("pose")
        default = {"joint": element.findtext("child", "").strip(),
                   "frame": element.get("attached_to", "")}.get(element.tag, "")
        relative = relative_to(pose_el) or default
        if relative not in ("", "__model__", *self.elements) and "::" not in relative:
            raise WorldError(f"{element.tag} '{shown}' is placed relative to '{relative}', which "
                             "this model does not have", location=key_of(pose_el if pose_el is not None
                                                                    else element, self.file),
                             hint="relative_to and attached_to name a link, joint, frame or nested "
                                  "model of the same model.")
        result = self.frame(relative) @ self.reader.pose(pose_el, self.file)
        self._busy.discard(name)
        self._done[name] = result
        return result


    def _nested(self, name: str) -> Matrix:
        """A frame inside a nested model or include, "nested::link"."""
        head, rest = name.split("::", 1)
        element = self.elements.get(head)
        if element is None:
            raise WorldError(f"no nested model named '{head}' (for frame '{name}')",
                             hint="Scoped names are MODEL::FRAME of a model nested in this one.")
        if element.tag == "include":
            target = self.reader.include_target(element, self.file)
            if target is None:
                return IDENTITY
            _, model, file = target
            own = self.reader.pose(model.find("pose"), file)
            outer = self.frame(head) if element.find("pose") is not None else own
            return outer @ Scope(self.reader, model, file).frame(rest)
        return self.frame(head) @ Scope(self.reader, element, self.file).frame(rest)


def relative_to(pose_el) -> str:
    """The frame a <pose> is relative to (relative_to, or SDF 1.5/1.6 frame=); "" for the default."""
    if pose_el is None:
        return ""
    return (pose_el.get("relative_to") or pose_el.get("frame") or "").strip()


def is_number(text: str | None) -> bool:
    """True when the text parses as a float."""
    try:
        float(text)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        return False
    return True
