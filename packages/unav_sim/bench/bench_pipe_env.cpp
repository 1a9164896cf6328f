// Throughput of the pipe-following environment on this machine, printed (not a test):
// steps/s of one env and of the vectorised env (one EGL context), for both dynamics, with the
// time per step split into physics, MPC + allocator, render submit and readback.
//   bench_pipe_env [--config F] [--steps 60] [--envs 4] [--dynamics mpc|kinematic] [key=value ...]
// The vector env runs twice on one EGL context and twice as it chooses (two displays on llvmpipe),
// alternated: this VM's speed drifts over minutes.
// key=value: any config key (scenario.cameras.width=80, scenario.render.marine_snow=false, ...).
// Machine-readable (D: kinematic or mpc, HxW: the observation, e.g. 180x320; N: --envs):
// BENCH sim/pipe_env_reset_ms; sim/pipe_env_D_HxW_steps_per_s and, per step of that one env,
// sim/pipe_env_D_HxW_{physics,control,render,readback}_ms; sim/pipe_env_D_HxW_Nenvs_{1ctx,auto_ctx}_steps_per_s
// (the vector env on one EGL context / as many as it chooses, mean of its two runs).
#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "unav_common/bench.hpp"
#include "unav_common/resources.hpp"
#include "unav_physics/scenario_builder.hpp"
#include "unav_sim/pipe_following_env.hpp"

using namespace unav::sim;
using Clock = std::chrono::steady_clock;

namespace {

EpisodeTimings sum(const EpisodeTimings& a, const EpisodeTimings& b) {
  EpisodeTimings s = a;
  s.physics_s += b.physics_s;
  s.control_s += b.control_s;
  s.render_s += b.render_s;
  s.readback_s += b.readback_s;
  s.physics_steps += b.physics_steps;
  s.control_steps += b.control_steps;
  s.frames += b.frames;
  return s;
}
EpisodeTimings diff(const EpisodeTimings& a, const EpisodeTimings& b) {
  EpisodeTimings d = a;
  d.physics_s -= b.physics_s;
  d.control_s -= b.control_s;
  d.render_s -= b.render_s;
  d.readback_s -= b.readback_s;
  d.frames -= b.frames;
  return d;
}

struct Throughput {
  double steps_per_s;
  std::string id;  // sim/pipe_env_<dynamics>_<H>x<W>
};

// Steps per second (all envs); one env's also gives its BENCH lines per part.
Throughput run(const PipeFollowingConfig& cfg, int num_envs, int steps, int contexts) {
  VectorPipeFollowingEnv vec(cfg, num_envs, 0, contexts);
  std::vector<std::uint8_t> obs;
  std::vector<std::array<double, 2>> actions(static_cast<std::size_t>(num_envs));
  std::uint64_t seed = 0;
  std::vector<std::uint64_t> seeds(static_cast<std::size_t>(num_envs));
  for (auto& s : seeds) s = seed++;
  vec.reset(seeds, &obs);
  EpisodeTimings before;
  for (int i = 0; i < num_envs; ++i) before = sum(before, vec.env(i).episode().timings());
  const auto t0 = Clock::now();
  int resets = 0;
  for (int k = 0; k < steps; ++k) {
    for (int i = 0; i < num_envs; ++i) actions[static_cast<std::size_t>(i)] = vec.env(i).expert_action();
    const auto r = vec.step(actions, &obs);
    std::vector<std::optional<std::uint64_t>> ended(static_cast<std::size_t>(num_envs));
    for (int i = 0; i < num_envs; ++i)
      if (r[static_cast<std::size_t>(i)].terminated || r[static_cast<std::size_t>(i)].truncated) {
        ended[static_cast<std::size_t>(i)] = seed++;
        ++resets;
      }
    if (resets > 0 && std::any_of(ended.begin(), ended.end(), [](const auto& e) { return e.has_value(); }))
      vec.reset_some(ended, &obs);
  }
  const double wall = std::chrono::duration<double>(Clock::now() - t0).count();
  EpisodeTimings after;
  for (int i = 0; i < num_envs; ++i) after = sum(after, vec.env(i).episode().timings());
  const EpisodeTimings d = diff(after, before);
  const double n = static_cast<double>(steps) * num_envs;
  std::printf(
      "%-9s %3dx%-3d envs=%d contexts=%d: %7.1f steps/s  (%.2f ms/step: physics %.2f, mpc+alloc %.2f, render %.2f, "
      "readback %.2f, other %.2f; parts summed over threads; %d resets incl.)\n",
      cfg.env.dynamics.c_str(), vec.env(0).obs_height(), vec.env(0).obs_width(), num_envs, vec.contexts(), n / wall,
      1e3 * wall / n, 1e3 * d.physics_s / n, 1e3 * d.control_s / n, 1e3 * d.render_s / n, 1e3 * d.readback_s / n,
      1e3 * (wall - d.physics_s - d.control_s - d.render_s - d.readback_s) / n, resets);
  const std::string id = "sim/pipe_env_" + cfg.env.dynamics + "_" + std::to_string(vec.env(0).obs_height()) + "x" +
                         std::to_string(vec.env(0).obs_width());
  if (num_envs == 1) {
    unav::common::print_bench(id + "_steps_per_s", n / wall, "steps_per_s");
    unav::common::print_bench(id + "_physics_ms", 1e3 * d.physics_s / n, "ms");
    unav::common::print_bench(id + "_control_ms", 1e3 * d.control_s / n, "ms");
    unav::common::print_bench(id + "_render_ms", 1e3 * d.render_s / n, "ms");
    unav::common::print_bench(id + "_readback_ms", 1e3 * d.readback_s / n, "ms");
  }
  return {n / wall, id};
}

// reset() of one env: a new random scene (geometry upload, the plant rebuilt on its seabed and
// current) and the first observation; median of `n`.
void time_resets(const PipeFollowingConfig& cfg, int n) {
  PipeFollowingEnv env(cfg);
  std::vector<double> ms, plant_ms;
  for (int i = 0; i < n; ++i) {
    const auto t0 = Clock::now();
    env.reset(1000U + static_cast<std::uint64_t>(i));
    env.observe();
    ms.push_back(1e3 * std::chrono::duration<double>(Clock::now() - t0).count());
    const auto t1 = Clock::now();  // the plant alone, as reset() rebuilt it for this scene
    const auto sim = unav::physics::build_simulator(env.episode().setup().scenario, env.episode().world(),
                                                    env.episode().setup().simulator, env.episode().setup().plant);
    plant_ms.push_back(1e3 * std::chrono::duration<double>(Clock::now() - t1).count());
  }
  std::sort(ms.begin(), ms.end());
  std::sort(plant_ms.begin(), plant_ms.end());
  std::printf(
      "reset (new %s scene + first observation): median %.2f ms, max %.2f ms over %d; of which the plant "
      "(seabed grid, current): median %.2f ms\n",
      cfg.env.scenes.c_str(), ms[ms.size() / 2], ms.back(), n, plant_ms[plant_ms.size() / 2]);
  unav::common::print_bench("sim/pipe_env_reset_ms", ms[ms.size() / 2], "ms");
}

}  // namespace

