"""The vector core and the stable-baselines3 VecEnv: same frames as single envs, SB3 autoreset."""
import numpy as np

from unav_gym import _core
from unav_gym.sb3 import PipeFollowingVecEnv

KW = {"dynamics": '"kinematic"', "scenario.cameras.width": "96", "scenario.cameras.height": "54"}


def test_vector_core_matches_single_cores():
    vec = _core.VectorPipeFollowingCore(3, "", KW, 2)
    obs, infos = vec.reset([11, 12, 13])
    actions = np.array([[0.2, 0.0], [-0.5, 0.3], [0.0, -1.0]])
    vobs, vrew, vterm, vtrunc, vinfos = vec.step(actions)
    for i, seed in enumerate([11, 12, 13]):
        single = _core.PipeFollowingCore("", KW)
        o0, i0 = single.reset(seed)
        assert np.array_equal(o0, obs[i])
        o1, r1, te, tr, i1 = single.step(actions[i])
        assert np.array_equal(o1, vobs[i])
        assert r1 == vrew[i] and te == vterm[i] and tr == vtrunc[i]


def test_sb3_vecenv_autoresets_in_the_same_step():
    env = PipeFollowingVecEnv(2, seed=0, dynamics="kinematic", max_steps=3,
                              **{"scenario.cameras.width": 96, "scenario.cameras.height": 54})
    first = env.reset()
    assert first.shape == (2, 54, 96, 3)
    for k in range(3):
        env.step_async(np.zeros((2, 2), dtype=np.float32))
        obs, rewards, dones, infos = env.step_wait()
    assert dones.all()
    for i in range(2):
        term = infos[i]["terminal_observation"]
        assert term.shape == (54, 96, 3)
        assert infos[i]["TimeLimit.truncated"] is True
        assert not np.array_equal(term, obs[i])  # obs[i] is the next episode's first frame
    assert rewards.dtype == np.float32
