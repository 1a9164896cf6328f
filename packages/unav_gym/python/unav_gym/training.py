"""Training helpers for the pipe follower: behaviour cloning from the privileged expert,
evaluation on held-out seeds and on the fixed evaluation pipe, ONNX export."""
from __future__ import annotations

import json
import math
from dataclasses import dataclass

import numpy as np
import torch

from unav_gym import _core
from unav_gym.envs import _overrides


@dataclass
class EvalResult:
    mean_return: float
    mean_length: float
    mean_e_p: float
    max_e_p: float
    mean_progress: float   # fraction of the pipe length followed when the episode ended
    completed: float       # share of episodes that reached the pipe end
    episodes: int

    def as_dict(self) -> dict:
        return dict(self.__dict__)


def policy_action(model, obs: np.ndarray) -> np.ndarray:
    action, _ = model.predict(obs, deterministic=True)
    return np.clip(action, -1.0, 1.0)


def evaluate(act, overrides: dict, seeds: list[int], config: str = "") -> EvalResult:
    """Runs one episode per seed with `act(obs) -> (2,) action` and returns the figures."""
    core = _core.PipeFollowingCore(config, _overrides(overrides))
    rets, lens, eps, maxes, prog, done_end = [], [], [], [], [], []
    for seed in seeds:
        obs, info = core.reset(int(seed))
        ret, n, e_sum, e_max = 0.0, 0, 0.0, 0.0
        while True:
            obs, r, term, trunc, info = core.step(np.asarray(act(obs), dtype=np.float64).reshape(2))
            ret += r
            n += 1
            e_sum += info["e_p"]
            e_max = max(e_max, info["e_p"])
            if term or trunc:
                break
        rets.append(ret)
        lens.append(n)
        eps.append(e_sum / n)
        maxes.append(e_max)
        prog.append(info["progress"])
        done_end.append(bool(info["pipe_end"]) and not term)
    return EvalResult(float(np.mean(rets)), float(np.mean(lens)), float(np.mean(eps)), float(np.max(maxes)),
                      float(np.mean(prog)), float(np.mean(done_end)), len(seeds))


def collect_expert(venv_core, steps: int, noise: float, rng: np.random.Generator):
    """DAgger-style data: roll out the expert with Gaussian action noise (so the data covers
    recoveries from off-centre states) and label every visited state with the clean expert action."""
    n = venv_core.num_envs
    obs, _ = venv_core.reset([int(s) for s in rng.integers(0, 2**62, size=n)])
    xs, ys = [], []
    for _ in range(int(math.ceil(steps / n))):
        expert = np.asarray(venv_core.expert_actions(), dtype=np.float32)
        xs.append(obs.copy())
        ys.append(expert)
        act = np.clip(expert + noise * rng.standard_normal(expert.shape), -1, 1)
        obs, _, term, trunc, _ = venv_core.step(act)
        done = np.logical_or(term, trunc)
        if done.any():
            seeds = [int(s) if d else None for s, d in zip(rng.integers(0, 2**62, size=n), done)]
            new_obs, _ = venv_core.reset_some(seeds)
            obs[done] = new_obs[done]
    return np.concatenate(xs)[:steps], np.concatenate(ys)[:steps]


def actor_mean(policy, obs_chw):
    """The Gaussian policy's mean action for NCHW float observations in 0..255, through the
    actor's own feature extractor (shared or not) only."""
    from stable_baselines3.common.policies import BaseModel
    features = BaseModel.extract_features(policy, obs_chw, policy.pi_features_extractor)
    return policy.action_net(policy.mlp_extractor.forward_actor(features))


def behaviour_clone(model, obs: np.ndarray, actions: np.ndarray, epochs: int, batch: int = 128,
                    lr: float = 1e-3, log=print) -> list[float]:
    """Fits the policy's mean action to the expert's (MSE), keeping PPO's value head untouched."""
    policy = model.policy
    opt = torch.optim.Adam(policy.parameters(), lr=lr)
    losses = []
    n = len(obs)
    rng = np.random.default_rng(0)
    for epoch in range(epochs):
        perm = rng.permutation(n)
        total = 0.0
        for i in range(0, n, batch):
            idx = perm[i:i + batch]
            # HWC uint8 -> CHW float 0..255: the policy (behind VecTransposeImage) scales by 1/255 itself.
            o = torch.as_tensor(obs[idx]).permute(0, 3, 1, 2).float()
            a = torch.as_tensor(actions[idx])
            mean = actor_mean(policy, o)
            loss = torch.nn.functional.mse_loss(mean, a)
            opt.zero_grad()
            loss.backward()
            opt.step()
            total += float(loss) * len(idx)
        losses.append(total / n)
        log(f"behaviour cloning epoch {epoch + 1}/{epochs}: mse {losses[-1]:.4f}")
    return losses


def check_image(h: int, w: int) -> np.ndarray:
    """The synthetic image of the export check: r = 255 x/(w-1), g = 255 y/(h-1), b = 128."""
    img = np.zeros((h, w, 3), dtype=np.float32)
    img[..., 0] = 255.0 * np.arange(w, dtype=np.float32)[None, :] / (w - 1)
    img[..., 1] = 255.0 * np.arange(h, dtype=np.float32)[:, None] / (h - 1)
    img[..., 2] = 128.0
    return img


class _OnnxPolicy(torch.nn.Module):
    """NHWC image (float 0..255) -> deterministic action (the Gaussian's mean). Clipping to
    [-1, 1] is left to the caller: OpenCV 4.6's ONNX importer cannot read opset-11 Clip."""

    def __init__(self, policy):
        super().__init__()
        self.policy = policy

    def forward(self, image):
        x = image.permute(0, 3, 1, 2).float()   # NHWC 0..255 -> NCHW; extract_features scales by 1/255
        return actor_mean(self.policy, x)


def export_onnx(model, path: str, obs_shape, metadata: dict) -> None:
    """ONNX graph for OpenCV DNN (the drl_planner node): input `image` float32 NHWC in 0..255 (RGB,
    the observation as a float), output `action` (N, 2), the deterministic (unclipped) action. Metadata beside it (<path>.json), with a check pair: the action for a fixed
    synthetic image, which the C++ loader test reproduces."""
    module = _OnnxPolicy(model.policy).eval()
    h, w, c = obs_shape
    dummy = torch.zeros(1, h, w, c, dtype=torch.float32)
    torch.onnx.export(module, dummy, path, input_names=["image"], output_names=["action"], opset_version=11,
                      dynamic_axes=None)
    with torch.no_grad():
        img = check_image(h, w)
        check = module(torch.as_tensor(img).unsqueeze(0))[0].clamp(-1, 1).tolist()
        # The same image rounded to uint8 values (what the C++ test feeds act(): convertTo rounds).
        check_u8 = module(torch.as_tensor(np.round(img).astype(np.float32)).unsqueeze(0))[0].clamp(-1, 1).tolist()
    metadata = dict(metadata, obs_shape=[h, w, c], check_action=check, check_action_u8=check_u8,
                    check_image="r = 255 x / (w - 1), g = 255 y / (h - 1), b = 128 (float, NHWC)")
    with open(path + ".json", "w") as f:
        json.dump(metadata, f, indent=2, sort_keys=True)
