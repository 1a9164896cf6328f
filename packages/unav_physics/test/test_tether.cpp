// The tether against analytic cases: a heavy cable hanging between two points takes the
// catenary, a taut cable across a uniform current pulls each end with half the Morison drag, a
// cable paid out onto the seabed rests on it, and a vehicle without thrust in a current is held
// within the tether's reach where an untethered one drifts away.
#include "unav_physics/tether.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <memory>

#include "unav_common/errors.hpp"
#include "unav_physics/scenario_builder.hpp"
#include "unav_physics/seabed.hpp"
#include "unav_physics/simulator.hpp"

using unav::physics::EnvironmentParams;
using unav::physics::Tether;
using unav::physics::TetherParams;

namespace {

constexpr double kRho = 1025.0, kG = 9.81;

TetherParams cable(double length, int segments) {
  TetherParams p;
  p.enabled = true;
  p.anchor_position = Eigen::Vector3d::Zero();
  p.length_m = length;
  p.segments = segments;
  return p;
}

// Steps the cable with both ends fixed for `seconds` at 1 kHz.
void settle(Tether& t, const Eigen::Vector3d& end, double seconds, const Eigen::Vector3d& current,
            const unav::physics::Seabed* seabed = nullptr) {
  t.reset(end);
  for (long k = 0; k < std::lround(seconds * 1000.0); ++k) t.step(1e-3, end, Eigen::Vector3d::Zero(), current, seabed);
}

}  // namespace

// A 30 m cable of 0.5 kg/m (7.6 mm: wet weight w = (0.5 - 1025 x 4.54e-5) 9.81 = 4.45 N/m), nearly
// inextensible (E A = 1e6 N: strain ~1e-4), hung between two points 20 m apart at one depth:
// z(x) = a (cosh(h / a) - cosh((x - h) / a)) with 15 = a sinh(10 / a) (a = 6.17 m, sag 10.05 m).
// 30 lumped segments follow it to a few centimetres (the lumped chain is a polygon inscribed in it:
// 9 mm measured); each end carries the horizontal tension w a and half the weight, w x 15 m (its
// half segment included), within 2 %.
TEST(Tether, HeavyCableHangsInACatenary) {
  TetherParams p = cable(30.0, 30);
  p.mass_per_m = 0.5;
  p.axial_stiffness_n = 1e6;
  EnvironmentParams env;
  Tether t(p, env);
  const Eigen::Vector3d end(20.0, 0.0, 0.0);
  settle(t, end, 120.0, Eigen::Vector3d::Zero());
  double lo = 1.0, hi = 100.0;  // 15 = a sinh(10 / a): decreasing in a
  for (int i = 0; i < 200; ++i) {
    const double a = 0.5 * (lo + hi);
    (a * std::sinh(10.0 / a) > 15.0 ? lo : hi) = a;
  }
  const double a = 0.5 * (lo + hi);
  double worst = 0.0;
  for (const auto& n : t.nodes()) {
    const double z = a * (std::cosh(10.0 / a) - std::cosh((n.x() - 10.0) / a));
    worst = std::max(worst, std::abs(n.z() - z));
    EXPECT_NEAR(n.y(), 0.0, 1e-9);
  }
  std::printf("catenary a = %.3f m, sag %.3f m, worst node error %.4f m\n", a, a * (std::cosh(10.0 / a) - 1.0), worst);
  EXPECT_LT(worst, 0.05);
  const double w = (0.5 - kRho * M_PI * 0.0076 * 0.0076 / 4.0) * kG;
  const Eigen::Vector3d f = t.force_on_vehicle_W(end, Eigen::Vector3d::Zero());
  EXPECT_NEAR(-f.x() / (w * a), 1.0, 0.02);    // towards the anchor
  EXPECT_NEAR(f.z() / (w * 15.0), 1.0, 0.02);  // downwards: the cable hangs below
  EXPECT_NEAR(-t.force_on_anchor_W().x() / f.x(), 1.0, 0.02);
}

// A neutrally buoyant cable stretched across a uniform 0.5 m/s cross current: the Morison load
// q = 0.5 rho Cn d U^2 = 1.17 N/m over 20 m is shared by the two ends (11.7 N each), less the
// little the bow (~0.8 m: end angles ~9 deg) turns the cable out of the flow (within 5 %); a
// quarter at 0.25 m/s (drag ~ U^2, within 5 %).
TEST(Tether, TautCableAcrossACurrentPullsWithHalfItsDrag) {
  const auto lateral = [](double u) {
    TetherParams p = cable(20.0, 20);
    p.mass_per_m = kRho * M_PI * p.diameter_m * p.diameter_m / 4.0;  // neutral
    Tether t(p, EnvironmentParams{});
    const Eigen::Vector3d end(20.0, 0.0, 0.0);
    settle(t, end, 120.0, Eigen::Vector3d(0.0, u, 0.0));
    return t.force_on_vehicle_W(end, Eigen::Vector3d::Zero()).y();
  };
  const double q = 0.5 * kRho * 1.2 * 0.0076 * 0.25;
  const double f_half = lateral(0.5), f_quarter = lateral(0.25);
  std::printf("lateral pull %.3f N (half the drag: %.3f N), at 0.25 m/s %.3f N\n", f_half, 0.5 * q * 20.0, f_quarter);
  EXPECT_NEAR(f_half / (0.5 * q * 20.0), 1.0, 0.05);
  EXPECT_NEAR(f_half / f_quarter, 4.0, 0.2);
}

