// Sensors read what physics predicts; seabed and surface behaviour.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "unav_physics/simulator.hpp"

namespace up = unav::physics;

namespace {

constexpr double kPi = 3.141592653589793;

up::VehicleParams with_all_sensors(double sigma_scale = 1.0) {
  up::VehicleParams v = up::bluerov2_heavy_params();
  auto& s = v.sensors;
  s.seed = 5;
  s.imu.enabled = s.pressure.enabled = s.dvl.enabled = s.altimeter.enabled = true;
  s.magnetometer.enabled = s.gps.enabled = true;
  s.imu.accel.noise_stddev = 0.02 * sigma_scale;  // bias walks off: "at rest" means truth + white noise
  s.imu.gyro.noise_stddev = 0.002 * sigma_scale;
  s.pressure.pressure.noise_stddev = 20.0 * sigma_scale;
  s.dvl.velocity.noise_stddev = 0.01 * sigma_scale;
  s.altimeter.range.noise_stddev = 0.02 * sigma_scale;
  s.magnetometer.field.noise_stddev = 2e-7 * sigma_scale;
  s.gps.horizontal.noise_stddev = 1.5 * sigma_scale;
  s.gps.vertical.noise_stddev = 3.0 * sigma_scale;
  return v;
}

up::RigidBodyState at(double z, double roll = 0, double pitch = 0, double yaw = 0) {
  up::RigidBodyState x;
  x.p_WB_W = Eigen::Vector3d(0, 0, z);
  x.q_WB = up::quaternion_from_rpy(roll, pitch, yaw);
  return x;
}

up::SimulatorOptions opts() {
  up::SimulatorOptions o;
  o.command_timeout = 0.0;
  return o;
}

TEST(Sensors, AtRestImuAndPressureReadWhatPhysicsPredicts) {
  // Neutral, level, at rest at 10 m: specific force = -g in body FRD = (0, 0, -9.81), zero rate,
  // p = p_atm + rho g z. Means over N samples must lie within 5 sigma / sqrt(N) (white noise only).
  up::Simulator sim(with_all_sensors(), opts(), nullptr, nullptr, at(10.0));
  Eigen::Vector3d f_sum = Eigen::Vector3d::Zero(), w_sum = Eigen::Vector3d::Zero();
  double p_sum = 0, d_sum = 0;
  int n_imu = 0, n_p = 0;
  std::uint64_t imu_seq = sim.sensors().imu.seq, p_seq = sim.sensors().pressure.seq;
  while (sim.time() < 5.0) {
    sim.step();
    const auto& r = sim.sensors();
    if (r.imu.seq != imu_seq) {
      imu_seq = r.imu.seq;
      ASSERT_TRUE(r.imu.valid);
      f_sum += r.imu.specific_force_B;
      w_sum += r.imu.angular_rate_B;
      ++n_imu;
    }
    if (r.pressure.seq != p_seq) {
      p_seq = r.pressure.seq;
      p_sum += r.pressure.pressure_pa;
      d_sum += r.pressure.depth_m;
      ++n_p;
    }
  }
  EXPECT_EQ(n_imu, 1000);  // 200 Hz for 5 s
  EXPECT_EQ(n_p, 250);     // 50 Hz
  EXPECT_LT((f_sum / n_imu - Eigen::Vector3d(0, 0, -9.81)).cwiseAbs().maxCoeff(), 5 * 0.02 / std::sqrt(n_imu));
  EXPECT_LT((w_sum / n_imu).cwiseAbs().maxCoeff(), 5 * 0.002 / std::sqrt(n_imu));
  const double p_expected = 101325.0 + 1025.0 * 9.81 * 10.0;
  EXPECT_NEAR(p_sum / n_p, p_expected, 5 * 20.0 / std::sqrt(n_p));
  EXPECT_NEAR(d_sum / n_p, 10.0, 5 * 20.0 / (1025.0 * 9.81) / std::sqrt(n_p));
}

TEST(Sensors, ImuAndMagnetometerRotateWithTheBody) {
  // Noise-free SensorSuite on hand-made states: f_B = -R^T g_W, m_B = R^T m_W.
  up::VehicleParams v = with_all_sensors(0.0);
  const up::EnvironmentParams env;
  up::SensorSuite s(v.sensors, env);
  const up::RigidBodyState x = at(5.0, 0.0, 30.0 * kPi / 180.0, 90.0 * kPi / 180.0);
  s.update(0.0, x, up::Vector6d::Zero(), nullptr);
  const Eigen::Matrix3d R = x.q_WB.toRotationMatrix();
  EXPECT_LT((s.readings().imu.specific_force_B - R.transpose() * Eigen::Vector3d(0, 0, -9.81)).norm(), 1e-12);
  // pitch 30 deg nose up: gravity has a forward component in body axes: f_x = +g sin 30.
  EXPECT_NEAR(s.readings().imu.specific_force_B.x(), 9.81 * 0.5, 1e-12);
  EXPECT_LT((s.readings().magnetometer.field_B - R.transpose() * env.magnetic_field_W).norm(), 1e-18);
  const up::RigidBodyState east = at(5.0, 0.0, 0.0, kPi / 2);  // nose east: north is to the left (-y)
  s.update(1.0, east, up::Vector6d::Zero(), nullptr);
  EXPECT_NEAR(s.readings().magnetometer.field_B.y(), -env.magnetic_field_W.x(), 1e-12);
}

TEST(Sensors, DvlAndAltimeterValidOnlyWithinRange) {
  up::VehicleParams v = with_all_sensors(0.0);
  v.sensors.dvl.max_altitude = 50.0;
  v.sensors.altimeter.max_range = 50.0;
  up::SensorSuite s(v.sensors, up::EnvironmentParams{});
  const up::FlatSeabed floor(100.0);
  up::RigidBodyState x = at(10.0);  // 90 m above the floor: out of range
  x.v_WB_B = Eigen::Vector3d(0.3, -0.1, 0.05);
  s.update(0.0, x, up::Vector6d::Zero(), &floor);
  EXPECT_FALSE(s.readings().dvl.valid);
  EXPECT_FALSE(s.readings().altimeter.valid);
  x = at(80.0, 20.0 * kPi / 180.0);  // 20 m above, rolled 20 deg
  x.v_WB_B = Eigen::Vector3d(0.3, -0.1, 0.05);
  s.update(1.0, x, up::Vector6d::Zero(), &floor);
  EXPECT_TRUE(s.readings().dvl.valid);
  EXPECT_LT((s.readings().dvl.velocity_B - x.v_WB_B).norm(), 1e-12);
  EXPECT_NEAR(s.readings().dvl.altitude_m, 20.0, 1e-12);
  ASSERT_TRUE(s.readings().altimeter.valid);
  EXPECT_NEAR(s.readings().altimeter.range_m, 20.0 / std::cos(20.0 * kPi / 180.0), 1e-9);
  s.update(2.0, x, up::Vector6d::Zero(), nullptr);  // no seabed: nothing to measure
  EXPECT_FALSE(s.readings().dvl.valid);
}

namespace {
// depth = d0 + a x + b y (NED), a tilted plane.
class PlaneSeabed : public up::Seabed {
 public:
  PlaneSeabed(double d0, double a, double b) : d0_(d0), a_(a), b_(b) {}
  double depth_at(double x, double y) const override { return d0_ + a_ * x + b_ * y; }

