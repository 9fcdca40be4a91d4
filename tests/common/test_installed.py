"""Installed versions read beside the module agree with importlib.metadata's."""

from __future__ import annotations

import importlib
import sys
from importlib import metadata

import pytest

from mobot_cli.common import installed


@pytest.mark.parametrize("name", ["pybullet", "numpy", "pydantic", "yourdfpy", "typer", "hypothesis"])
def test_the_version_beside_the_module_is_importlib_metadatas(name):
    importlib.import_module(name)
    installed.version.cache_clear()
    module = sys.modules[name]  # the fast path: the dist-info beside the module
    folder = module.__file__.rsplit("/", 2 if module.__file__.endswith("__init__.py") else 1)[0]
    assert installed._beside(folder, name) == metadata.version(name)
    assert installed.version(name) == metadata.version(name)


def test_a_module_without_its_dist_info_beside_it_asks_importlib_metadata(tmp_path, monkeypatch):
    installed.version.cache_clear()
    monkeypatch.syspath_prepend(tmp_path)
    (tmp_path / "mobot_nowhere.py").write_text("")
    importlib.import_module("mobot_nowhere")
    assert installed._beside(str(tmp_path), "mobot_nowhere") is None
    assert installed.version("mobot_nowhere") is None
    installed.version.cache_clear()


def test_two_dist_infos_of_one_name_are_left_to_importlib_metadata(tmp_path):
    for v in ("1.0", "2.0"):
        info = tmp_path / f"twice-{v}.dist-info"
        info.mkdir()
        (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: twice\nVersion: {v}\n\nbody\n")
    assert installed._beside(str(tmp_path), "twice") is None
    (tmp_path / "twice-1.0.dist-info" / "METADATA").unlink()
    (tmp_path / "twice-1.0.dist-info").rmdir()
    assert installed._beside(str(tmp_path), "twice") == "2.0"