int main(int argc, char** argv) {
  std::string path;
  int steps = 60, num_envs = 4;
  std::vector<std::string> dynamics{"kinematic", "mpc"};
  std::vector<std::pair<std::string, std::string>> overrides;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const bool has_value = i + 1 < argc;
    if (a == "--config" && has_value) {
      path = argv[++i];
    } else if (a == "--steps" && has_value) {
      steps = std::atoi(argv[++i]);
    } else if (a == "--envs" && has_value) {
      num_envs = std::atoi(argv[++i]);
    } else if (a == "--dynamics" && has_value) {
      dynamics = {argv[++i]};
    } else if (a.find('=') != std::string::npos) {
      overrides.emplace_back(a.substr(0, a.find('=')), a.substr(a.find('=') + 1));
    } else {
      std::fprintf(stderr,
                   "usage: bench_pipe_env [--config F] [--steps N] [--envs N] [--dynamics D] [key=value ...]\n");
      return 2;
    }
  }
  if (path.empty()) path = unav::common::find_resource("config/learning/pipe_following.yaml");
  PipeFollowingConfig cfg = load_pipe_following_config(path);
  for (const auto& [k, v] : overrides) apply_override(&cfg, k, v, "command line");
  std::printf("pipe-following env throughput (%s), expert actions, random scenes\n", path.c_str());
  time_resets(cfg, 20);
  for (const auto& dyn : dynamics) {
    cfg.env.dynamics = dyn;
    run(cfg, 1, steps, 1);
    // The vector env on one EGL context, then on two displays where llvmpipe allows (alternated).
    if (num_envs > 1) {
      double sps[2] = {0.0, 0.0};
      std::string id;
      for (int rep = 0; rep < 2; ++rep)
        for (int contexts : {1, 0}) {
          const Throughput t = run(cfg, num_envs, steps, contexts);
          sps[contexts == 1 ? 0 : 1] += 0.5 * t.steps_per_s;
          id = t.id + "_" + std::to_string(num_envs) + "envs";
        }
      unav::common::print_bench(id + "_1ctx_steps_per_s", sps[0], "steps_per_s");
      unav::common::print_bench(id + "_auto_ctx_steps_per_s", sps[1], "steps_per_s");
    }
  }
  return 0;
}
