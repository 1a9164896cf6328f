"""Gymnasium interface of UNav-Sim.

    import gymnasium, unav_gym
    env = gymnasium.make("unav/PipeFollowing-v0")                  # the paper's task, 180x320 RGB
    env = gymnasium.make("unav/PipeFollowing-v0", dynamics="kinematic",
                         **{"scenario.cameras.width": 128, "scenario.cameras.height": 72})
    envs = gymnasium.make_vec("unav/PipeFollowing-v0", num_envs=4)  # one process; frames on 1-2 GL contexts

Keyword arguments are keys of config/learning/pipe_following.yaml: a bare key is an ``env`` key
(``max_steps=100``), ``scenario.<key>`` and ``pipe_scenes.<key>`` reach the other sections;
``config=`` names another file. Unknown keys raise ValueError naming the key.
"""
import gymnasium

from unav_gym.envs import PipeFollowingEnv, PipeFollowingVectorEnv, default_config

__all__ = ["PipeFollowingEnv", "PipeFollowingVectorEnv", "default_config"]

if "unav/PipeFollowing-v0" not in gymnasium.registry:
    gymnasium.register(
        id="unav/PipeFollowing-v0",
        entry_point="unav_gym.envs:PipeFollowingEnv",
        vector_entry_point="unav_gym.envs:PipeFollowingVectorEnv",
    )
