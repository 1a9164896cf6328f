"""A stable-baselines3 VecEnv over the C++ vector core: N envs stepped in one process (dynamics
on threads, frames on one or two GL contexts), SB3's same-step autoreset (info["terminal_observation"])."""
from __future__ import annotations

import json
from typing import Any

import numpy as np
from gymnasium import spaces
from stable_baselines3.common.vec_env.base_vec_env import VecEnv

from unav_gym import _core
from unav_gym.envs import _SEED_SPACE, _info, _overrides


class PipeFollowingVecEnv(VecEnv):
    def __init__(self, num_envs: int = 4, config: str | None = None, seed: int = 0, num_threads: int = 0,
                 **kwargs: Any):
        self._core = _core.VectorPipeFollowingCore(int(num_envs), config or "", _overrides(kwargs), int(num_threads))
        h, w, c = self._core.obs_shape
        super().__init__(int(num_envs), spaces.Box(0, 255, (h, w, c), np.uint8),
                         spaces.Box(-1.0, 1.0, (2,), np.float32))
        self._rng = np.random.default_rng(seed)
        self._actions: np.ndarray | None = None

    def _draw_seeds(self) -> list[int]:
        return [int(s) for s in self._rng.integers(0, _SEED_SPACE, size=self.num_envs)]

    def seed(self, seed: int | None = None):
        self._rng = np.random.default_rng(seed)
        return [seed] * self.num_envs

    def reset(self):
        obs, _ = self._core.reset(self._draw_seeds())
        return obs

    def step_async(self, actions: np.ndarray) -> None:
        self._actions = np.asarray(actions, dtype=np.float64).reshape(self.num_envs, 2)

    def step_wait(self):
        obs, rewards, terminated, truncated, infos = self._core.step(self._actions)
        done = np.logical_or(terminated, truncated)
        infos = [_info(i) for i in infos]
        if done.any():
            # SB3 resets in the same step: keep the last frame, return the first of the next episode.
            seeds = self._draw_seeds()
            resets = [seeds[i] if done[i] else None for i in range(self.num_envs)]
            for i in np.flatnonzero(done):
                infos[i]["terminal_observation"] = obs[i].copy()
                infos[i]["TimeLimit.truncated"] = bool(truncated[i] and not terminated[i])
            # A step with every action ignored except for the resetting envs is not what we want:
            # reset only those (the others' observation is unchanged by observing again).
            new_obs, _ = self._core.reset_some(resets)
            for i in np.flatnonzero(done):
                obs[i] = new_obs[i]
        return obs, rewards.astype(np.float32), done, infos

    def expert_actions(self) -> np.ndarray:
        return np.asarray(self._core.expert_actions(), dtype=np.float32)

    def close(self) -> None:
        self._core = None

    def get_attr(self, attr_name, indices=None):
        return [getattr(self, attr_name, None)] * len(self._idx(indices))

    def set_attr(self, attr_name, value, indices=None) -> None:
        setattr(self, attr_name, value)

    def env_method(self, method_name, *method_args, indices=None, **method_kwargs):
        raise NotImplementedError(f"env_method({method_name}) is not supported by the in-process vector core")

    def env_is_wrapped(self, wrapper_class, indices=None):
        return [False] * len(self._idx(indices))

    def _idx(self, indices):
        if indices is None:
            return list(range(self.num_envs))
        return [indices] if isinstance(indices, int) else list(indices)
