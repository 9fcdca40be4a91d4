"""ResourceResolver: search order, package.xml names, URI forms, and what a miss says."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from mobot_cli.assets.resources import ResourceResolver, bundled_dir
from mobot_cli.errors import ResourceError


def make_package(root: Path, folder: str, name: str, files: tuple[str, ...] = ()) -> Path:
    pkg = root / folder
    pkg.mkdir(parents=True)
    (pkg / "package.xml").write_text(f"<package format='3'>\n  <name>{name}</name>\n</package>\n")
    for rel in files:
        (pkg / rel).parent.mkdir(parents=True, exist_ok=True)
        (pkg / rel).write_text("solid x\nendsolid x\n")
    return pkg


def test_bundled_dirs_are_the_repository_folders():
    assert bundled_dir("robots") == Path(__file__).resolve().parents[2] / "robots"
    assert (bundled_dir("robots") / "mobot" / "package.xml").is_file()
    with pytest.raises(ValueError):
        bundled_dir("meshes")


def test_package_found_by_package_xml_name_not_folder_name(tmp_path, monkeypatch):
    pkg = make_package(tmp_path / "ws" / "src", "some_repo/desc", "fancy_description",
                       ("meshes/base.stl",))
    monkeypatch.setenv("MOBOT_RESOURCE_PATH", str(tmp_path / "ws"))
    resolver = ResourceResolver(None)
    assert resolver.find_package("fancy_description") == pkg
    assert resolver.resolve_uri("package://fancy_description/meshes/base.stl", None) == \
        pkg / "meshes" / "base.stl"


def test_bundled_package_is_found_without_any_environment():
    found = ResourceResolver(None).find_package("mobot_description")
    assert found == bundled_dir("robots") / "mobot"


def test_search_order_scenario_folder_first_then_env_in_documented_order(tmp_path, monkeypatch):
    first = make_package(tmp_path / "scenario", "p", "dup")
    mobot = make_package(tmp_path / "mobot_path", "p", "dup")
    ros = make_package(tmp_path / "ros", "p", "dup")
    monkeypatch.setenv("MOBOT_RESOURCE_PATH", str(tmp_path / "mobot_path"))
    monkeypatch.setenv("ROS_PACKAGE_PATH", str(tmp_path / "ros"))
    assert ResourceResolver(tmp_path / "scenario").find_package("dup") == first
    assert ResourceResolver(None).find_package("dup") == mobot
    monkeypatch.delenv("MOBOT_RESOURCE_PATH")
    assert ResourceResolver(None).find_package("dup") == ros
    roots = ResourceResolver(tmp_path / "scenario").roots
    assert roots[:3] == ((tmp_path / "scenario").resolve(), bundled_dir("robots").resolve(),
                         bundled_dir("worlds").resolve())


def test_ament_prefix_uses_share_and_path_lists_split_on_pathsep(tmp_path, monkeypatch):
    pkg = make_package(tmp_path / "install" / "share", "my_pkg", "my_pkg")
    other = tmp_path / "models"
    (other / "table").mkdir(parents=True)
    monkeypatch.setenv("AMENT_PREFIX_PATH", os.pathsep.join([str(tmp_path / "nope"),
                                                             str(tmp_path / "install")]))
    monkeypatch.setenv("GAZEBO_MODEL_PATH", str(other))
    resolver = ResourceResolver(None)
    assert resolver.find_package("my_pkg") == pkg
    assert resolver.resolve_uri("model://table", None) == other / "table"


def test_folder_named_like_the_package_counts_as_a_package(tmp_path, monkeypatch):
    (tmp_path / "plain" / "meshes").mkdir(parents=True)
    (tmp_path / "plain" / "meshes" / "a.stl").write_text("x")
    monkeypatch.setenv("GZ_SIM_RESOURCE_PATH", str(tmp_path))
    assert ResourceResolver(None).resolve_uri("package://plain/meshes/a.stl", None) == \
        tmp_path / "plain" / "meshes" / "a.stl"


def test_hidden_folders_are_not_crawled(tmp_path, monkeypatch):
    make_package(tmp_path, ".hidden/pkg", "secret_pkg")
    monkeypatch.setenv("MOBOT_RESOURCE_PATH", str(tmp_path))
    with pytest.raises(ResourceError):
        ResourceResolver(None).find_package("secret_pkg")


def test_file_uris_and_relative_paths(tmp_path):
    (tmp_path / "robot" / "meshes").mkdir(parents=True)
    mesh = tmp_path / "robot" / "meshes" / "m.stl"
    mesh.write_text("x")
    urdf = tmp_path / "robot" / "r.urdf"
    resolver = ResourceResolver(None)
    assert resolver.resolve_uri(f"file://{mesh}", urdf) == mesh
    assert resolver.resolve_uri("file://meshes/m.stl", urdf) == mesh
    assert resolver.resolve_uri("meshes/m.stl", urdf) == mesh


def test_relative_file_uri_resolves_from_the_enclosing_package(corpus):
    # The bookstore's model.sdf files use file://models/<name>/meshes/... from models/<name>/.
    world = corpus / "aws-robomaker-bookstore-world"
    sdf = next((world / "models").glob("*/model.sdf"))
    mesh_dir = sdf.parent / "meshes"
    mesh = next(p for p in mesh_dir.iterdir() if p.is_file())
    uri = f"file://models/{sdf.parent.name}/meshes/{mesh.name}"
    assert ResourceResolver(None).resolve_uri(uri, sdf) == mesh.resolve()


def test_missing_package_names_uri_referencing_file_and_every_folder(tmp_path, monkeypatch):
    monkeypatch.setenv("MOBOT_RESOURCE_PATH", os.pathsep.join([str(tmp_path / "a"),
                                                               str(tmp_path / "b")]))
    referrer = tmp_path / "robot.urdf"
    with pytest.raises(ResourceError) as err:
        ResourceResolver(tmp_path / "scn").resolve_uri("package://ghost_pkg/meshes/x.stl",
                                                       referrer)
    text = str(err.value)
    assert "package 'ghost_pkg' (for 'package://ghost_pkg/meshes/x.stl') not found" in text
    assert text.startswith(f"{referrer}: ")
    for folder in (tmp_path / "scn", tmp_path / "a", tmp_path / "b", bundled_dir("robots")):
        assert str(folder.resolve()) in text
    assert "MOBOT_RESOURCE_PATH" in err.value.hint


def test_missing_file_inside_found_package(tmp_path, monkeypatch):
    make_package(tmp_path, "p", "p")
    monkeypatch.setenv("MOBOT_RESOURCE_PATH", str(tmp_path))
    with pytest.raises(ResourceError, match=r"'package://p/meshes/gone.stl' points to .*gone.stl"):
        ResourceResolver(None).resolve_uri("package://p/meshes/gone.stl", None)


def test_network_uris_are_refused(tmp_path):
    with pytest.raises(ResourceError, match="nothing is fetched from the network"):
        ResourceResolver(None).resolve_uri("https://fuel.gazebosim.org/1.0/x/models/y", None)


def test_model_sdf_follows_model_config(corpus, tmp_path):
    from mobot_cli.assets.resources import model_sdf

    monkey = corpus / "gazebo_models"
    model = next(p for p in sorted(monkey.iterdir()) if (p / "model.config").is_file())
    assert model_sdf(model).suffix == ".sdf" and model_sdf(model).parent == model.resolve()
    (tmp_path / "m").mkdir()
    (tmp_path / "m" / "model.config").write_text(
        '<model><sdf version="1.4">old.sdf</sdf><sdf version="1.6">new.sdf</sdf></model>')
    (tmp_path / "m" / "old.sdf").write_text("<sdf/>")
    (tmp_path / "m" / "new.sdf").write_text("<sdf/>")
    assert model_sdf(tmp_path / "m") == (tmp_path / "m" / "new.sdf").resolve()
    (tmp_path / "m" / "new.sdf").unlink()
    assert model_sdf(tmp_path / "m").name == "old.sdf"
    (tmp_path / "m" / "old.sdf").unlink()
    with pytest.raises(ResourceError, match=r"has no SDF file \(model.config names: new.sdf, old"):
        model_sdf(tmp_path / "m")


def test_a_file_may_name_its_own_package_without_search_paths(tmp_path):
    pkg = make_package(tmp_path, "repo/robot_desc", "robot_description", ("meshes/a.stl",))
    urdf = pkg / "urdf" / "r.urdf"
    assert ResourceResolver(None).resolve_uri("package://robot_description/meshes/a.stl",
                                              urdf) == pkg / "meshes" / "a.stl"
    with pytest.raises(ResourceError):
        ResourceResolver(None).find_package("robot_description", tmp_path / "elsewhere.urdf")
