// In-process closed loop for the tests and the bench: physics Simulator (plant, 1 kHz) <-
// allocator <- MPC (20 Hz, its own model) <- setpoint.
#pragma once

#include <algorithm>
#include <functional>
#include <memory>
#include <vector>

#include "unav_control/allocator.hpp"
#include "unav_control/mpc.hpp"
#include "unav_physics/current.hpp"
#include "unav_physics/simulator.hpp"

namespace unav::control::testing {

struct LoopSample {
  double t;
  physics::RigidBodyState x;
};

struct LoopResult {
  std::vector<LoopSample> samples;  // at the control rate
  double max_abs_u = 0.0;           // over every command sent
  bool wrench_in_box = true;        // every MPC wrench within its bounds (1e-9 slack)
  int solver_failures = 0;
  std::vector<double> solve_ms;
  std::vector<int> iterations;
  const physics::RigidBodyState& final_state() const { return samples.back().x; }
};

struct LoopSetup {
  physics::VehicleParams plant;
  physics::VehicleParams model;
  MpcOptions mpc;              // input_bounds overwritten from the model's allocator box x margin
  double bounds_margin = 0.9;
  Eigen::Vector3d current_W = Eigen::Vector3d::Zero();
  physics::RigidBodyState initial;
  double control_period = 0.05;  // s (20 Hz)
  double physics_dt = 1e-3;      // s (1 kHz)
};

inline LoopResult run_closed_loop(const LoopSetup& s, const std::function<PoseSetpoint(double)>& setpoint,
                                  double duration) {
  physics::SimulatorOptions so;
  so.dt = s.physics_dt;
  physics::Simulator sim(s.plant, so, std::make_unique<physics::ConstantCurrent>(s.current_W), nullptr, s.initial);
  Allocator alloc(s.plant.thrusters);
  MpcOptions mo = s.mpc;
  mo.input_bounds = Allocator(s.model.thrusters).achievable_wrench_box().Scaled(s.bounds_margin);
  Mpc mpc(s.model, mo);
  LoopResult r;
  const int sub = static_cast<int>(std::lround(s.control_period / s.physics_dt));
  ThrusterVector u;
  const int n_ctrl = static_cast<int>(std::lround(duration / s.control_period));
  for (int k = 0; k < n_ctrl; ++k) {
    const double t = sim.time();
    Vector6d w;
    const MpcSummary ms = mpc.Solve(sim.state(), setpoint(t), t, &w);
    if (!ms.ok()) ++r.solver_failures;
    r.solve_ms.push_back(ms.solve_time_ms);
    r.iterations.push_back(ms.iterations);
    if (!mo.input_bounds.Contains(w, 1e-9)) r.wrench_in_box = false;
    alloc.Allocate(w, &u);
    r.max_abs_u = std::max(r.max_abs_u, u.cwiseAbs().maxCoeff());
    sim.set_command(t, u.data(), static_cast<std::size_t>(u.size()));
    for (int i = 0; i < sub; ++i) sim.step();
    r.samples.push_back({sim.time(), sim.state()});
  }
  return r;
}

}  // namespace unav::control::testing
