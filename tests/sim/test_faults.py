"""The physics engine's fault checks on a cart of our own: launched, flipped, sped, and left alone."""

from __future__ import annotations

import math

import pytest

from mobot_cli.errors import SimulationFault
from mobot_cli.plan import FaultLimits, Physics, SpawnPose, WorldPlan
from mobot_cli.sim.bullet.world import World
from tests.sim.test_world import cart, run


def test_a_robot_launched_upward_is_flying_once_it_has_touched_nothing_for_a_second():
    with World(Physics(), WorldPlan()) as world:
        world.spawn(cart())
        run(world, "cart", 120)
        world.teleport("cart", SpawnPose(z_auto=True), linear=(0.0, 0.0, 6.0))  # 1.8 m up and 1.2 s aloft
        with pytest.raises(SimulationFault) as info:
            run(world, "cart", 480)
        fault = info.value
        assert (fault.robot, fault.kind, fault.exit_code) == ("cart", "flying", 3)
        assert fault.step == 120 + 240  # checked at 10 Hz: the look at exactly 1 s catches it
        assert "is flying at step 360: it has touched nothing for 1.0 s" in fault.message


def test_a_robot_dropped_from_a_height_is_falling_not_flying():
    with World(Physics(), WorldPlan()) as world:
        world.spawn(cart(xyz=(0.0, 0.0, 6.0), z_auto=False))  # 1.1 s of free fall, then the floor
        run(world, "cart", 480)
        assert world.read("cart").true_z < 0.2


def test_a_robot_turned_on_its_side_is_tipped_over_and_the_limit_is_settable():
    on_side = (math.sin(math.radians(35)), 0.0, 0.0, math.cos(math.radians(35)))  # roll 70 deg
    with World(Physics(), WorldPlan()) as world:
        world.spawn(cart())
        world.teleport("cart", SpawnPose(xyz=(0.0, 0.0, 0.5), quat=on_side))
        with pytest.raises(SimulationFault, match=r"tipped over at step 24: tilted 7\d deg \(roll 7\d deg") as info:
            run(world, "cart", 24)
        assert info.value.kind == "tipped_over"
    lenient = Physics(faults=FaultLimits(max_tilt=math.pi))
    with World(lenient, WorldPlan()) as world:
        world.spawn(cart())
        world.teleport("cart", SpawnPose(xyz=(0.0, 0.0, 0.5), quat=on_side))
        run(world, "cart", 240)  # 180 deg: no tilt is beyond it


def test_a_robot_thrown_sideways_fast_ran_away():
    with World(Physics(), WorldPlan()) as world:
        world.spawn(cart())
        world.teleport("cart", SpawnPose(xyz=(0.0, 0.0, 0.3)), linear=(30.0, 0.0, 0.0))
        with pytest.raises(SimulationFault, match=r"ran away at step 24: moving at 30\.0 m/s") as info:
            run(world, "cart", 24)
        assert info.value.kind == "runaway"


def test_commanded_speed_raises_the_runaway_limit():
    with World(Physics(faults=FaultLimits(max_speed=1.0)), WorldPlan()) as world:
        world.spawn(cart())
        world.set_command("cart", 1.5, 0.0)  # 1.5 m/s: the limit is now 3 m/s
        run(world, "cart", 480)
        assert world.read("cart").true_vx == pytest.approx(1.5, abs=0.1)
