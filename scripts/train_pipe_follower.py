#!/usr/bin/env python3
"""Train the pipe-following policy (the paper's DRL planner) with stable-baselines3 PPO.

    .venv/bin/python scripts/train_pipe_follower.py --out out/train/seed0 --seed 0 --steps 30000
    .venv/bin/python scripts/train_pipe_follower.py --variant full ...      # 180x320, the paper's input
    .venv/bin/python scripts/train_pipe_follower.py --resume out/train/seed0/checkpoints/ppo_20000.zip ...

Levers for a 2-core laptop (all on by default, each switchable): the in-process vector env (one
GL context, dynamics on threads); the 1 m action itself as frame skip; a behaviour-cloning warm
start from the privileged MPC-waypoint expert (--bc-steps, DAgger-style noisy rollouts labelled
by the clean expert); the fast variant (kinematic waypoints, 72x128 images; the deployed planner
resizes the 180x320 camera to the trained size). The policy is evaluated on held-out scene seeds
(split=eval) during training and, at the end, on the fixed ~20 m evaluation pipe with the MPC
flying the waypoints. Outputs in --out: progress.csv (SB3 logger), monitor.csv, eval.csv,
checkpoints/, best.zip (best held-out return), last.zip, policy.zip (= best), policy.onnx (+ .json:
seed, steps, config), summary.json.
Extra arguments key=value override config keys (max_steps=100, scenario.render.marine_snow=false, ...).
"""
from __future__ import annotations

import argparse
import csv
import json
import os
import sys
import time

import numpy as np
import torch

VARIANTS = {
    # The fast variant: what trains within a session on 2 CPU cores.
    "fast": {"dynamics": "kinematic", "scenario.cameras.width": 128, "scenario.cameras.height": 72},
    # The paper's input size; kinematic waypoints for speed (the MPC flies them at deployment).
    "full": {"dynamics": "kinematic"},
}


