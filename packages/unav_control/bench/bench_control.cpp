// Timing of the control core, printed: MPC solve time p50/p99 and iterations at the default
// horizon (from config/controllers/mpc.yaml) inside a closed loop (surge + yaw steps, then a
// current), and allocation time per call. Single-threaded (Ceres num_threads = 1).
// Machine-readable: BENCH control/mpc_solve_{p50,p99}_ms, control/mpc_iterations_mean,
// control/mpc_replay_cpu_{p50,p99}_ms, control/allocate_{pseudo_inverse,redistributed}_ns.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <numeric>
#include <random>
#include <vector>

#include "../test/closed_loop.hpp"
#include "unav_common/bench.hpp"
#include "unav_common/resources.hpp"
#include "unav_control/config.hpp"

using namespace unav;
using namespace unav::control;

namespace {
double pct(std::vector<double> v, double p) {
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<std::size_t>(std::lround(p * static_cast<double>(v.size() - 1))))];
}
}  // namespace

int main() {
  const MpcConfig cfg = load_mpc_config(unav::common::find_resource("config/controllers/mpc.yaml"));
  testing::LoopSetup s;
  s.plant = physics::bluerov2_heavy_params();
  s.model = cfg.model;
  s.mpc = cfg.options;
  s.bounds_margin = cfg.bounds_margin;
  s.initial.p_WB_W = Eigen::Vector3d(0, 0, 5);
  std::vector<double> ms;
  std::vector<double> its;
  // Scenario 1: a sequence of steps (surge 1 m, yaw 90 deg, sway/heave, diagonal 2 m).
  auto steps = [](double t) {
    if (t < 6) return PoseSetpoint::FromPositionYaw({1, 0, 5}, 0);
    if (t < 12) return PoseSetpoint::FromPositionYaw({1, 0, 5}, M_PI / 2);
    if (t < 18) return PoseSetpoint::FromPositionYaw({1, 1, 5.5}, M_PI / 2);
    return PoseSetpoint::FromPositionYaw({3, -1, 4.5}, -M_PI / 4);
  };
  auto r1 = testing::run_closed_loop(s, steps, 25.0);
  // Scenario 2: station keeping in a 0.2 m/s current.
  s.current_W = Eigen::Vector3d(0.2 * std::cos(0.5), 0.2 * std::sin(0.5), 0);
  auto r2 = testing::run_closed_loop(
      s,
      [](double) {
        return PoseSetpoint::FromPositionYaw({0, 0, 5}, 0);
      },
      15.0);
  for (auto* r : {&r1, &r2}) {
    ms.insert(ms.end(), r->solve_ms.begin(), r->solve_ms.end());
    for (int i : r->iterations) its.push_back(i);
  }
  std::printf("MPC (N=%d, dt=%.3f s, %d blocks, max_iterations=%d), %zu closed-loop solves on one core:\n",
              cfg.options.horizon_steps, cfg.options.dt, cfg.options.control_blocks, cfg.options.max_iterations,
              ms.size());
  std::printf("  solve time  p50 %.3f ms  p90 %.3f ms  p99 %.3f ms  max %.3f ms\n", pct(ms, 0.5), pct(ms, 0.9),
              pct(ms, 0.99), pct(ms, 1.0));
  std::printf("  iterations  p50 %.0f  p99 %.0f  max %.0f  mean %.2f\n", pct(its, 0.5), pct(its, 0.99), pct(its, 1.0),
              std::accumulate(its.begin(), its.end(), 0.0) / its.size());
  std::printf("  solver failures: %d\n", r1.solver_failures + r2.solver_failures);
  common::print_bench("control/mpc_solve_p50_ms", pct(ms, 0.5), "ms");
  common::print_bench("control/mpc_solve_p99_ms", pct(ms, 0.99), "ms");
  common::print_bench("control/mpc_iterations_mean", std::accumulate(its.begin(), its.end(), 0.0) / its.size(),
                      "iterations");
  // The machine is shared (2 cores): wall time includes preemption. Replay the same states and
  // setpoints into a fresh MPC and time each solve in thread CPU time as well.
  {
    MpcOptions mo = cfg.options;
    mo.input_bounds = Allocator(cfg.model.thrusters).achievable_wrench_box().Scaled(cfg.bounds_margin);
    Mpc mpc(cfg.model, mo);
    std::vector<double> cpu, wall;
    for (const auto& smp : r1.samples) {
      Vector6d w;
      timespec a{}, b{};
      clock_gettime(CLOCK_THREAD_CPUTIME_ID, &a);
      const MpcSummary sm = mpc.Solve(smp.x, steps(smp.t), smp.t, &w);
      clock_gettime(CLOCK_THREAD_CPUTIME_ID, &b);
      cpu.push_back((b.tv_sec - a.tv_sec) * 1e3 + (b.tv_nsec - a.tv_nsec) * 1e-6);
      wall.push_back(sm.solve_time_ms);
    }
    std::printf("  replay of %zu solves: wall p50 %.3f / p99 %.3f ms, thread CPU p50 %.3f / p99 %.3f / max %.3f ms\n",
                cpu.size(), pct(wall, 0.5), pct(wall, 0.99), pct(cpu, 0.5), pct(cpu, 0.99), pct(cpu, 1.0));
    common::print_bench("control/mpc_replay_cpu_p50_ms", pct(cpu, 0.5), "ms");
    common::print_bench("control/mpc_replay_cpu_p99_ms", pct(cpu, 0.99), "ms");
  }

  // Allocation: random wrenches over twice the achievable box (about half saturate).
  const AllocatorConfig acfg = load_allocator_config(unav::common::find_resource("config/controllers/allocator.yaml"));
  for (AllocationMode mode : {AllocationMode::kPseudoInverse, AllocationMode::kRedistributed}) {
    AllocatorOptions ao = acfg.options;
    ao.mode = mode;
    Allocator a(acfg.vehicle.thrusters, ao);
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> uni(-1.0, 1.0);
    const WrenchBox& box = a.achievable_wrench_box();
    std::vector<Vector6d> ws(4096);
    for (auto& w : ws) {
      for (int j = 0; j < 6; ++j) w(j) = uni(rng) * 2.0 * box.upper(j) / 6.0 * 3.0;
    }
    ThrusterVector u;
    double sink = 0.0;
    const int reps = 50;
    const auto t0 = std::chrono::steady_clock::now();
    for (int r = 0; r < reps; ++r) {
      for (const auto& w : ws) sink += a.Allocate(w, &u).scale + u(0);
    }
    const double ns = std::chrono::duration<double, std::nano>(std::chrono::steady_clock::now() - t0).count() /
                      (reps * static_cast<double>(ws.size()));
    std::printf("Allocation (%s, %d thrusters): %.0f ns per call (checksum %.3f)\n", to_string(mode), a.num_thrusters(),
                ns, sink);
    common::print_bench(std::string("control/allocate_") + to_string(mode) + "_ns", ns, "ns");
  }
  return 0;
}
