// Scenario files (scenario.hpp): the shipped ones load, distributions draw per seed, paths
// resolve, and bad input is named with file, key path, value and rule before anything runs.
#include "unav_scene/scenario.hpp"

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <set>

#include <gtest/gtest.h>

namespace fs = std::filesystem;
using unav::ConfigError;
using unav::scene::load_scenario;
using unav::scene::Scenario;

namespace {

const std::string kScenarios = std::string(UNAV_REPO_ROOT) + "/config/scenarios/";

std::string write(const std::string& name, const std::string& text) {
  const fs::path dir = fs::path(::testing::TempDir()) / ("unav_scenario_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  std::ofstream(dir / name) << text;
  return (dir / name).string();
}

std::string error_of(const std::string& text) {
  const std::string f = write("bad.yaml", text);
  try {
    load_scenario(f);
  } catch (const ConfigError& e) {
    const std::string m = e.what();
    return m.rfind(f, 0) == 0 ? "FILE" + m.substr(f.size()) : m;
  }
  return "";
}

}  // namespace

TEST(Scenario, TheShippedScenariosLoadWithTheirPathsResolved) {
  const Scenario s = load_scenario(kScenarios + "pipe_inspection.yaml");
  EXPECT_EQ(s.name, "pipe_inspection");
  for (const std::string& p : {s.world, s.vehicle.model, s.control.mpc, s.control.allocator, s.cameras.config}) {
    EXPECT_TRUE(fs::path(p).is_absolute()) << p;
    EXPECT_TRUE(fs::exists(p)) << p;
  }
  EXPECT_EQ(s.cameras.names, (std::vector<std::string>{"down", "front"}));
  ASSERT_EQ(s.mission.waypoints.size(), 4u);
  EXPECT_EQ(s.mission.waypoints[2].position, Eigen::Vector3d(11.0, -4.0, 8.35));
  EXPECT_EQ(s.vehicle.initial_position, Eigen::Vector3d(-1.5, 0.0, 8.35));
  const auto cams = unav::scene::scenario_cameras(s);
  ASSERT_EQ(cams.size(), 2u);
  EXPECT_EQ(cams[0].name, "down");
}

TEST(Scenario, DistributionsDrawPerSeedAndRepeat) {
  const std::string f = kScenarios + "pipe_inspection_random.yaml";
  std::set<std::string> waters;
  std::set<bool> shadows;
  for (std::uint64_t seed = 0; seed < 200; ++seed) {
    const Scenario s = load_scenario(f, seed);
    EXPECT_EQ(s.seed, static_cast<int64_t>(seed));
    waters.insert(s.water);
    shadows.insert(s.render.shadows);
    EXPECT_GE(s.vehicle.initial_position.x(), -2.0);
    EXPECT_LT(s.vehicle.initial_position.x(), -1.0);
    EXPECT_LE(std::abs(s.vehicle.initial_rpy_deg.z()), 20.0);
    EXPECT_GE(s.render.lamp_scatter_samples, 0);
    EXPECT_LE(s.render.lamp_scatter_samples, 8);
  }
  // 5 waters, 200 draws: each missed with probability (4/5)^200 ~ 4e-20.
  EXPECT_EQ(waters, (std::set<std::string>{"I", "IB", "II", "1C", "3C"}));
  EXPECT_EQ(shadows.size(), 2u);
  const Scenario a = load_scenario(f, 17), b = load_scenario(f, 17), c = load_scenario(f);
  EXPECT_EQ(a.vehicle.initial_position, b.vehicle.initial_position);  // bit for bit
  EXPECT_EQ(a.water, b.water);
  EXPECT_EQ(c.seed, 0);  // the file's seed
  EXPECT_EQ(c.vehicle.initial_position, load_scenario(f, 0).vehicle.initial_position);
}

TEST(Scenario, BadInputIsNamedBeforeAnythingRuns) {
  EXPECT_EQ(error_of("vehicle: {modle: x.yaml}"),
            "FILE: vehicle.modle = x.yaml: unknown key; allowed keys: model, set, initial_position, initial_rpy_deg");
  EXPECT_EQ(
      error_of("world: nowhere/world.yaml").rfind("FILE: world = nowhere/world.yaml: no such file (looked under", 0),
      0u);
  EXPECT_EQ(error_of("physics: {dt: {uniform: [0.001, 0.1]}}"),
            "FILE: physics.dt = {uniform: [0.001, 0.1]}: the distribution reaches 0.1, which must be in (0, 0.05]");
  EXPECT_EQ(error_of("seed: {int: [0, 9]}"), "FILE: seed: the seed that draws the distributions must be a fixed value");
  EXPECT_EQ(error_of("control: {period: 0.0505}"),
            "FILE: control.period = 0.050500: must be a whole number of physics.dt steps (0.001000 s)");
  EXPECT_EQ(error_of("cameras: {width: 320}"), "FILE: cameras.width/cameras.height = 320x0: give both or neither");
  EXPECT_EQ(error_of("mission: {waypoints: [{position: [1, 2, .nan]}]}"),
            "FILE: mission.waypoints[0].position[2] = .nan: must be finite (NaN/Inf rejected)");
  try {
    load_scenario("/nonexistent/scenario.yaml");
    FAIL() << "a missing file must throw";
  } catch (const ConfigError& e) {
    EXPECT_EQ(std::string(e.what()), "/nonexistent/scenario.yaml: cannot be opened (missing or unreadable)");
  }
}

TEST(Scenario, PathsResolveAgainstTheScenarioFolderFirst) {
  const std::string world = write("world.yaml", "seabed: {depth_m: 6.0}\n");
  const Scenario s = load_scenario(write("local.yaml", "world: world.yaml\n"));
  EXPECT_EQ(s.world, world);
}

// scenario_set / `unav run --set`: key.path=value overrides replace keys (sections kept), add new
// ones inside sections, may be distributions, and obey the same rules as the file.
TEST(Scenario, OverridesReplaceKeysBeforeTheDrawUnderTheSameRules) {
  const std::string f = kScenarios + "pipe_inspection.yaml";
  const Scenario s = load_scenario(f, std::nullopt,
                                   {"water=3C", "vehicle.initial_position=[0, 0, 5]", "render.shadows=false",
                                    "sonars.names=[fls]", "mission.duration_s={uniform: [20, 40]}"});
  EXPECT_EQ(s.water, "3C");
  EXPECT_EQ(s.vehicle.initial_position, Eigen::Vector3d(0.0, 0.0, 5.0));
  EXPECT_EQ(s.vehicle.model, load_scenario(f).vehicle.model);  // the rest of the section stays
  EXPECT_FALSE(s.render.shadows);
  EXPECT_TRUE(s.render.caustics);
  EXPECT_EQ(s.sonars.names, std::vector<std::string>{"fls"});
  EXPECT_TRUE(fs::path(s.sonars.config).is_absolute()) << s.sonars.config;
  EXPECT_GE(s.mission.duration_s, 20.0);
  EXPECT_LE(s.mission.duration_s, 40.0);
  EXPECT_EQ(s.mission.waypoints.size(), 4u);
  // Another draw of the overridden distribution, the same draw for the same seed.
  const auto d = [&](std::uint64_t seed) {
    return load_scenario(f, seed, {"mission.duration_s={uniform: [20, 40]}"}).mission.duration_s;
  };
  EXPECT_EQ(load_scenario(f, std::nullopt, {"water=3C", "water="}).water, "");  // later wins; empty = ""
  EXPECT_EQ(d(3), d(3));
  EXPECT_NE(d(3), d(4));

  const auto error = [&](const std::vector<std::string>& o) {
    try {
      load_scenario(f, std::nullopt, o);
    } catch (const ConfigError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  const std::string unknown = error({"vehicle.modle=x.yaml"});
  EXPECT_NE(unknown.find("pipe_inspection.yaml (scenario_set: vehicle.modle=x.yaml)"), std::string::npos) << unknown;
  EXPECT_NE(unknown.find("vehicle.modle"), std::string::npos) << unknown;
  EXPECT_NE(unknown.find("unknown key"), std::string::npos) << unknown;
  const std::string range = error({"physics.dt=0.5"});
  EXPECT_NE(range.find("physics.dt"), std::string::npos) << range;
  EXPECT_NE(range.find("0.5"), std::string::npos) << range;
  EXPECT_NE(error({"water"}).find("key.path=value"), std::string::npos);
  EXPECT_NE(error({"=3C"}).find("key.path=value"), std::string::npos);
  EXPECT_NE(error({"water.preset=3C"}).find("is not a section"), std::string::npos) << error({"water.preset=3C"});
  EXPECT_NE(error({"sonars.names=[fls]", "sonars.config=nowhere.yaml"}).find("no such file"), std::string::npos);
}
