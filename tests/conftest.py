"""Shared fixtures: the corpus of real robots and worlds, found through MOBOT_CORPUS."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parent.parent
CORPUS = Path(os.environ.get("MOBOT_CORPUS", REPO.parent / "shared" / "corpus")).resolve()


@pytest.fixture(scope="session")
def corpus() -> Path:
    """The corpus folder; tests that need it skip with the reason when it is absent."""
    if not (CORPUS / "README.md").is_file():
        pytest.skip(f"corpus not found at {CORPUS}: set MOBOT_CORPUS to the shared corpus folder")
    return CORPUS


@pytest.fixture(autouse=True)
def _isolated_cache(tmp_path_factory, monkeypatch):
    """Every test session gets its own cache and key folders so runs never see a user's."""
    cache = tmp_path_factory.getbasetemp() / "mobot-cache"
    monkeypatch.setenv("MOBOT_CACHE_DIR", str(cache))
    monkeypatch.setenv("MOBOT_KEYS_DIR", str(tmp_path_factory.getbasetemp() / "mobot-keys"))  # CURVE keys
    monkeypatch.delenv("MOBOT_SERVER_KEY", raising=False)
    for var in ("MOBOT_RESOURCE_PATH", "ROS_PACKAGE_PATH", "AMENT_PREFIX_PATH",
                "GZ_SIM_RESOURCE_PATH", "GAZEBO_MODEL_PATH"):
        monkeypatch.delenv(var, raising=False)
