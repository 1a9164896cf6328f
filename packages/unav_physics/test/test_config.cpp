// Configuration loading: the bundled files load; every bad input gives a message naming the
// file, the key, the value and the rule.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include <unistd.h>

#include "unav_physics/simulator.hpp"

namespace up = unav::physics;

namespace {

const std::string kConfig = UNAV_CONFIG_DIR;
const std::string kHeavy = kConfig + "/vehicles/bluerov2_heavy.yaml";

std::string read(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::filesystem::path temp_dir() {
  return std::filesystem::temp_directory_path() / ("unav_physics_test_" + std::to_string(::getpid()));
}

// Writes the Heavy config with `from` replaced by `to` and returns the new file's path.
std::string variant(const std::string& name, const std::string& from, const std::string& to) {
  std::string text = read(kHeavy);
  const auto pos = text.find(from);
  EXPECT_NE(pos, std::string::npos) << from;
  if (pos != std::string::npos) text.replace(pos, from.size(), to);
  std::filesystem::create_directories(temp_dir());
  std::string path = (temp_dir() / (name + ".yaml")).string();
  std::ofstream(path) << text;
  return path;
}

// Loads `path` expecting a ConfigError whose message contains each of `parts`.
void expect_error(const std::string& path, const std::vector<std::string>& parts) {
  try {
    up::load_vehicle(path);
    ADD_FAILURE() << "no error for " << path;
  } catch (const up::ConfigError& e) {
    const std::string msg = e.what();
    EXPECT_EQ(msg.rfind(path + ": ", 0), 0u) << msg;  // starts with the file name
    for (const auto& p : parts) EXPECT_NE(msg.find(p), std::string::npos) << "'" << p << "' not in: " << msg;
  }
}

TEST(Config, BundledHeavyLoadsWithReferenceValues) {
  const up::VehicleParams v = up::load_vehicle(kHeavy);
  const up::VehicleParams ref = up::bluerov2_heavy_params();
  EXPECT_EQ(v.name, "bluerov2_heavy");
  EXPECT_EQ(v.mass, 13.5);
  EXPECT_EQ(v.inertia, ref.inertia);
  EXPECT_EQ(v.added_mass, ref.added_mass);
  EXPECT_EQ(v.linear_damping, ref.linear_damping);
  EXPECT_EQ(v.quadratic_damping, ref.quadratic_damping);
  EXPECT_EQ(v.r_b_B, ref.r_b_B);
  ASSERT_EQ(v.thrusters.size(), 8u);
  for (std::size_t i = 0; i < 8; ++i) {
    EXPECT_NEAR(v.thrusters[i].direction_B.norm(), 1.0, 1e-12);
    EXPECT_LT((v.thrusters[i].position_B - ref.thrusters[i].position_B).norm(), 1e-12);
    EXPECT_LT((v.thrusters[i].direction_B - ref.thrusters[i].direction_B).norm(), 1e-12);
    EXPECT_NEAR(v.thrusters[i].max_forward_thrust(), 40.0, 0.1);
    EXPECT_EQ(v.thrusters[i].time_constant, 0.1);
  }
  EXPECT_TRUE(v.sensors.imu.enabled && v.sensors.dvl.enabled && v.sensors.gps.enabled);
  EXPECT_EQ(v.sensors.imu.rate_hz, 200.0);
  EXPECT_NEAR(v.buoyancy_force(up::EnvironmentParams{}), 13.5 * 9.81, 1e-12);  // neutral
}

TEST(Config, BundledSixThrusterBlueRov2Loads) {
  const up::VehicleParams v = up::load_vehicle(kConfig + "/vehicles/bluerov2.yaml");
  EXPECT_EQ(v.thrusters.size(), 6u);
  EXPECT_EQ(v.mass, 11.5);
  EXPECT_FALSE(v.sensors.dvl.enabled);
  up::SimulatorOptions o;
  up::Simulator sim(v, o);  // any vehicle, any thruster count
  EXPECT_EQ(sim.thrusters().size(), 6);
  EXPECT_EQ(sim.set_command(0.0, std::vector<double>(8, 0.0)), up::CommandStatus::kRejectedWrongLength);
}

TEST(Config, BadVehicleValuesNameFileKeyValueAndRule) {
  expect_error(variant("neg_mass", "mass: 13.5", "mass: -1"), {"mass = -1: must be > 0 kg"});
  expect_error(variant("nan_mass", "mass: 13.5", "mass: .nan"), {"mass = .nan: must be finite"});
  expect_error(variant("text_mass", "mass: 13.5", "mass: heavy"), {"mass = heavy: must be a number"});
  expect_error(variant("inf_added", "added_mass: [6.3567, 7.1206, 18.6863", "added_mass: [6.3567, 7.1206, .inf"),
               {"added_mass[2] = .inf: must be finite"});
  expect_error(
      variant("asym_inertia", "inertia: [0.26, 0.23, 0.37]", "inertia: [[0.26, 0.1, 0], [0, 0.23, 0], [0, 0, 0.37]]"),
      {"inertia = [[0.26, 0.1, 0]", "must be symmetric"});
  expect_error(
      variant("npd_inertia", "inertia: [0.26, 0.23, 0.37]", "inertia: [[0.26, 0.5, 0], [0.5, 0.23, 0], [0, 0, 0.37]]"),
      {"inertia = [[0.26, 0.5, 0]", "must be positive definite"});
  expect_error(variant("triangle", "inertia: [0.26, 0.23, 0.37]", "inertia: [0.1, 0.1, 0.37]"),
               {"inertia = ", "principal moments must satisfy the triangle inequality"});
  expect_error(variant("zero_dir", "{name: T4, position: [-0.156, -0.111, 0.085], direction: [-0.7071,  0.7071,  0.0]}",
                       "{name: T4, position: [-0.156, -0.111, 0.085], direction: [0, 0, 0]}"),
               {"thrusters[3].direction = [0, 0, 0]: has zero length"});
  expect_error(
      variant("zero_tc", "{name: T3, position: [-0.156,  0.111, 0.085], direction: [-0.7071, -0.7071,  0.0]}",
              "{name: T3, position: [-0.156,  0.111, 0.085], direction: [-0.7071, -0.7071,  0.0], time_constant: 0}"),
      {"thrusters[2].time_constant = 0: must be > 0 s"});
  expect_error(variant("neg_tc_default", "time_constant: 0.1     # s", "time_constant: -0.1     # s"),
               {"thrusters[0].time_constant = -0.1: must be > 0 s"});
  expect_error(variant("unknown_top", "mass: 13.5", "mass: 13.5\nmasss: 13.5"), {"masss = 13.5: unknown key"});
  expect_error(variant("unknown_nested", "{name: T2, position:", "{name: T2, positon: [0, 0, 0], position:"),
               {"thrusters[1].positon = [0, 0, 0]: unknown key"});
  expect_error(
      variant("short_damping", "linear_damping: [13.7, 0.0, 33.0, 0.0, 0.8, 0.0]", "linear_damping: [13.7, 0.0, 33.0]"),
      {"linear_damping = [13.7, 0.0, 33.0]: must be a list of 6 numbers"});
  expect_error(variant("neg_damping", "quadratic_damping: [141.0", "quadratic_damping: [-141.0"),
               {"quadratic_damping = ", "must have a non-negative diagonal"});
  expect_error(variant("imu_rate", "rate: 200.0          # Hz", "rate: -5          # Hz"),
               {"sensors.imu.rate = -5: must be > 0 Hz"});
  expect_error(variant("imu_key", "rate: 200.0          # Hz", "rat: 200.0"), {"sensors.imu.rat = 200.0: unknown key"});
  expect_error(variant("both_buoyancy", "buoyancy: neutral", "buoyancy: neutral\nvolume: 0.0134"),
               {"buoyancy = neutral: and volume are exclusive"});
  expect_error(variant("no_mass", "mass: 13.5", ""), {"mass: is required"});
  std::filesystem::remove_all(temp_dir());
}

TEST(Config, UnreadableAndMalformedFiles) {
  EXPECT_THROW(up::load_vehicle("/nonexistent/vehicle.yaml"), up::ConfigError);
  try {
    up::load_vehicle("/nonexistent/vehicle.yaml");
  } catch (const up::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/vehicle.yaml: cannot open file"), std::string::npos);
  }
  expect_error(variant("malformed", "mass: 13.5", "mass: [13.5"), {"malformed YAML"});
  std::filesystem::remove_all(temp_dir());
}

TEST(Config, InMemoryValidationUsesTheSameKeys) {
  up::VehicleParams v = up::bluerov2_heavy_params();
  v.thrusters[5].direction_B.setZero();
  try {
    up::validate_vehicle(v, "<test>");
    ADD_FAILURE();
  } catch (const up::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("<test>: thrusters[5].direction = [0, 0, 0]: has zero length"),
              std::string::npos)
        << e.what();
  }
  v = up::bluerov2_heavy_params();
  v.mass = 0.0;
  EXPECT_THROW(up::VehicleDynamics{v}, up::ConfigError);
  up::SimulatorOptions o;
  o.dt = -1e-3;
  std::string msg;
  EXPECT_FALSE(o.IsValid(&msg));
  EXPECT_NE(msg.find("dt must be in (0, 0.1] s (got -0.001)"), std::string::npos) << msg;
  EXPECT_THROW(up::Simulator(up::bluerov2_heavy_params(), o), up::ConfigError);
}

TEST(Config, CurrentAndSeabedErrors) {
  const auto dir = temp_dir();
  std::filesystem::create_directories(dir);
  auto write = [&](const std::string& name, const std::string& text) {
    std::string p = (dir / name).string();
    std::ofstream(p) << text;
    return p;
  };
  auto expect = [](auto&& fn, const std::string& part) {
    try {
      fn();
      ADD_FAILURE() << "no error, expected " << part;
    } catch (const up::ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
    }
  };
  const std::string bad_type = write("c1.yaml", "current: {type: tidal, velocity: [0, 0, 0]}\n");
  expect([&] { up::load_current(bad_type); }, bad_type + ": current.type = tidal: must be one of constant");
  const std::string bad_tc =
      write("c2.yaml", "current: {type: gauss_markov, stddev: [0.1, 0.1, 0], time_constant: 0}\n");
  expect([&] { up::load_current(bad_tc); }, bad_tc + ": current.time_constant = 0: must be > 0 s");
  const std::string bad_vel = write("c3.yaml", "current: {type: constant, velocity: [0.1, .nan, 0]}\n");
  expect([&] { up::load_current(bad_vel); }, bad_vel + ": current.velocity[1] = .nan: must be finite");
  const std::string bad_key = write("c4.yaml", "current: {type: constant, velocty: [0, 0, 0]}\n");
  expect([&] { up::load_current(bad_key); }, bad_key + ": current.velocty");
  const std::string ragged = write("s1.yaml", "seabed: {type: grid, resolution: 1, depths: [[1, 2], [3]]}\n");
  expect([&] { up::load_seabed(ragged); }, ragged + ": seabed.depths[1] = [3]: must be a list with as many values");
  const std::string bad_res = write("s2.yaml", "seabed: {type: grid, resolution: 0, depths: [[1]]}\n");
  expect([&] { up::load_seabed(bad_res); }, bad_res + ": seabed.resolution = 0: must be > 0 m");
  std::filesystem::remove_all(dir);
}

TEST(Config, SeabedFilesLoad) {
  const auto grid = up::load_seabed(std::string(UNAV_TEST_DATA_DIR) + "/seabed_grid.yaml");
  EXPECT_DOUBLE_EQ(grid->depth_at(0.0, 0.0), 25.0);
  EXPECT_DOUBLE_EQ(grid->depth_at(5.0, 0.0), 22.0);  // halfway between 25 and 19
  const auto pgm = up::load_seabed(std::string(UNAV_TEST_DATA_DIR) + "/seabed_pgm.yaml");
  // Image rows (top first): [0 255 0], [255 0 51]; the bottom row is x_N = 0.
  EXPECT_DOUBLE_EQ(pgm->depth_at(0.0, 0.0), 20.0);  // 255 -> white
  EXPECT_DOUBLE_EQ(pgm->depth_at(0.0, 1.0), 30.0);  // 0 -> black
  EXPECT_DOUBLE_EQ(pgm->depth_at(0.0, 2.0), 28.0);  // 51 -> 30 - 0.2 * 10
  EXPECT_DOUBLE_EQ(pgm->depth_at(1.0, 1.0), 20.0);
}

TEST(Config, EnvironmentFromYaml) {
  const YAML::Node n = YAML::Load("{water_density: 999.7, gravity: 9.80665}");
  const up::EnvironmentParams e = up::parse_environment(n, "world.yaml");
  EXPECT_EQ(e.water_density, 999.7);
  EXPECT_THROW(up::parse_environment(YAML::Load("{water_density: -1}"), "world.yaml"), up::ConfigError);
  EXPECT_THROW(up::parse_environment(YAML::Load("{density: 1000}"), "world.yaml"), up::ConfigError);
}

}  // namespace