// 30 m paid out from 1 m below the surface to a point on a flat 10 m seabed 10 m away: the slack
// lies on the seabed (a node rests within its penalty's few millimetres), never through it.
TEST(Tether, SlackRestsOnTheSeabed) {
  TetherParams p = cable(30.0, 30);
  p.anchor_position = Eigen::Vector3d(0.0, 0.0, 1.0);
  p.mass_per_m = 0.2;
  Tether t(p, EnvironmentParams{});
  const unav::physics::FlatSeabed bed(10.0);
  settle(t, Eigen::Vector3d(10.0, 0.0, 9.9), 60.0, Eigen::Vector3d::Zero(), &bed);
  int on_bed = 0;
  for (const auto& n : t.nodes()) {
    EXPECT_LT(n.z() + 0.5 * p.diameter_m, 10.0 + 0.01);
    on_bed += n.z() + 0.5 * p.diameter_m > 9.99 ? 1 : 0;
  }
  EXPECT_GE(on_bed, 5);
}

TEST(Tether, ACableShorterThanTheDistanceIsRefused) {
  Tether t(cable(5.0, 10), EnvironmentParams{});
  try {
    t.reset(Eigen::Vector3d(10.0, 0.0, 0.0));
    FAIL() << "a 5 m cable reached 10 m";
  } catch (const unav::ConfigError& e) {
    EXPECT_EQ(e.key(), "length_m");
  }
  EXPECT_THROW(t.set_length(0.0), unav::ConfigError);
}

// The BlueROV2 Heavy without thrust in a 0.3 m/s current: untethered it drifts with the water
// (about U t = 18 m in a minute); on a 10 m tether from a point 5 m upstream it is held within the
// cable's reach (10 m plus its stretch), and the tether pulls it upstream.
TEST(Tether, AVehicleWithoutThrustIsHeldWithinTheTethersReach) {
  const auto drift = [](bool tethered) {
    unav::physics::VehicleParams v = unav::physics::bluerov2_heavy_params();
    v.tether = cable(10.0, 10);
    v.tether.enabled = tethered;
    v.tether.anchor_position = Eigen::Vector3d(-5.0, 0.0, 5.0);
    unav::physics::SimulatorOptions o;
    o.command_timeout = 0.0;
    unav::physics::RigidBodyState x0;
    x0.p_WB_W = Eigen::Vector3d(0.0, 0.0, 5.0);
    unav::physics::Simulator sim(v, o, std::make_unique<unav::physics::ConstantCurrent>(Eigen::Vector3d(0.3, 0.0, 0.0)),
                                 nullptr, x0);
    sim.advance_to(60.0);
    if (tethered) {
      EXPECT_LT(sim.tether_force_W().x(), -1.0);  // upstream
    }
    return (sim.state().p_WB_W - Eigen::Vector3d(-5.0, 0.0, 5.0)).norm();
  };
  const double free = drift(false), held = drift(true);
  std::printf("after 60 s: untethered %.2f m from the anchor, tethered %.2f m\n", free, held);
  EXPECT_GT(free, 15.0);
  EXPECT_LT(held, 10.5);
  EXPECT_GT(held, 9.0);  // at the end of its reach, the cable straight downstream
}

// A scenario's vehicle.set replaces vehicle-file keys under the file's own rules: the tether
// enabled and paid out to 40 m; a bad value is named with the file, the overrides and the key.
TEST(Tether, AScenarioSetsTheVehiclesTether) {
  unav::scene::Scenario sc;
  sc.vehicle.model = std::string(UNAV_CONFIG_DIR) + "/vehicles/bluerov2_heavy.yaml";
  sc.vehicle.set = {"tether.enabled=true", "tether.length_m=40"};
  const unav::physics::VehicleParams v = unav::physics::scenario_vehicle(sc);
  EXPECT_TRUE(v.tether.enabled);
  EXPECT_EQ(v.tether.length_m, 40.0);
  sc.vehicle.set = {"tether.length_m=-1"};
  try {
    (void)unav::physics::scenario_vehicle(sc);
    FAIL() << "a negative tether length accepted";
  } catch (const unav::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("bluerov2_heavy.yaml (vehicle.set: tether.length_m=-1): tether.length_m = -1"),
              std::string::npos)
        << e.what();
  }
}