 private:
  double d0_, a_, b_;
};
}  // namespace

// Four Janus beams (22.5 deg) over a seabed sloping 0.2 along north: each beam's slant range is
// the ray-plane intersection, s = (10 - 5) / (d_z - 0.2 d_x); the velocity from the four beam
// projections is the body velocity (no noise: to rounding).
TEST(Sensors, DvlBeamsOnATiltedSeabed) {
  up::VehicleParams v = with_all_sensors(0.0);
  ASSERT_EQ(v.sensors.dvl.beams, 4);
  up::SensorSuite s(v.sensors, up::EnvironmentParams{});
  const PlaneSeabed slope(10.0, 0.2, 0.0);
  up::RigidBodyState x = at(5.0);
  x.v_WB_B = Eigen::Vector3d(0.5, 0.2, 0.1);
  s.update(0.0, x, up::Vector6d::Zero(), &slope);
  const auto& r = s.readings().dvl;
  ASSERT_TRUE(r.valid);
  EXPECT_EQ(r.locked_beams, 4);
  double vertical = 0.0;
  for (int i = 0; i < 4; ++i) {
    const Eigen::Vector3d d = up::dvl_beam_B(i, 22.5);
    const double expected = 5.0 / (d.z() - 0.2 * d.x());
    EXPECT_NEAR(r.beam_range_m[static_cast<std::size_t>(i)], expected, 1e-9) << "beam " << i;
    EXPECT_NEAR(r.beam_velocity[static_cast<std::size_t>(i)], d.dot(x.v_WB_B), 1e-15) << "beam " << i;
    vertical += expected * d.z();
  }
  EXPECT_LT((r.velocity_B - x.v_WB_B).norm(), 1e-12);
  EXPECT_NEAR(r.altitude_m, vertical / 4.0, 1e-9);
}

// A steep slope (0.6 along north-east) takes the down-slope beam beyond max_altitude: the other
// three still give the exact velocity (a 3-beam solution, as real DVLs report).
TEST(Sensors, DvlThreeBeamSolutionWhenOneBeamLosesTheBottom) {
  up::VehicleParams v = with_all_sensors(0.0);
  v.sensors.dvl.max_altitude = 6.0;  // beam 0 meets the bottom 6.65 m down, the others 4.0 and 5.0 m
  up::SensorSuite s(v.sensors, up::EnvironmentParams{});
  const double k = 0.6 / std::sqrt(2.0);
  const PlaneSeabed slope(10.0, k, k);
  up::RigidBodyState x = at(5.0);
  x.v_WB_B = Eigen::Vector3d(-0.3, 0.4, 0.05);
  s.update(0.0, x, up::Vector6d::Zero(), &slope);
  const auto& r = s.readings().dvl;
  ASSERT_TRUE(r.valid);
  EXPECT_EQ(r.locked_beams, 3);
  EXPECT_FALSE(r.beam_valid[0]);
  EXPECT_LT((r.velocity_B - x.v_WB_B).norm(), 1e-12);
  // Two beams lost (max_altitude 4.5): no solution.
  v.sensors.dvl.max_altitude = 4.5;
  up::SensorSuite two(v.sensors, up::EnvironmentParams{});
  two.update(0.0, x, up::Vector6d::Zero(), &slope);
  EXPECT_EQ(two.readings().dvl.locked_beams, 1);
  EXPECT_FALSE(two.readings().dvl.valid);
}

// Noise sigma per beam: the least-squares velocity has covariance sigma^2 (B^T B)^-1, for a Janus
// array diag(1 / (2 sin^2 a), 1 / (2 sin^2 a), 1 / (4 cos^2 a)). 4000 samples: the sample standard
// deviation is within 5 % of that (its own spread is ~1.1 %).
TEST(Sensors, DvlBeamNoiseGivesTheLeastSquaresSpread) {
  up::VehicleParams v = with_all_sensors(0.0);
  v.sensors.dvl.velocity.noise_stddev = 0.01;
  up::SensorSuite s(v.sensors, up::EnvironmentParams{});
  const up::FlatSeabed floor(20.0);
  up::RigidBodyState x = at(10.0);
  x.v_WB_B = Eigen::Vector3d(0.5, 0.0, 0.0);
  Eigen::Vector3d sum = Eigen::Vector3d::Zero(), sum2 = Eigen::Vector3d::Zero();
  const int n = 4000;
  for (int k = 0; k < n; ++k) {
    s.update(0.1 * k, x, up::Vector6d::Zero(), &floor);
    const Eigen::Vector3d e = s.readings().dvl.velocity_B - x.v_WB_B;
    sum += e;
    sum2 += e.cwiseProduct(e);
  }
  const Eigen::Vector3d sd = (sum2 / n - (sum / n).cwiseProduct(sum / n)).cwiseSqrt();
  const double a = 22.5 * kPi / 180.0;
  const Eigen::Vector3d want(0.01 / (std::sqrt(2.0) * std::sin(a)), 0.01 / (std::sqrt(2.0) * std::sin(a)),
                             0.01 / (2.0 * std::cos(a)));
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(sd(i) / want(i), 1.0, 0.05) << "axis " << i << ": " << sd(i);
}

TEST(Sensors, DvlBeamSettingsAreChecked) {
  up::SensorSuiteParams p = with_all_sensors(0.0).sensors;
  p.dvl.beams = 3;
  try {
    up::validate_sensors(p, "v.yaml");
    FAIL() << "3 beams accepted";
  } catch (const up::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("v.yaml: sensors.dvl.beams = 3: must be 4"), std::string::npos) << e.what();
  }
  p.dvl.beams = 4;
  p.dvl.beam_angle_deg = 90.0;
  EXPECT_THROW(up::validate_sensors(p, "v.yaml"), up::ConfigError);
}

