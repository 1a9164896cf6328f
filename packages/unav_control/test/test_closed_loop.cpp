// Closed loop in process: physics Simulator as the plant (1 kHz, thruster lag, the paper's
// BlueROV2 Heavy), allocator, MPC at 20 Hz on its own model loaded from config/.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "closed_loop.hpp"
#include "unav_control/config.hpp"
#include "unav_control/waypoint_follower.hpp"

namespace unav::control {
namespace {

using testing::LoopResult;
using testing::LoopSetup;

LoopSetup default_setup() {
  const MpcConfig cfg = load_mpc_config(std::string(UNAV_CONFIG_DIR) + "/controllers/mpc.yaml");
  LoopSetup s;
  s.plant = physics::bluerov2_heavy_params();
  s.model = cfg.model;
  s.mpc = cfg.options;
  s.bounds_margin = cfg.bounds_margin;
  s.initial.p_WB_W = Eigen::Vector3d(0.0, 0.0, 5.0);
  return s;
}

/// Last time |e(t)| exceeded `band` (0 if never): the settling time for that band.
template <typename F>
double settling_time(const LoopResult& r, F error, double band) {
  double t_settle = 0.0;
  for (const auto& s : r.samples) {
    if (std::abs(error(s.x)) > band) t_settle = s.t;
  }
  return t_settle;
}

void expect_within_bounds(const LoopResult& r) {
  EXPECT_LE(r.max_abs_u, 1.0);  // the allocator never commands beyond full thrust
  EXPECT_TRUE(r.wrench_in_box);
  EXPECT_EQ(r.solver_failures, 0);
}

TEST(ClosedLoop, SurgeStepOneMetre) {
  const LoopSetup s = default_setup();
  const auto r = run_closed_loop(s, [](double) { return PoseSetpoint::FromPositionYaw({1.0, 0.0, 5.0}, 0.0); }, 8.0);
  double x_max = 0.0;
  for (const auto& smp : r.samples) x_max = std::max(x_max, smp.x.p_WB_W.x());
  // Settling: within 2% of the 1 m step (2 cm) from 5 s on, and the other axes quiet.
  const double ts = settling_time(r, [](const physics::RigidBodyState& x) { return x.p_WB_W.x() - 1.0; }, 0.02);
  std::printf("surge step: overshoot %.2f%%, 2%% settling %.2f s, final x %.4f m\n", 100.0 * (x_max - 1.0), ts,
              r.final_state().p_WB_W.x());
  EXPECT_LT(x_max, 1.05);  // < 5% overshoot
  EXPECT_LE(ts, 5.0);
  EXPECT_NEAR(r.final_state().p_WB_W.y(), 0.0, 0.02);
  EXPECT_NEAR(r.final_state().p_WB_W.z(), 5.0, 0.02);
  expect_within_bounds(r);
}

TEST(ClosedLoop, YawStepNinetyDegrees) {
  const LoopSetup s = default_setup();
  const auto r = run_closed_loop(s, [](double) { return PoseSetpoint::FromPositionYaw({0.0, 0.0, 5.0}, M_PI / 2); }, 8.0);
  auto yaw_err = [](const physics::RigidBodyState& x) {
    return std::remainder(physics::roll_pitch_yaw(x.q_WB).z() - M_PI / 2, 2 * M_PI);
  };
  double overshoot = 0.0;
  for (const auto& smp : r.samples) overshoot = std::max(overshoot, -yaw_err(smp.x) < 0 ? yaw_err(smp.x) : 0.0);
  // 2% of 90 deg = 1.8 deg band.
  const double ts = settling_time(r, yaw_err, 0.02 * M_PI / 2);
  std::printf("yaw step: overshoot %.2f deg, 2%% settling %.2f s\n", overshoot * 180 / M_PI, ts);
  EXPECT_LE(ts, 6.0);
  EXPECT_LT(overshoot, 0.05 * M_PI / 2);
  EXPECT_LT(r.final_state().p_WB_W.head<2>().norm(), 0.05);
  expect_within_bounds(r);
}

TEST(ClosedLoop, ConstantCurrentNoSteadyStateError) {
  LoopSetup s = default_setup();
  s.current_W = Eigen::Vector3d(0.2 * std::cos(0.5), 0.2 * std::sin(0.5), 0.0);  // 0.2 m/s, 29 deg off the bow
  const auto r = run_closed_loop(s, [](double) { return PoseSetpoint::FromPositionYaw({0.0, 0.0, 5.0}, 0.0); }, 25.0);
  // Steady state: the last 5 s. Without the disturbance estimate the drag (~8 N) against the
  // proportional weights would leave centimetres of offset.
  double e_max = 0.0;
  for (const auto& smp : r.samples) {
    if (smp.t >= 20.0) e_max = std::max(e_max, (smp.x.p_WB_W - Eigen::Vector3d(0, 0, 5)).norm());
  }
  std::printf("current 0.2 m/s: steady-state position error %.4f m\n", e_max);
  EXPECT_LT(e_max, 0.02);
  expect_within_bounds(r);
}

TEST(ClosedLoop, ModelMismatchHeavierModel) {
  LoopSetup s = default_setup();
  s.model.mass *= 1.2;  // MPC believes the vehicle is 20% heavier than the plant
  s.current_W = Eigen::Vector3d(0.2, 0.0, 0.0);
  const auto r = run_closed_loop(s, [](double) { return PoseSetpoint::FromPositionYaw({1.0, 0.0, 5.0}, 0.0); }, 15.0);
  const double ts = settling_time(r, [](const physics::RigidBodyState& x) { return x.p_WB_W.x() - 1.0; }, 0.02);
  std::printf("20%% heavier model + current: 2%% settling %.2f s, final error %.4f m\n", ts,
              (r.final_state().p_WB_W - Eigen::Vector3d(1, 0, 5)).norm());
  EXPECT_LT((r.final_state().p_WB_W - Eigen::Vector3d(1, 0, 5)).norm(), 0.02);
  expect_within_bounds(r);
}

TEST(ClosedLoop, FollowsPipelinePathAboveSeabed) {
  LoopSetup s = default_setup();
  // Pipeline on a 10 m seabed: 4 m north, then 3 m east; inspect 1.5 m above it.
  const auto path = path_above({{0, 0, 10}, {2, 0, 10}, {4, 0, 10}, {4, 1.5, 10}, {4, 3, 10}}, 1.5);
  s.initial.p_WB_W = Eigen::Vector3d(0, 0, 8.5);
  WaypointFollowerOptions wo;
  wo.acceptance_radius = 0.3;
  WaypointFollower follower(wo);
  ASSERT_TRUE(follower.SetPath(path));
  double t_finished = -1.0;
  // The follower needs the state, so this loop is written out (same rates as run_closed_loop).
  physics::SimulatorOptions so;
  physics::Simulator sim(s.plant, so, nullptr, nullptr, s.initial);
  Allocator alloc(s.plant.thrusters);
  MpcOptions mo = s.mpc;
  mo.input_bounds = Allocator(s.model.thrusters).achievable_wrench_box().Scaled(s.bounds_margin);
  Mpc mpc(s.model, mo);
  ThrusterVector u;
  double max_depth_error = 0.0;
  for (int k = 0; k < 600 && t_finished < 0.0; ++k) {  // at most 30 s
    const WaypointUpdate wu = follower.Update(sim.state().p_WB_W);
    if (wu.finished) t_finished = sim.time();
    Vector6d w;
    ASSERT_TRUE(mpc.Solve(sim.state(), wu.setpoint, sim.time(), &w).ok());
    alloc.Allocate(w, &u);
    sim.set_command(sim.time(), u.data(), static_cast<std::size_t>(u.size()));
    for (int i = 0; i < 50; ++i) sim.step();
    max_depth_error = std::max(max_depth_error, std::abs(sim.state().p_WB_W.z() - 8.5));
  }
  std::printf("pipeline path (7 m, 5 waypoints): finished after %.2f s, max depth error %.3f m\n", t_finished,
              max_depth_error);
  EXPECT_GT(t_finished, 0.0);
  EXPECT_LT(t_finished, 30.0);
  EXPECT_LT(max_depth_error, 0.1);  // stays 1.5 m above the pipe within 10 cm
}

}  // namespace
}  // namespace unav::control
