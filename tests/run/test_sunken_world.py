"""A world sunk far below z = 0 (PX4's kth_marinarium: a tank floor at z = -96.8 m) is not a fall."""

from __future__ import annotations

import json
from dataclasses import astuple

import pytest

from mobot_cli.cli import invoke

PIT = ('<?xml version="1.0"?><sdf version="1.9"><world name="pit"><model name="tank"><static>true</static>'
       "<pose>0 0 -60 0 0 0</pose><link name='l'>"
       "<collision name='floor'><pose>0 0 -0.05 0 0 0</pose><geometry><box><size>6 4 0.1</size></box>"
       "</geometry></collision>"
       "<collision name='wall'><pose>3 0 1 0 0 0</pose><geometry><box><size>0.1 4 2</size></box>"
       "</geometry></collision></link></model></world></sdf>")


@pytest.mark.parametrize("engine", ["bullet", "kinematic"])
def test_a_robot_on_a_floor_far_below_zero_drives_there(tmp_path, engine):
    (tmp_path / "pit.sdf").write_text(PIT)
    scenario = tmp_path / "s.yaml"
    scenario.write_text("version: 1\nduration: 4\nworld: pit.sdf\nrobots:\n"
                        "  - name: diver\n    pose: {x: -2, y: 0}\n"
                        "    commands: [{at: 0.5, linear: 0.3, for: 10}]\n")
    code, out, err = astuple(invoke(["run", scenario, "--set", f"physics.engine={engine}",
                                     "--out", tmp_path / "r", "--quiet"]))
    assert code == 0, err
    summary = json.loads((tmp_path / "r" / "summary.json").read_text())
    pose = summary["robots"]["diver"]["final_pose"]
    assert summary["status"] == "ok" and summary["steps"] == 4 * 240
    assert pose["z"] == pytest.approx(-60.0, abs=0.1)  # on the tank's floor, its top at z = -60
    assert pose["x"] == pytest.approx(-2 + 0.3 * 3.5, abs=0.2)


def test_falling_off_a_sunken_floor_is_still_a_fall(tmp_path):
    (tmp_path / "pit.sdf").write_text(PIT)
    scenario = tmp_path / "s.yaml"
    scenario.write_text("version: 1\nduration: 12\nworld: pit.sdf\n"
                        "faults: {max_tilt: 180, flying_time: 10}\nrobots:\n"  # only the fall may stop it
                        "  - name: diver\n    pose: {x: -2.5, y: 0, yaw: 3.141592653589793}\n"
                        "    commands: [{at: 0.5, linear: 0.5, for: 20}]\n")
    code, out, err = astuple(invoke(["run", scenario, "--out", tmp_path / "r", "--quiet"]))
    assert code == 3, err
    assert "robot 'diver' fell out of the world (z = -70." in err