TEST(Sensors, GpsValidOnlyAtTheSurface) {
  up::SensorSuite s(with_all_sensors(0.0).sensors, up::EnvironmentParams{});
  s.update(0.0, at(0.05), up::Vector6d::Zero(), nullptr);
  EXPECT_TRUE(s.readings().gps.valid);
  s.update(1.0, at(1.0), up::Vector6d::Zero(), nullptr);
  EXPECT_FALSE(s.readings().gps.valid);
  s.update(2.0, at(0.1 + 1e-6), up::Vector6d::Zero(), nullptr);
  EXPECT_FALSE(s.readings().gps.valid);
}

TEST(Sensors, BuoyantVehicleSurfacesFloatsAndGetsAFix) {
  // B = 1.5 W: it rises, then floats where the submerged fraction is 2/3 of the 0.254 m height:
  // z = 0.254 * 2/3 - 0.127 = 0.0423 m, within GPS range; below 1 m the GPS must be invalid.
  up::VehicleParams v = with_all_sensors();
  v.buoyancy = 1.5 * v.mass * 9.81;
  up::Simulator sim(v, opts(), nullptr, nullptr, at(3.0));
  sim.advance_to(1.0);
  EXPECT_FALSE(sim.sensors().gps.valid);
  sim.advance_to(40.0);
  EXPECT_NEAR(sim.state().p_WB_W.z(), 0.254 * 2.0 / 3.0 - 0.127, 1e-3);
  EXPECT_TRUE(sim.sensors().gps.valid);
  EXPECT_NEAR(sim.sensors().gps.latitude_deg, 0.0, 1e-3);
}

