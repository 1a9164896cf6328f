"""unav/PipeFollowing-v0 is a real gymnasium.Env: both checkers, types, seeding, bad input."""
import math
import warnings

import gymnasium
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env as gym_check_env
from stable_baselines3.common.env_checker import check_env as sb3_check_env

import unav_gym  # noqa: F401  (registers the ids)

SMALL = {"scenario.cameras.width": 128, "scenario.cameras.height": 72}


def test_gymnasium_checker_passes_on_the_papers_env():
    # Default config: MPC dynamics, 180x320 down camera, random scenes; includes the checker's
    # seeded determinism checks (reset(seed) twice, one seeded step twice).
    env = gymnasium.make("unav/PipeFollowing-v0")
    assert env.observation_space.shape == (180, 320, 3)
    assert env.observation_space.dtype == np.uint8
    assert env.action_space.shape == (2,)
    gym_check_env(env.unwrapped, skip_render_check=False)


def test_stable_baselines3_checker_passes():
    env = gymnasium.make("unav/PipeFollowing-v0", dynamics="kinematic", **SMALL)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # SB3 warns about anything it would not train on
        sb3_check_env(env.unwrapped, warn=True)


def test_step_returns_python_types_and_the_papers_reward():
    env = gymnasium.make("unav/PipeFollowing-v0", dynamics="kinematic", scenes="fixed", start_offset_m=0.0,
                         start_heading_deg=0.0, start_arc_fraction=0.0, **SMALL)
    obs, info = env.reset(seed=3)
    assert obs.shape == (72, 128, 3) and obs.dtype == np.uint8
    obs, reward, terminated, truncated, info = env.step(np.array([0.0, 1.0], dtype=np.float32))
    assert type(reward) is float and type(terminated) is bool and type(truncated) is bool
    # Straight on the pipe, then a 30 deg turn: r = 10 - 2 * 0 - 2 * pi/6.
    assert info["e_p"] == pytest.approx(0.0, abs=1e-9)
    assert reward == pytest.approx(10.0 - 2.0 * math.pi / 6.0, abs=1e-9)
    for key in ("e_p", "e_psi", "progress", "arc_length", "pipe_length", "lateral", "time"):
        assert key in info


def test_seeds_repeat_and_differ():
    env = gymnasium.make("unav/PipeFollowing-v0", dynamics="kinematic", **SMALL)
    a, ia = env.reset(seed=5)
    b, ib = env.reset(seed=5)
    c, ic = env.reset(seed=6)
    assert np.array_equal(a, b) and ia["scene_seed"] == ib["scene_seed"]
    assert not np.array_equal(a, c) and ia["scene_seed"] != ic["scene_seed"]
    # Evaluation split: disjoint scene seeds.
    ev = gymnasium.make("unav/PipeFollowing-v0", dynamics="kinematic", split="eval", **SMALL)
    _, ie = ev.reset(seed=5)
    assert ie["scene_seed"] != ia["scene_seed"]


def test_bad_input_is_named():
    with pytest.raises(ValueError, match="max_stepz"):
        gymnasium.make("unav/PipeFollowing-v0", max_stepz=5)
    with pytest.raises(ValueError, match="dynamics"):
        gymnasium.make("unav/PipeFollowing-v0", dynamics="teleport")
    env = gymnasium.make("unav/PipeFollowing-v0", dynamics="kinematic", **SMALL)
    with pytest.raises(ValueError, match="no_such_option"):
        env.reset(seed=1, options={"no_such_option": 1})
    with pytest.raises(ValueError, match="scenes"):
        env.reset(seed=1, options={"scenes": "fixed"})
    env.reset(seed=1, options={"start_offset_m": 0.0})
    with pytest.raises(ValueError, match="2 elements"):
        env.step(np.zeros(3))


def test_out_of_range_and_nan_actions_are_counted_never_integrated():
    env = gymnasium.make("unav/PipeFollowing-v0", dynamics="kinematic", scenes="fixed", start_offset_m=0.0,
                         start_heading_deg=0.0, start_arc_fraction=0.0, **SMALL)
    env.reset(seed=0)
    with pytest.warns(UserWarning, match="clipped"):
        _, reward, _, _, info = env.unwrapped.step(np.array([np.nan, 7.0]))
    assert info["rejected_actions"] == 1 and info["clipped_actions"] == 1
    assert math.isfinite(reward)
    assert info["position"][0] == pytest.approx(1.0, abs=1e-9)  # NaN -> straight ahead, 1 m north
    assert info["e_psi"] == pytest.approx(math.pi / 6, abs=1e-9)  # 7 -> 1: full turn


def test_make_vec_uses_the_in_process_vector_env():
    envs = gymnasium.make_vec("unav/PipeFollowing-v0", num_envs=3, dynamics="kinematic", max_steps=2, **SMALL)
    assert isinstance(envs.unwrapped, unav_gym.PipeFollowingVectorEnv)
    obs, infos = envs.reset(seed=0)
    assert obs.shape == (3, 72, 128, 3)
    assert infos["e_p"].shape == (3,)
    actions = np.zeros((3, 2), dtype=np.float32)
    obs, rew, term, trunc, infos = envs.step(actions)
    obs, rew, term, trunc, infos = envs.step(actions)
    assert trunc.all()  # max_steps = 2
    # Next-step autoreset: the following step resets every env (reward 0, step count 0).
    obs, rew, term, trunc, infos = envs.step(actions)
    assert (rew == 0).all() and (infos["steps"] == 0).all()
    assert not trunc.any() and not term.any()
