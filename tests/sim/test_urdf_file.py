"""sim/urdf_file.py: the facts a run's helper works out for it (the file PyBullet loads a URDF from,
the links whose friction the URDF sets) are those the run would work out itself."""

from __future__ import annotations

import pytest

from mobot_cli.sim import urdf_file

URDF = """<robot name="r">
  <link name="base"><contact><lateral_friction value="0.4"/></contact></link>
  <link name="wheel"/>
</robot>"""


@pytest.fixture(autouse=True)
def _forget():
    yield
    urdf_file._known.clear()


def test_the_facts_are_those_worked_out_here():
    found = urdf_file.facts([URDF, "<robot name='broken'"])
    assert list(found) == [URDF]  # the text that does not parse is left to the run, which reports it
    path, friction = found[URDF]
    assert path.read_text() == URDF and friction == frozenset({"base"})
    assert (path, friction) == (urdf_file.urdf_path(URDF), urdf_file.links_with_friction(URDF))


def test_known_facts_are_taken_as_they_are(tmp_path, monkeypatch):
    other = tmp_path / "elsewhere.urdf"
    other.write_text(URDF)
    urdf_file.known({URDF: (other, frozenset({"wheel"}))})
    monkeypatch.setattr("hashlib.sha256", None)  # neither hashed nor parsed again
    assert urdf_file.urdf_path(URDF) == other
    assert urdf_file.links_with_friction(URDF) == frozenset({"wheel"})


def test_a_known_file_since_removed_is_written_again(tmp_path):
    gone = tmp_path / "gone.urdf"
    urdf_file.known({URDF: (gone, frozenset())})
    path = urdf_file.urdf_path(URDF)
    assert path != gone and path.read_text() == URDF