TEST(Sensors, SeabedContactStopsASinkingVehicle) {
  // W - B = 132.4 - 120 = 12.4 N down. Free fall toward a flat floor at 20 m; the penalty spring
  // (2000 N/m) then holds the bottom point (z + 0.127) at 12.4 / 2000 = 6.2 mm penetration.
  up::VehicleParams v = with_all_sensors();
  v.buoyancy = 120.0;
  v.sensors.dvl.min_altitude = 0.05;  // the DVL (at the origin) rests 0.12 m above the floor
  up::Simulator sim(v, opts(), nullptr, std::make_unique<up::FlatSeabed>(20.0), at(18.0));
  sim.advance_to(3.0);
  EXPECT_GT(sim.state().v_WB_B.z(), 0.05);  // sinking
  sim.advance_to(40.0);
  const double penetration = sim.state().p_WB_W.z() + 0.127 - 20.0;
  EXPECT_NEAR(penetration, (v.mass * 9.81 - 120.0) / 2000.0, 1e-4);
  EXPECT_LT(sim.state().nu().norm(), 1e-4);
  ASSERT_TRUE(sim.sensors().dvl.valid);
  EXPECT_NEAR(sim.sensors().dvl.altitude_m, 0.127 - penetration, 0.01);
}

TEST(Sensors, GridSeabedInterpolatesBilinearly) {
  const up::GridSeabed g(10.0, -5.0, 2.0, {{20.0, 22.0}, {24.0, 30.0}});
  EXPECT_DOUBLE_EQ(g.depth_at(10.0, -5.0), 20.0);
  EXPECT_DOUBLE_EQ(g.depth_at(12.0, -3.0), 30.0);
  EXPECT_DOUBLE_EQ(g.depth_at(11.0, -4.0), 24.0);  // centre: mean of the four corners
  EXPECT_DOUBLE_EQ(g.depth_at(11.0, -5.0), 22.0);
  EXPECT_DOUBLE_EQ(g.depth_at(-100.0, 100.0), 22.0);  // outside: nearest edge
  EXPECT_THROW(up::GridSeabed(0, 0, 1.0, {{1.0, 2.0}, {3.0}}), up::ConfigError);
}

