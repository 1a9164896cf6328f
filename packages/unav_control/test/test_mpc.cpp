// MPC: option validation (configure time, throws with the values), run-time bad input (status +
// safe wrench, never NaN), bounds, hover and move blocking.
#include <gtest/gtest.h>

#include <limits>

#include "unav_control/mpc.hpp"

namespace unav::control {
namespace {

const double kNaN = std::numeric_limits<double>::quiet_NaN();

MpcOptions options() {
  MpcOptions o;
  o.input_bounds = Allocator(physics::bluerov2_heavy_params().thrusters).achievable_wrench_box().Scaled(0.9);
  return o;
}

physics::RigidBodyState at(const Eigen::Vector3d& p) {
  physics::RigidBodyState x;
  x.p_WB_W = p;
  return x;
}

std::string invalid_message(const MpcOptions& o) {
  std::string msg;
  EXPECT_FALSE(o.IsValid(&msg));
  EXPECT_THROW(Mpc(physics::bluerov2_heavy_params(), o), physics::ConfigError);
  return msg;
}

TEST(MpcOptions, DefaultsAreValid) {
  std::string msg;
  EXPECT_TRUE(options().IsValid(&msg)) << msg;
}

TEST(MpcOptions, BadValuesNamed) {
  MpcOptions o = options();
  o.horizon_steps = 0;
  EXPECT_NE(invalid_message(o).find("horizon_steps must be >= 1 (got 0)"), std::string::npos);

  o = options();
  o.control_blocks = 30;
  EXPECT_NE(invalid_message(o).find("control_blocks"), std::string::npos);

  o = options();
  o.state_weights(4) = -1.0;  // not positive semi-definite
  std::string m = invalid_message(o);
  EXPECT_NE(m.find("state_weights"), std::string::npos) << m;
  EXPECT_NE(m.find("-1"), std::string::npos) << m;

  o = options();
  o.input_weights(0) = kNaN;
  EXPECT_NE(invalid_message(o).find("input_weights"), std::string::npos);

  o = options();
  o.input_bounds.lower(1) = 10.0;  // lower > upper on sway? upper is ~100: use a crossing pair
  o.input_bounds.upper(1) = 5.0;
  m = invalid_message(o);
  EXPECT_NE(m.find("input_bounds"), std::string::npos) << m;
  EXPECT_NE(m.find("lower = ["), std::string::npos) << m;

  o = options();
  o.dt = 0.0;
  EXPECT_NE(invalid_message(o).find("dt must be"), std::string::npos);
  o = options();
  o.disturbance_gain = 1.5;
  EXPECT_NE(invalid_message(o).find("disturbance_gain"), std::string::npos);
  o = options();
  o.max_iterations = 0;
  EXPECT_NE(invalid_message(o).find("max_iterations"), std::string::npos);
}

TEST(Mpc, HoverAtSetpointNeedsAlmostNothing) {
  Mpc mpc(physics::bluerov2_heavy_params(), options());
  Vector6d w;
  const MpcSummary s = mpc.Solve(at({0, 0, 5}), PoseSetpoint::FromPositionYaw({0, 0, 5}, 0.0), 0.0, &w);
  EXPECT_TRUE(s.ok()) << s.message;
  // Neutral buoyancy with B above G: the level vehicle at rest needs no wrench; solver
  // tolerance leaves a few mN.
  EXPECT_LT(w.norm(), 1e-2);
}

TEST(Mpc, FarSetpointSaturatesWithinBounds) {
  const MpcOptions o = options();
  Mpc mpc(physics::bluerov2_heavy_params(), o);
  Vector6d w;
  const MpcSummary s = mpc.Solve(at({0, 0, 5}), PoseSetpoint::FromPositionYaw({20, -20, 10}, 0.0), 0.0, &w);
  EXPECT_TRUE(s.ok()) << s.message;
  EXPECT_TRUE(o.input_bounds.Contains(w, 1e-9));
  EXPECT_GT(w(0), 0.5 * o.input_bounds.upper(0));  // pushes hard towards north
  EXPECT_LT(w(1), 0.5 * o.input_bounds.lower(1));  // and west
  EXPECT_EQ(mpc.planned_wrenches().size(), 5u);  // move blocking
  EXPECT_EQ(mpc.predicted_states().size(), 20u);
  EXPECT_GT(mpc.predicted_states().back().p_WB_W.x(), 0.5);  // 100 N on ~20 kg for 1 s: ~1 m
  EXPECT_LT(mpc.predicted_states().back().p_WB_W.y(), -0.5);
}

TEST(Mpc, BadRuntimeInputGivesStatusAndSafeWrench) {
  const MpcOptions o = options();
  Mpc mpc(physics::bluerov2_heavy_params(), o);
  Vector6d w = Vector6d::Constant(123.0);
  // No plan yet: the safe wrench is zero.
  PoseSetpoint bad = PoseSetpoint::FromPositionYaw({1, 0, 5}, 0.0);
  bad.p_W.x() = kNaN;
  MpcSummary s = mpc.Solve(at({0, 0, 5}), bad, 0.0, &w);
  EXPECT_EQ(s.status, MpcStatus::kInvalidSetpoint);
  EXPECT_NE(s.message.find("nan"), std::string::npos) << s.message;
  EXPECT_EQ(w, Vector6d::Zero());

  // A good solve, then bad input: the previous plan's input for now, within the bounds.
  const PoseSetpoint good = PoseSetpoint::FromPositionYaw({3, 0, 5}, 0.0);
  ASSERT_TRUE(mpc.Solve(at({0, 0, 5}), good, 0.05, &w).ok());
  const std::vector<Vector6d> plan = mpc.planned_wrenches();
  PoseSetpoint not_unit = good;
  not_unit.q_WB.coeffs() *= 2.0;
  s = mpc.Solve(at({0, 0, 5}), not_unit, 0.10, &w);
  EXPECT_EQ(s.status, MpcStatus::kInvalidSetpoint);
  EXPECT_NE(s.message.find("|q| = 2"), std::string::npos) << s.message;
  EXPECT_TRUE(w.allFinite());
  EXPECT_TRUE(o.input_bounds.Contains(w, 1e-9));
  EXPECT_LT((w - plan[0]).norm(), 1e-12);  // 1 step later, still in the first 4-step block

  physics::RigidBodyState x = at({0, 0, 5});
  x.v_WB_B.y() = std::numeric_limits<double>::infinity();
  s = mpc.Solve(x, good, 0.15, &w);
  EXPECT_EQ(s.status, MpcStatus::kInvalidState);
  EXPECT_TRUE(w.allFinite());
  x = at({0, 0, 5});
  x.q_WB = Eigen::Quaterniond(0.5, 0.0, 0.0, 0.0);
  EXPECT_EQ(mpc.Solve(x, good, 0.20, &w).status, MpcStatus::kInvalidState);
  EXPECT_EQ(mpc.Solve(at({0, 0, 5}), good, kNaN, &w).status, MpcStatus::kInvalidTime);
  EXPECT_TRUE(w.allFinite());
  // And it recovers.
  EXPECT_TRUE(mpc.Solve(at({0, 0, 5}), good, 0.30, &w).ok());
  EXPECT_TRUE(o.input_bounds.Contains(w, 1e-9));
}

TEST(Mpc, WarmStartNeedsFewerIterations) {
  Mpc mpc(physics::bluerov2_heavy_params(), options());
  Vector6d w;
  const PoseSetpoint sp = PoseSetpoint::FromPositionYaw({0.5, 0.3, 5.2}, 0.4);
  const MpcSummary cold = mpc.Solve(at({0, 0, 5}), sp, 0.0, &w);
  const MpcSummary warm = mpc.Solve(at({0, 0, 5}), sp, 0.0, &w);  // same instant: unshifted plan
  EXPECT_LE(warm.iterations, cold.iterations);
  EXPECT_LE(warm.initial_cost, cold.initial_cost);
}

}  // namespace
}  // namespace unav::control
