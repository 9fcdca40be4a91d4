"""A live world in the kinematic engine: spawn, cmd and odom through the real CLI."""

from __future__ import annotations

import json
import math

import pytest

from mobot_cli.cli import invoke
from tests.live.live_server import LiveProcess


@pytest.fixture(scope="module")
def live(tmp_path_factory):
    server = LiveProcess("--fast", "--set", "physics.engine=kinematic",
                         cache_dir=tmp_path_factory.getbasetemp() / "mobot-cache")
    yield server
    server.kill()


def mobot(live, *args: str):
    done = invoke([*args, "--endpoint", live.endpoint])
    assert "Traceback" not in done.stderr
    return done


def test_spawn_cmd_and_odom_in_a_kinematic_live_world(live):
    done = mobot(live, "spawn", "driver", "--file", "mobot", "-x", "3", "-y", "-3", "-Y", str(math.pi / 2), "--json")
    assert done.exit_code == 0, done.stderr
    done = mobot(live, "cmd", "driver", "--linear", "0.3", "--for", "2.0", "--wait")
    assert done.exit_code == 0, done.stderr
    reply = json.loads(mobot(live, "odom", "driver", "--json").stdout)
    # The bundled robot's wheels ramp at 2 m/s^2: what the ramp up loses the ramp down after
    # the stop gains back, so 0.3 m/s for 2 s is 0.6 m, exactly (no slip).
    assert reply["odom"]["x"] == pytest.approx(0.6, abs=1e-6)
    assert reply["truth"]["x"] == pytest.approx(3.0, abs=1e-6)
    assert reply["truth"]["y"] == pytest.approx(-3.0 + reply["odom"]["x"], abs=1e-6)
    done = mobot(live, "spawn", "blocked", "--file", "mobot", "-x", "3", "-y", str(-3.0 + reply["odom"]["x"]), "--json")
    assert done.exit_code != 0 and "INVALID_POSE" in done.stdout + done.stderr  # checked where it stands
