"""Shared fixtures: the corpus of real robots and worlds, found through MOBOT_CORPUS."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parent.parent
CORPUS = Path(os.environ.get("MOBOT_CORPUS", REPO.parent / "shared" / "corpus")).resolve()
# DDS on loopback only: the interface, no multicast, peers found by port on 127.0.0.1.
LOOPBACK_DDS = ('<CycloneDDS><Domain><General><Interfaces><NetworkInterface name="lo"/></Interfaces>'
                "<AllowMulticast>false</AllowMulticast></General><Discovery><ParticipantIndex>auto"
                '</ParticipantIndex><Peers><Peer address="127.0.0.1"/></Peers></Discovery></Domain></CycloneDDS>')


@pytest.fixture(scope="session")
def corpus() -> Path:
    """The corpus folder; tests that need it skip with the reason when it is absent."""
    if not (CORPUS / "README.md").is_file():
        pytest.skip(f"corpus not found at {CORPUS}: set MOBOT_CORPUS to the shared corpus folder")
    return CORPUS


@pytest.fixture(scope="session", autouse=True)
def _isolated_keys(tmp_path_factory):
    """CURVE keys live in the session's temp folder, never the user's (module fixtures start servers)."""
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("MOBOT_KEYS_DIR", str(tmp_path_factory.getbasetemp() / "mobot-keys"))
        patch.delenv("MOBOT_SERVER_KEY", raising=False)
        yield


@pytest.fixture(autouse=True)
def _isolated_cache(tmp_path_factory, monkeypatch):
    """Every test session gets its own cache folder so runs never see a user's cache."""
    cache = tmp_path_factory.getbasetemp() / "mobot-cache"
    monkeypatch.setenv("MOBOT_CACHE_DIR", str(cache))
    for var in ("MOBOT_RESOURCE_PATH", "ROS_PACKAGE_PATH", "AMENT_PREFIX_PATH",
                "GZ_SIM_RESOURCE_PATH", "GAZEBO_MODEL_PATH"):
        monkeypatch.delenv(var, raising=False)


@pytest.fixture(autouse=True)
def _dds_on_loopback(monkeypatch):
    """Whatever joins a ROS 2 domain in a test (and its child processes) stays on this machine,
    in a domain of this test run's own."""
    monkeypatch.setenv("ROS_DOMAIN_ID", str(100 + os.getpid() % 100))
    monkeypatch.setenv("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    monkeypatch.setenv("CYCLONEDDS_URI", LOOPBACK_DDS)
    for var in ("ROS_DISTRO", "ROS_LOCALHOST_ONLY", "ROS_STATIC_PEERS"):
        monkeypatch.delenv(var, raising=False)
