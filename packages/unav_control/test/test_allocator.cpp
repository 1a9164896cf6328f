// Allocator: exact reproduction, direction-preserving saturation, redistribution, failures,
// asymmetric thrust, the wrench box, bad input.
#include <gtest/gtest.h>

#include <random>

#include "unav_control/allocator.hpp"

namespace unav::control {
namespace {

// Wrench errors: the allocation is a handful of 6x8 products on values <= ~200 N, so double
// round-off is ~1e-13 N; 1e-9 (the requirement) leaves four orders of margin.
constexpr double kExactTol = 1e-9;

std::vector<physics::ThrusterParams> heavy() { return physics::bluerov2_heavy_params().thrusters; }

Vector6d random_direction(std::mt19937_64& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  Vector6d v;
  for (int j = 0; j < 6; ++j) v(j) = n(rng);
  return v.normalized();
}

TEST(Allocator, MatrixMatchesPhysicsAndMaxThrust) {
  const Allocator a(heavy());
  EXPECT_EQ(a.num_thrusters(), 8);
  // T200 defaults: C_T rho w_max^2 D^4 = 0.344 * 1025 * 58.33^2 * 0.076^4 ~ 40 N.
  EXPECT_NEAR(a.max_forward_thrust()(0), 0.344 * 1025 * 58.33 * 58.33 * std::pow(0.076, 4), 1e-9);
  // Column of T5 (vertical, n = -z at (0.12, 0.218, 0)): [0 0 -1; r x n = (-0.218, 0.12, 0)].
  Vector6d c5;
  c5 << 0, 0, -1, -0.218, 0.12, 0;
  EXPECT_LT((a.thruster_matrix().col(4) - c5).norm(), 1e-12);
}

TEST(Allocator, ReproducesFeasibleWrenchesExactly) {
  for (AllocationMode mode : {AllocationMode::kPseudoInverse, AllocationMode::kRedistributed}) {
    AllocatorOptions o;
    o.mode = mode;
    const Allocator a(heavy(), o);
    std::mt19937_64 rng(1);
    std::uniform_real_distribution<double> mag(0.0, 1.0);
    ThrusterVector u;
    for (int i = 0; i < 500; ++i) {
      // A random direction, shrunk to what the thrusters can do: feasible by construction.
      Vector6d tau = 150.0 * mag(rng) * random_direction(rng);
      AllocatorOptions po;
      po.mode = AllocationMode::kPseudoInverse;
      const AllocationSummary probe = Allocator(heavy(), po).Allocate(tau, &u);
      tau = 0.999 * probe.achieved;  // strictly inside: at the edge round-off may flip a thruster to 1 + 1e-16
      const AllocationSummary s = a.Allocate(tau, &u);
      ASSERT_EQ(s.status, AllocationStatus::kExact) << to_string(s.status);
      EXPECT_LE(u.cwiseAbs().maxCoeff(), 1.0);
      EXPECT_LT((a.WrenchFromCommand(u) - tau).norm(), kExactTol);
      EXPECT_LT((a.thruster_matrix() * (u.array() * a.max_forward_thrust().array()).matrix() - tau).norm(),
                kExactTol);  // symmetric thrusters: T = u T_max
    }
  }
}

TEST(Allocator, SaturatedWrenchKeepsItsDirection) {
  AllocatorOptions o;
  o.mode = AllocationMode::kPseudoInverse;
  const Allocator a(heavy(), o);
  std::mt19937_64 rng(2);
  ThrusterVector u;
  for (int i = 0; i < 200; ++i) {
    const Vector6d tau = 1000.0 * random_direction(rng);  // far beyond every axis' reach (~110 N)
    const AllocationSummary s = a.Allocate(tau, &u);
    ASSERT_EQ(s.status, AllocationStatus::kScaled);
    EXPECT_GT(s.scale, 0.0);
    EXPECT_LT(s.scale, 1.0);
    EXPECT_NEAR(u.cwiseAbs().maxCoeff(), 1.0, 1e-12);  // the limiting thruster at full thrust
    EXPECT_LT((s.achieved - s.scale * tau).norm(), kExactTol * 1000.0);  // same direction, scaled
    EXPECT_NEAR(s.achieved.normalized().dot(tau.normalized()), 1.0, 1e-12);
  }
}

TEST(Allocator, RedistributionReachesMoreAndStaysExactOrScaled) {
  AllocatorOptions o;
  o.mode = AllocationMode::kRedistributed;
  const Allocator red(heavy(), o);
  o.mode = AllocationMode::kPseudoInverse;
  const Allocator pinv(heavy(), o);
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> uni(-1.0, 1.0);
  ThrusterVector u, u_ref(8);
  int redistributed = 0, saturating = 0;
  for (int i = 0; i < 500; ++i) {
    for (int k = 0; k < 8; ++k) u_ref(k) = uni(rng);
    const Vector6d tau = pinv.WrenchFromCommand(u_ref);  // feasible: some u in the box makes it
    if (pinv.Allocate(tau, &u).status != AllocationStatus::kScaled) continue;
    ++saturating;
    const AllocationSummary s = red.Allocate(tau, &u);
    EXPECT_LE(u.cwiseAbs().maxCoeff(), 1.0);
    if (s.status == AllocationStatus::kRedistributed) {
      ++redistributed;
      EXPECT_LT((red.WrenchFromCommand(u) - tau).norm(), kExactTol);
      EXPECT_GE(s.saturated, 1);
    } else {
      ASSERT_EQ(s.status, AllocationStatus::kScaled);  // fallback keeps the direction
      EXPECT_NEAR(s.achieved.normalized().dot(tau.normalized()), 1.0, 1e-12);
    }
  }
  std::printf("pinv saturated on %d feasible wrenches; redistribution reproduced %d exactly\n", saturating,
              redistributed);
  EXPECT_GT(saturating, 50);
  // Iterative redistribution is not guaranteed to find every feasible solution; on this fixed
  // sample (seed 3) it found all of them.
  EXPECT_EQ(redistributed, saturating);
}

TEST(Allocator, OneFailedThrusterStillFeasible) {
  Allocator a(heavy());
  const WrenchBox before = a.achievable_wrench_box();
  ASSERT_TRUE(a.SetThrusterFailed(2, true));  // T3
  EXPECT_TRUE(a.thruster_failed(2));
  const WrenchBox after = a.achievable_wrench_box();
  for (int j = 0; j < 6; ++j) {
    EXPECT_LE(after.upper(j), before.upper(j) + 1e-9);
    EXPECT_GT(after.upper(j), 0.0);  // 7 thrusters still span all six axes
    EXPECT_LT(after.lower(j), 0.0);
  }
  std::mt19937_64 rng(4);
  ThrusterVector u;
  for (int i = 0; i < 200; ++i) {
    const Vector6d d = random_direction(rng);
    // Inside the box by the l1 argument: sum_j |tau_j| / reach_j <= 1 is a convex combination of
    // achievable axis wrenches.
    double l1 = 0.0;
    for (int j = 0; j < 6; ++j) l1 += std::abs(d(j)) / (d(j) > 0 ? after.upper(j) : -after.lower(j));
    const Vector6d tau = 0.99 * d / l1;
    const AllocationSummary s = a.Allocate(tau, &u);
    ASSERT_EQ(s.status, AllocationStatus::kExact);
    EXPECT_EQ(u(2), 0.0);
    EXPECT_LT((a.WrenchFromCommand(u) - tau).norm(), kExactTol);
  }
  EXPECT_FALSE(a.SetThrusterFailed(8, true));
  ASSERT_TRUE(a.SetThrusterFailed(2, false));
  EXPECT_NEAR((a.achievable_wrench_box().upper - before.upper).norm(), 0.0, 1e-9);
}

TEST(Allocator, LosingAllHorizontalThrustersMakesSurgeInfeasible) {
  Allocator a(heavy());
  for (int i = 0; i < 4; ++i) a.SetThrusterFailed(i, true);
  EXPECT_EQ(a.achievable_wrench_box().upper(0), 0.0);
  ThrusterVector u;
  const AllocationSummary s = a.Allocate(Vector6d::Unit(0) * 10.0, &u);
  EXPECT_EQ(s.status, AllocationStatus::kInfeasible);
  EXPECT_TRUE(u.allFinite());
  EXPECT_EQ(u.head<4>().cwiseAbs().maxCoeff(), 0.0);
  // Heave is still exact with the verticals.
  EXPECT_EQ(a.Allocate(Vector6d::Unit(2) * 20.0, &u).status, AllocationStatus::kExact);
}

TEST(Allocator, AsymmetricReverseThrust) {
  auto t = heavy();
  for (auto& th : t) th.C_T_reverse = 0.344 * 40.2 / 51.5;  // T200 at 16 V: reverse 78% of forward
  const Allocator a(t);
  const WrenchBox box = a.achievable_wrench_box();
  // Verticals push up (-z) with forward thrust: upward reach (lower(2)) is 4 T_fwd, downward 4 T_rev.
  EXPECT_NEAR(-box.lower(2), 4.0 * a.max_forward_thrust()(4), 1e-6);
  EXPECT_NEAR(box.upper(2), 4.0 * a.max_reverse_thrust()(4), 1e-6);
  ThrusterVector u;
  const Vector6d down = Vector6d::Unit(2) * 0.999 * box.upper(2);  // verticals at 99.9% reverse
  const AllocationSummary s = a.Allocate(down, &u);
  EXPECT_EQ(s.status, AllocationStatus::kExact);
  EXPECT_NEAR(u(4), -0.999, 1e-12);
  EXPECT_LT((s.achieved - down).norm(), kExactTol);
}

TEST(Allocator, BoxEdgesAreExactlyAchievable) {
  const Allocator a(heavy());
  const WrenchBox box = a.achievable_wrench_box();
  ThrusterVector u;
  for (int j = 0; j < 6; ++j) {
    EXPECT_NE(a.Allocate(Vector6d::Unit(j) * box.upper(j), &u).status, AllocationStatus::kScaled);
    EXPECT_NE(a.Allocate(Vector6d::Unit(j) * box.lower(j), &u).status, AllocationStatus::kScaled);
    AllocatorOptions o;
    o.mode = AllocationMode::kPseudoInverse;
    EXPECT_EQ(Allocator(heavy(), o).Allocate(Vector6d::Unit(j) * box.upper(j) * 1.01, &u).status,
              AllocationStatus::kScaled);
  }
  // Surge reach: 4 thrusters at 45 deg, 4 * 40 N * cos 45 = 113 N (the pitch moment of the low
  // horizontal thrusters is cancelled by the verticals, which are not the limit).
  EXPECT_NEAR(box.upper(0), 4.0 * a.max_forward_thrust()(0) * std::sqrt(0.5), 1e-6);
}

TEST(Allocator, BadInput) {
  const Allocator a(heavy());
  ThrusterVector u;
  Vector6d tau = Vector6d::Zero();
  tau(3) = std::numeric_limits<double>::quiet_NaN();
  const AllocationSummary s = a.Allocate(tau, &u);
  EXPECT_EQ(s.status, AllocationStatus::kInvalidInput);
  EXPECT_EQ(u.size(), 8);
  EXPECT_EQ(u.cwiseAbs().maxCoeff(), 0.0);

  AllocatorOptions o;
  o.thruster_weights = {1, 1, 1, -2, 1, 1, 1, 1};
  std::string msg;
  EXPECT_FALSE(o.IsValid(&msg));
  EXPECT_NE(msg.find("thruster_weights[3]"), std::string::npos) << msg;
  EXPECT_NE(msg.find("-2"), std::string::npos) << msg;
  EXPECT_THROW(Allocator(heavy(), o), physics::ConfigError);
  o.thruster_weights = {1, 2};
  try {
    Allocator bad(heavy(), o);
    FAIL();
  } catch (const physics::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("|weights| = 2, thrusters = 8"), std::string::npos) << e.what();
  }
  EXPECT_THROW(Allocator(std::vector<physics::ThrusterParams>{}), physics::ConfigError);
}

TEST(Allocator, WeightsShiftEffort) {
  AllocatorOptions o;
  o.thruster_weights = {10, 1, 1, 1, 1, 1, 1, 1};  // T1 expensive
  const Allocator w(heavy(), o);
  const Allocator plain(heavy());
  ThrusterVector u1, u2;
  const Vector6d tau = (Vector6d() << 30, 0, 0, 0, 0, 0).finished();
  w.Allocate(tau, &u1);
  plain.Allocate(tau, &u2);
  EXPECT_LT(std::abs(u1(0)), std::abs(u2(0)));
  EXPECT_LT((w.WrenchFromCommand(u1) - tau).norm(), kExactTol);
}

}  // namespace
}  // namespace unav::control
