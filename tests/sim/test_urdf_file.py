"""What mobot writes for PyBullet is read whole: no line PyBullet's 8,191-byte reader would cut."""

from __future__ import annotations

import xml.etree.ElementTree as ET

import pytest

from mobot_cli.sim.bullet.urdf_file import LINE_LIMIT, UnwritableURDF, fits, pybullet_text, urdf_path
from mobot_cli.sim.pb import p

INERTIAL = ('<inertial><origin xyz="0 0 0" rpy="0 0 0"/><mass value="0.01"/>'
            '<inertia ixx="1e-05" ixy="0" ixz="0" iyy="1e-05" iyz="0" izz="1e-05"/></inertial>')


def one_line_robot(links: int, name: str = "big") -> str:
    """A one-line URDF as ElementTree writes it (as mobot's SDF converter did): ~360 bytes a link."""
    body = ['<link name="base_link">' + INERTIAL + '<collision><geometry><box size="0.4 0.3 0.1"/>'
            '</geometry></collision></link>']
    for i in range(links):
        body.append(f'<link name="part_{i:03d}">{INERTIAL}<visual><geometry><box size="0.01 0.01 0.01"/>'
                    f'</geometry></visual></link><joint name="fix_{i:03d}" type="fixed"><parent link="base_link"/>'
                    f'<child link="part_{i:03d}"/><origin xyz="{0.001 * i:.3f} 0 0.1"/></joint>')
    return '<?xml version="1.0"?>\n<robot name="' + name + '">' + "".join(body) + "</robot>"


def cut_in_a_tag(links: int) -> str:
    """``one_line_robot`` with its name padded so that PyBullet's first cut (8,191 bytes into the
    line) falls right after '<iner', as the issue saw it."""
    line = one_line_robot(links).split("\n")[1]
    start = line.rfind("<inertial", 0, 8186)
    return one_line_robot(links, name="big" + "_" * (8186 - start))


def load(text: str) -> int:
    """Load a URDF file holding ``text`` into a fresh PyBullet client: its number of joints, -1 if refused."""
    cid = p.connect(p.DIRECT)
    try:
        body = p.loadURDF(str(urdf_path(text)), physicsClientId=cid)
        return p.getNumJoints(body, physicsClientId=cid)
    except p.error:
        return -1
    finally:
        p.disconnect(cid)


def same_elements(a: str, b: str) -> bool:
    """Both texts hold the same elements, attributes and non-blank text."""
    def rows(text):
        return [(e.tag, sorted(e.attrib.items()), " ".join((e.text or "").split()))
                for e in ET.fromstring(text).iter()]
    return rows(a) == rows(b)


def test_a_one_line_urdf_of_20_kb_is_cut_by_pybullet_and_the_written_text_is_not():
    """The bug itself, on real PyBullet: 60 links on one 23 kB line fail to load; written by
    pybullet_text the same robot loads with all its joints."""
    text = cut_in_a_tag(60)
    assert len(text) > 20_000 and not fits(text) and text.split("\n")[1][8186:8191] == "<iner"
    assert load(text) == -1  # PyBullet cut a tag (the "XMLElement name=iner")
    written = pybullet_text(text)
    assert fits(written) and same_elements(text, written)
    assert max(len(line.encode()) for line in written.split("\n")) < LINE_LIMIT
    assert load(written) == 60


def test_text_that_already_fits_is_returned_as_it_is():
    text = one_line_robot(3)
    assert fits(text) and pybullet_text(text) is text


def test_long_text_is_wrapped_and_a_carriage_return_never_reaches_pybullet():
    """PyBullet ends a line at a CR and drops the rest; <gazebo> text may be long (a plugin's list)."""
    words = " ".join(f"joint_{i}" for i in range(2000))
    text = one_line_robot(1).replace("</robot>", f"<gazebo><plugin><joints>{words}</joints>"
                                                  "<note>a&#13;b</note></plugin></gazebo></robot>")
    written = pybullet_text(text)
    assert fits(written) and "\r" not in written
    assert ET.fromstring(written).findtext("gazebo/plugin/joints").split() == words.split()
    assert load(written) == 1


def test_a_long_value_pybullet_never_reads_leaves_its_block_out_of_pybullets_copy():
    blob = "x" * (LINE_LIMIT * 3)
    text = one_line_robot(1).replace("</robot>", f'<gazebo><plugin name="{blob}"/></gazebo>'
                                                  '<gazebo reference="base_link"><mu1>0.5</mu1></gazebo></robot>')
    written = pybullet_text(text)
    assert fits(written) and blob not in written
    assert [g.get("reference") for g in ET.fromstring(written).findall("gazebo")] == ["base_link"]
    assert load(written) == 1


def test_spaces_padding_numbers_are_tidied_and_a_long_name_pybullet_reads_is_refused():
    padded = "0.1" + " " * (LINE_LIMIT * 2) + "0.2 0.3"
    text = one_line_robot(1).replace('<box size="0.4 0.3 0.1"/>', f'<box size="{padded}"/>')
    written = pybullet_text(text)
    assert fits(written) and ET.fromstring(written).find("link/collision/geometry/box").get("size") == "0.1 0.2 0.3"
    name = "n" * (LINE_LIMIT * 3)
    message = (r"attribute name= of <link> \(12288 bytes\) in <link name=\"n{60}\"> is longer than mobot can "
               r"write in a line PyBullet reads whole \(3840 bytes\)")
    with pytest.raises(UnwritableURDF, match=message):
        pybullet_text(one_line_robot(1).replace('"part_000"', f'"{name}"'))


def test_a_start_tag_too_long_for_a_line_is_broken_between_its_attributes():
    attrs = " ".join(f'a{i}="{"v" * 1000}"' for i in range(12))
    text = one_line_robot(1).replace("</robot>", f'<material name="m" {attrs}/></robot>')
    written = pybullet_text(text)
    assert fits(written) and same_elements(text, written)
    assert load(written) == 1


def test_a_long_word_after_short_ones_gets_a_line_of_its_own():
    text = one_line_robot(1).replace("</robot>", "<gazebo><plugin><blob>" + "a " * 400 + "b" * 3500 + " c"
                                                  "</blob></plugin></gazebo></robot>")
    written = pybullet_text(text)
    assert fits(written)
    assert ET.fromstring(written).findtext("gazebo/plugin/blob").split() == ["a"] * 400 + ["b" * 3500, "c"]
