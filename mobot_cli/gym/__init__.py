"""mobot as a Gymnasium environment (extra ``gym``): ``gymnasium.make("mobot_cli.gym:mobot/GoTo-v0")``."""

import gymnasium

from mobot_cli.gym.env import MobotEnv, StepOutcome

ENV_ID = "mobot/GoTo-v0"
if ENV_ID not in gymnasium.registry:
    gymnasium.register(id=ENV_ID, entry_point="mobot_cli.gym.env:MobotEnv", max_episode_steps=400)

__all__ = ["ENV_ID", "MobotEnv", "StepOutcome"]