TEST(Sensors, SameSeedSameNoiseDifferentSeedDifferentNoise) {
  auto run = [](std::uint64_t seed) {
    up::VehicleParams v = with_all_sensors();
    v.sensors.seed = seed;
    v.sensors.imu.accel.bias_random_walk = 0.01;
    up::Simulator sim(v, opts(), nullptr, std::make_unique<up::FlatSeabed>(30.0), at(10.0));
    sim.advance_to(1.0);
    return sim.sensors().imu.specific_force_B;
  };
  EXPECT_EQ(run(1), run(1));
  EXPECT_NE(run(1), run(2));
}

}  // namespace

namespace {
// A seabed that does not say how shallow it gets: rays are followed from the sensor.
class UnboundedSeabed : public up::Seabed {
 public:
  explicit UnboundedSeabed(const up::Seabed& s) : s_(s) {}
  double depth_at(double x, double y) const override { return s_.depth_at(x, y); }

 private:
  const up::Seabed& s_;
};
}  // namespace

// The DVL's ray cast skips what lies above the seabed's shallowest depth: the range is the same
// as following the whole ray (to the 1e-9 m the bisection + secant reach), on a flat seabed the
// analytic 25 m / cos(22.5 deg), and a level or rising ray never reaches the bottom.
TEST(Sensors, RayRangeSkipsTheWaterAboveTheShallowestSeabed) {
  const up::FlatSeabed flat(30.0);
  const Eigen::Vector3d origin(1.0, -2.0, 5.0), beam = up::dvl_beam_B(1, 22.5);
  EXPECT_NEAR(up::seabed_ray_range(flat, origin, beam, 100.0), 25.0 / std::cos(22.5 * M_PI / 180.0), 1e-9);
  EXPECT_NEAR(up::seabed_ray_range(flat, origin, beam, 100.0),
              up::seabed_ray_range(UnboundedSeabed(flat), origin, beam, 100.0), 1e-9);
  EXPECT_LT(up::seabed_ray_range(flat, origin, Eigen::Vector3d(1, 0, 0), 100.0), 0.0);
  EXPECT_LT(up::seabed_ray_range(flat, origin, Eigen::Vector3d(0.6, 0, -0.8), 100.0), 0.0);
  EXPECT_LT(up::seabed_ray_range(flat, origin, beam, 20.0), 0.0);  // beyond max_range
  // A ridged grid (1 m cells, 18..24 m): every beam from 3 m and from 17.5 m, both ways alike.
  std::vector<std::vector<double>> depths(40, std::vector<double>(40));
  for (int i = 0; i < 40; ++i)
    for (int j = 0; j < 40; ++j) depths[i][j] = 21.0 + 3.0 * std::sin(0.7 * i) * std::cos(0.4 * j);
  const up::GridSeabed grid(-20.0, -20.0, 1.0, depths);
  double shallowest = depths[0][0];
  for (const auto& row : depths) shallowest = std::min(shallowest, *std::min_element(row.begin(), row.end()));
  EXPECT_EQ(grid.shallowest_depth(), shallowest);
  for (const double z : {3.0, 17.5})
    for (int b = 0; b < 4; ++b) {
      const Eigen::Vector3d o(0.3, -1.1, z), d = up::dvl_beam_B(b, 30.0);
      const double fast = up::seabed_ray_range(grid, o, d, 60.0);
      ASSERT_GT(fast, 0.0) << "z " << z << " beam " << b;
      EXPECT_NEAR(fast, up::seabed_ray_range(UnboundedSeabed(grid), o, d, 60.0), 1e-9) << "z " << z << " beam " << b;
    }
}
