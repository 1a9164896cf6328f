"""gymnasium.Env and gymnasium VectorEnv over the C++ pipe-following core (unav_gym._core)."""
from __future__ import annotations

import json
from typing import Any

import gymnasium
import numpy as np
from gymnasium import spaces
from gymnasium.vector.utils import batch_space

from unav_gym import _core

# Episode seeds are drawn from the Gymnasium generator in [0, 2**62): the core maps them to
# disjoint training / evaluation scene seeds (split=train / eval).
_SEED_SPACE = 2**62


def default_config() -> str:
    """Path of the installed config/learning/pipe_following.yaml."""
    return _core.default_config()


def _overrides(kwargs: dict[str, Any]) -> dict[str, str]:
    # YAML is a superset of JSON: numbers, booleans, lists and strings pass through json.dumps.
    return {str(k): json.dumps(v) for k, v in kwargs.items()}


def _info(d: dict) -> dict:
    d["position"] = np.asarray(d["position"], dtype=np.float64)
    return d


class PipeFollowingEnv(gymnasium.Env):
    """The paper's DRL pipe following (UNav-Sim section V-B).

    Observation: the down camera's RGB image, uint8 (H, W, 3) (180x320 by default).
    Action: (a1, a2) in [-1, 1]^2: direction of the 1 m step relative to the heading, and the
    heading change; the MPC flies the waypoint (``dynamics="kinematic"``: placed on it).
    Reward: 10 - 2 e_p^2 - 2 e_psi. Terminated when e_p > 2.5 m; truncated at the pipe end or
    after ``max_steps``. ``info``: e_p, e_psi, progress, arc_length, lateral, ... (see README).
    Actions outside [-1, 1] are clipped and NaN components replaced by 0; both are counted in
    info (clipped_actions, rejected_actions) and warned about once.
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": 1}

    def __init__(self, config: str | None = None, render_mode: str | None = None, **kwargs: Any):
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(f"render_mode {render_mode!r}: supported {self.metadata['render_modes']}")
        self.render_mode = render_mode
        self._core = _core.PipeFollowingCore(config or "", _overrides(kwargs))
        h, w, c = self._core.obs_shape
        self.observation_space = spaces.Box(0, 255, (h, w, c), np.uint8)
        self.action_space = spaces.Box(-1.0, 1.0, (2,), np.float32)
        self._last_obs: np.ndarray | None = None
        self._warned = False

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        super().reset(seed=seed)
        for key, value in (options or {}).items():
            self._core.set_option(str(key), json.dumps(value))
        episode_seed = int(self.np_random.integers(0, _SEED_SPACE))
        obs, info = self._core.reset(episode_seed)
        self._last_obs = obs
        return obs, _info(info)

    def step(self, action):
        obs, reward, terminated, truncated, info = self._core.step(np.asarray(action, dtype=np.float64).reshape(-1))
        if (info["clipped_actions"] or info["rejected_actions"]) and not self._warned:
            gymnasium.logger.warn(
                f"unav/PipeFollowing: actions outside [-1, 1] are clipped and NaN replaced by 0 "
                f"(so far {info['clipped_actions']} clipped, {info['rejected_actions']} rejected; see info)")
            self._warned = True
        self._last_obs = obs
        return obs, float(reward), bool(terminated), bool(truncated), _info(info)

    def render(self):
        return None if self._last_obs is None else self._last_obs.copy()

    def expert_action(self) -> np.ndarray:
        """Privileged action (knows the pipe): steers to the centre line 2 m ahead."""
        return np.asarray(self._core.expert_action(), dtype=np.float32)


class PipeFollowingVectorEnv(gymnasium.vector.VectorEnv):
    """N pipe-following environments in one process, dynamics on threads, frames on GL threads
    (on llvmpipe two EGL contexts on two displays, rendering at once).

    Next-step autoreset (Gymnasium 1.0): the step after a sub-environment ends resets it and
    returns its first observation with reward 0.
    """

    metadata = {"render_modes": ["rgb_array"], "autoreset_mode": "next_step"}

    def __init__(self, num_envs: int = 4, config: str | None = None, num_threads: int = 0,
                 render_mode: str | None = None, **kwargs: Any):
        self._core = _core.VectorPipeFollowingCore(int(num_envs), config or "", _overrides(kwargs), int(num_threads))
        self.num_envs = int(num_envs)
        self.render_mode = render_mode
        h, w, c = self._core.obs_shape
        self.single_observation_space = spaces.Box(0, 255, (h, w, c), np.uint8)
        self.single_action_space = spaces.Box(-1.0, 1.0, (2,), np.float32)
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self._autoreset = np.zeros(self.num_envs, dtype=bool)
        self._last_obs: np.ndarray | None = None

    def _draw_seeds(self) -> list[int]:
        return [int(s) for s in self.np_random.integers(0, _SEED_SPACE, size=self.num_envs)]

    def _infos(self, infos: list[dict]) -> dict:
        out: dict = {}
        for i, info in enumerate(infos):
            out = self._add_info(out, _info(info), i)
        return out

    def reset(self, *, seed: int | list[int] | None = None, options: dict[str, Any] | None = None):
        if isinstance(seed, (list, tuple)):
            seed = seed[0]
        if seed is not None or not hasattr(self, "_np_random") or self._np_random is None:
            self._np_random, self._np_random_seed = gymnasium.utils.seeding.np_random(seed)
        for key, value in (options or {}).items():
            self._core.set_option(str(key), json.dumps(value))
        obs, infos = self._core.reset(self._draw_seeds())
        self._autoreset[:] = False
        self._last_obs = obs
        return obs, self._infos(infos)

    def step(self, actions):
        seeds = self._draw_seeds()
        resets = [seeds[i] if self._autoreset[i] else None for i in range(self.num_envs)]
        obs, rewards, terminated, truncated, infos = self._core.step(
            np.asarray(actions, dtype=np.float64).reshape(self.num_envs, 2), resets)
        self._autoreset = np.logical_or(terminated, truncated)
        self._last_obs = obs
        return obs, rewards, terminated, truncated, self._infos(infos)

    def render(self):
        return None if self._last_obs is None else tuple(self._last_obs)

    def expert_actions(self) -> np.ndarray:
        return np.asarray(self._core.expert_actions(), dtype=np.float32)