// What depends on which keys a vehicle file gives: thruster_defaults fill the keys a thruster
// entry leaves out (an entry's own key wins), unnamed thrusters are T<i+1>, a sensor section that
// is given is enabled unless it says `enabled: false`, an absent one stays off; buoyancy
// 'neutral' is the default (B = m g). The schema (VehicleParams::Serialize) round-trips.
TEST(Config, ThrusterDefaultsAndSensorSectionsFollowWhatIsGiven) {
  const YAML::Node v = YAML::Load(R"(
mass: 10
inertia: [0.2, 0.2, 0.3]
added_mass: [1, 1, 1, 0.1, 0.1, 0.1]
linear_damping: [1, 1, 1, 0.1, 0.1, 0.1]
quadratic_damping: [[10, 0, 0, 0, 0, 0], [0, 10, 0, 0, 0, 0], [0, 0, 10, 0, 0, 0],
                    [0, 0, 0, 1, 0, 0], [0, 0, 0, 0, 1, 0], [0, 0, 0, 0, 0, 1]]
buoyancy: neutral
thruster_defaults: {w_max: 50, time_constant: 0.2}
thrusters:
  - {position: [0.1, 0, 0], direction: [2, 0, 0]}
  - {name: aft, position: [-0.1, 0, 0], direction: [-1, 0, 0], time_constant: 0.05}
sensors:
  imu: {rate: 100}
  dvl: {enabled: false, beams: 0}
)");
  const up::VehicleParams p = up::parse_vehicle(v, "given.yaml");
  ASSERT_EQ(p.thrusters.size(), 2u);
  EXPECT_EQ(p.thrusters[0].name, "T1");
  EXPECT_EQ(p.thrusters[1].name, "aft");
  EXPECT_EQ(p.thrusters[0].w_max, 50.0);
  EXPECT_EQ(p.thrusters[1].w_max, 50.0);
  EXPECT_EQ(p.thrusters[0].time_constant, 0.2);
  EXPECT_EQ(p.thrusters[1].time_constant, 0.05);                    // its own key wins
  EXPECT_EQ(p.thrusters[0].C_T, up::ThrusterParams{}.C_T);          // neither: the default
  EXPECT_EQ(p.thrusters[0].direction_B, Eigen::Vector3d::UnitX());  // normalised
  EXPECT_TRUE(p.sensors.imu.enabled);
  EXPECT_EQ(p.sensors.imu.rate_hz, 100.0);
  EXPECT_FALSE(p.sensors.dvl.enabled);
  EXPECT_EQ(p.sensors.dvl.beams, 0);
  EXPECT_FALSE(p.sensors.gps.enabled);
  EXPECT_NEAR(p.buoyancy_force(up::EnvironmentParams{}), 10 * 9.81, 1e-12);
  EXPECT_EQ(p.quadratic_damping(3, 3), 1.0);
  // Written back through the same schema and read again: the same vehicle.
  YAML::Node again = unav::common::ToYaml(p);
  const up::VehicleParams q = up::parse_vehicle(again, "again.yaml");
  EXPECT_EQ(q.inertia, p.inertia);
  EXPECT_EQ(q.quadratic_damping, p.quadratic_damping);
  EXPECT_EQ(q.thrusters[1].time_constant, 0.05);
  EXPECT_EQ(q.sensors.imu.rate_hz, 100.0);
  EXPECT_FALSE(q.sensors.dvl.enabled);
}