def parse_value(text: str):
    try:
        return json.loads(text)
    except json.JSONDecodeError:
        return text


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", default="out/train/pipe_follower")
    ap.add_argument("--config", default="", help="learning config (default: config/learning/pipe_following.yaml)")
    ap.add_argument("--variant", choices=sorted(VARIANTS), default="fast")
    ap.add_argument("--steps", type=int, default=30000, help="PPO environment steps")
    ap.add_argument("--envs", type=int, default=4)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--bc-steps", type=int, default=6000, help="expert samples for the warm start (0 = none)")
    ap.add_argument("--bc-epochs", type=int, default=10)
    ap.add_argument("--bc-noise", type=float, default=0.5, help="action noise of the expert rollouts")
    ap.add_argument("--lr", type=float, default=2e-5, help="PPO learning rate (small: fine-tuning the BC policy)")
    ap.add_argument("--critic-warmup", type=int, default=4096,
                    help="PPO steps that train only the value head first (the cloned actor frozen)")
    ap.add_argument("--n-steps", type=int, default=256, help="PPO rollout length per env")
    ap.add_argument("--eval-every", type=int, default=5000)
    ap.add_argument("--eval-episodes", type=int, default=6)
    ap.add_argument("--checkpoint-every", type=int, default=10000)
    ap.add_argument("--resume", default="", help="a checkpoint .zip to continue from")
    ap.add_argument("--threads", type=int, default=1, help="torch threads")
    ap.add_argument("--no-progress-bar", action="store_true")
    ap.add_argument("overrides", nargs="*", help="config key=value")
    args = ap.parse_args()

    torch.set_num_threads(args.threads)
    from stable_baselines3 import PPO
    from stable_baselines3.common.callbacks import BaseCallback, CheckpointCallback, CallbackList
    from stable_baselines3.common.logger import configure
    from stable_baselines3.common.vec_env import VecMonitor

    from unav_gym.sb3 import PipeFollowingVecEnv
    from unav_gym import training

    overrides = dict(VARIANTS[args.variant])
    for kv in args.overrides:
        if "=" not in kv:
            ap.error(f"override {kv!r}: expected key=value")
        k, v = kv.split("=", 1)
        overrides[k] = parse_value(v)
    os.makedirs(os.path.join(args.out, "checkpoints"), exist_ok=True)
    log_lines = open(os.path.join(args.out, "train.log"), "a")

    def log(msg: str) -> None:
        print(msg, flush=True)
        log_lines.write(msg + "\n")
        log_lines.flush()

    venv = VecMonitor(PipeFollowingVecEnv(args.envs, config=args.config, seed=args.seed, **overrides),
                      filename=os.path.join(args.out, "monitor.csv"))
    obs_shape = venv.observation_space.shape
    log(f"pipe follower: variant {args.variant}, obs {obs_shape}, {args.envs} envs, seed {args.seed}, "
        f"overrides {overrides}")
    eval_overrides = dict(overrides, split="eval")
    eval_seeds = list(range(args.eval_episodes))
    eval_rows: list[dict] = []

    best = {"return": -float("inf"), "steps": -1}

    def run_eval(model, steps: int) -> None:
        t = time.time()
        r = training.evaluate(lambda o: training.policy_action(model, o), eval_overrides, eval_seeds, args.config)
        row = dict(steps=steps, **r.as_dict(), seconds=time.time() - t)
        eval_rows.append(row)
        with open(os.path.join(args.out, "eval.csv"), "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=list(row))
            w.writeheader()
            w.writerows(eval_rows)
        log(f"eval @ {steps} steps (held-out scenes): return {r.mean_return:.1f}, length {r.mean_length:.1f}, "
            f"mean e_p {r.mean_e_p:.3f} m, progress {r.mean_progress:.2f}, completed {r.completed:.2f}")
        # Model selection on the held-out training-distribution scenes (a validation set); the
        # fixed evaluation pipe is never looked at before the end.
        if r.mean_return > best["return"]:
            best.update({"return": r.mean_return, "steps": steps})
            model.save(os.path.join(args.out, "best.zip"))

    if args.resume:
        model = PPO.load(args.resume, env=venv, device="cpu")
        log(f"resumed from {args.resume} at {model.num_timesteps} steps")
    else:
        model = PPO("CnnPolicy", venv, n_steps=args.n_steps, batch_size=256, n_epochs=4, learning_rate=args.lr,
                    gamma=0.95, gae_lambda=0.9, clip_range=0.1, ent_coef=0.0,
                    # Separate CNNs for actor and critic: value targets (~100) would otherwise push
                    # the shared features away from what behaviour cloning taught the actor.
                    policy_kwargs=dict(log_std_init=-1.5, share_features_extractor=False),
                    seed=args.seed, device="cpu", verbose=0)
        run_eval(model, 0)
        if args.bc_steps > 0:
            t = time.time()
            rng = np.random.default_rng(args.seed + 1000)
            obs, act = training.collect_expert(venv.venv._core, args.bc_steps, args.bc_noise, rng)
            log(f"behaviour cloning: {len(obs)} expert samples in {time.time() - t:.0f} s")
            training.behaviour_clone(model, obs, act, args.bc_epochs, log=log)
            del obs, act
            run_eval(model, 0)
    model.set_logger(configure(args.out, ["csv", "log"] + (["tensorboard"] if _has_tensorboard() else [])))

    class EvalCallback(BaseCallback):
        def __init__(self):
            super().__init__()
            self.next = (model.num_timesteps // args.eval_every + 1) * args.eval_every

        def _on_step(self) -> bool:
            if self.num_timesteps >= self.next:
                run_eval(self.model, self.num_timesteps)
                self.next += args.eval_every
            return True

    def set_actor_trainable(trainable: bool) -> None:
        critic = ("value_net", "mlp_extractor.value_net", "vf_features_extractor")
        for name, param in model.policy.named_parameters():
            if not name.startswith(critic):
                param.requires_grad_(trainable)

    warmup = 0 if args.resume else min(args.critic_warmup, args.steps)
    if warmup > 0:
        set_actor_trainable(False)
        t = time.time()
        model.learn(warmup, progress_bar=False)
        set_actor_trainable(True)
        log(f"critic warm-up: {warmup} steps with the actor frozen ({time.time() - t:.0f} s)")
        run_eval(model, model.num_timesteps)

    ckpt = CheckpointCallback(max(1, args.checkpoint_every // args.envs), os.path.join(args.out, "checkpoints"),
                              name_prefix="ppo")
    t0 = time.time()
    model.learn(args.steps - warmup, callback=CallbackList([ckpt, EvalCallback()]), reset_num_timesteps=False,
                progress_bar=not args.no_progress_bar)
    train_s = time.time() - t0
    model.save(os.path.join(args.out, "last.zip"))
    if not eval_rows or eval_rows[-1]["steps"] != model.num_timesteps:
        run_eval(model, model.num_timesteps)
    # The shipped policy: the best on the held-out scenes.
    model = PPO.load(os.path.join(args.out, "best.zip"), device="cpu")
    model.save(os.path.join(args.out, "policy.zip"))
    log(f"policy = the best held-out evaluation: return {best['return']:.1f} at {best['steps']} steps")

    # The fixed evaluation pipe (never trained on), MPC flying the waypoints, at the policy's size.
    fixed = dict(overrides, scenes="fixed", dynamics="mpc", start_offset_m=0.0, start_heading_deg=0.0,
                 start_arc_fraction=0.0)
    r_fixed = training.evaluate(lambda o: training.policy_action(model, o), fixed, [0], args.config)
    log(f"fixed evaluation pipe (MPC): mean e_p {r_fixed.mean_e_p:.3f} m, max {r_fixed.max_e_p:.3f} m, "
        f"progress {r_fixed.mean_progress:.2f}, completed {bool(r_fixed.completed)}")
    meta = dict(seed=args.seed, steps=int(best["steps"]), trained_steps=args.steps, variant=args.variant, overrides=overrides,
                obs_shape=list(obs_shape), bc_steps=args.bc_steps, bc_epochs=args.bc_epochs, lr=args.lr,
                config=args.config or "config/learning/pipe_following.yaml", train_seconds=train_s,
                stable_baselines3="2.4.1", torch=torch.__version__)
    training.export_onnx(model, os.path.join(args.out, "policy.onnx"), obs_shape, meta)
    summary = dict(meta, eval=[r for r in eval_rows if r["steps"] == best["steps"]][-1], last_eval=eval_rows[-1],
                   fixed_pipe=r_fixed.as_dict())
    with open(os.path.join(args.out, "summary.json"), "w") as f:
        json.dump(summary, f, indent=2, sort_keys=True)
    log(f"done in {train_s:.0f} s of PPO: {args.out}/policy.zip, policy.onnx, eval.csv, progress.csv")
    return 0


def _has_tensorboard() -> bool:
    try:
        import torch.utils.tensorboard  # noqa: F401
        return True
    except Exception:
        return False


if __name__ == "__main__":
    sys.exit(main())
