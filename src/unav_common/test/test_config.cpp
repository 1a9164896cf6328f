// The config schema: reading every field type, the errors (file, key path, value, rule),
// overrides, documentation and writing back.
#include "unav_common/config.hpp"
#include "unav_common/temp_dir.hpp"

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

#include <gtest/gtest.h>

namespace uc = unav::common;
using unav::ConfigError;

namespace {

struct Thruster {
  std::string name = "t";
  Eigen::Vector3d position{0.0, 0.0, 0.0};
  Eigen::Vector3d direction{1.0, 0.0, 0.0};
  template <class Archive>
  void Serialize(Archive* a) {
    a->Visit(uc::Field("name", &name).Doc("thruster name"));
    a->Visit(uc::Field("position", &position).Unit("m").Doc("r_i, body FRD"));
    a->Visit(uc::Field("direction", &direction).Range(-1.0, 1.0).Doc("n_i, unit vector"));
  }
};

struct Current {
  std::string model = "constant";
  double speed = 0.0;
  Eigen::Vector2d direction_ne{1.0, 0.0};
  template <class Archive>
  void Serialize(Archive* a) {
    a->Visit(uc::Field("model", &model).OneOf({"constant", "sinusoidal"}).Doc("current model"));
    a->Visit(uc::Field("speed", &speed).Min(0.0).Unit("m/s").Doc("mean speed"));
    a->Visit(uc::Field("direction_ne", &direction_ne).Doc("north, east"));
  }
};

struct MpcParams {
  bool enabled = true;
  int horizon_steps = 20;
  int64_t seed = 42;
  uint32_t count = 7;
  double dt = 0.05;
  double gain = 0.5;
  std::string model_vehicle_config = "vehicles/bluerov2_heavy.yaml";
  std::vector<double> waypoints;
  std::vector<int> ids{1, 2};
  std::vector<std::string> names{"a"};
  Eigen::Vector2d xy{0.0, 0.0};
  Eigen::Vector3d position_weights{200.0, 200.0, 200.0};
  Current current;
  std::vector<Thruster> thrusters{Thruster{"t0", {1, 0, 0}, {1, 0, 0}}, Thruster{"t1", {-1, 0, 0}, {0, 1, 0}}};

  template <class Archive>
  void Serialize(Archive* a) {
    a->Visit(uc::Field("enabled", &enabled).Doc("run the controller"));
    a->Visit(uc::Field("horizon_steps", &horizon_steps).Range(1, 500).Doc("N, prediction steps"));
    a->Visit(uc::Field("seed", &seed).Doc("random seed"));
    a->Visit(uc::Field("count", &count).Max(100).Doc("a count"));
    a->Visit(uc::Field("dt", &dt).Above(0.0).Unit("s").Doc("model step"));
    a->Visit(uc::Field("gain", &gain).Above(0.0).Max(1.0).Doc("blend"));
    a->Visit(uc::Field("model_vehicle_config", &model_vehicle_config).Doc("vehicle YAML"));
    a->Visit(uc::Field("waypoints", &waypoints).Unit("m").Doc("x, y pairs"));
    a->Visit(uc::Field("ids", &ids).Min(0).Doc("ids"));
    a->Visit(uc::Field("names", &names).Doc("names"));
    a->Visit(uc::Field("xy", &xy).Unit("m").Doc("start"));
    a->Visit(uc::Field("position_weights", &position_weights).Min(0.0).Doc("Q, position"));
    a->Visit(uc::Field("current", &current).Doc("water current"));
    a->Visit(uc::Field("thrusters", &thrusters).Doc("thrusters"));
  }
};

MpcParams Load(const std::string& yaml) {
  MpcParams p;
  uc::LoadYaml(YAML::Load(yaml), "config/mpc.yaml", &p);
  return p;
}

/// The ConfigError of loading `yaml` (fails the test when there is none).
ConfigError LoadError(const std::string& yaml) {
  try {
    Load(yaml);
  } catch (const ConfigError& e) {
    return e;
  }
  ADD_FAILURE() << "no ConfigError for: " << yaml;
  return ConfigError("none");
}

ConfigError OverrideError(const std::string& name, const std::string& value, MpcParams* p = nullptr) {
  MpcParams local;
  try {
    uc::ApplyOverride(p ? p : &local, name, value, "-p");
  } catch (const ConfigError& e) {
    return e;
  }
  ADD_FAILURE() << "no ConfigError for " << name << " := " << value;
  return ConfigError("none");
}

bool Same(const MpcParams& a, const MpcParams& b) {
  if (a.thrusters.size() != b.thrusters.size()) return false;
  for (size_t i = 0; i < a.thrusters.size(); ++i) {
    if (a.thrusters[i].name != b.thrusters[i].name || a.thrusters[i].position != b.thrusters[i].position ||
        a.thrusters[i].direction != b.thrusters[i].direction)
      return false;
  }
  return a.enabled == b.enabled && a.horizon_steps == b.horizon_steps && a.seed == b.seed && a.count == b.count &&
         a.dt == b.dt && a.gain == b.gain && a.model_vehicle_config == b.model_vehicle_config &&
         a.waypoints == b.waypoints && a.ids == b.ids && a.names == b.names && a.xy == b.xy &&
         a.position_weights == b.position_weights && a.current.model == b.current.model &&
         a.current.speed == b.current.speed && a.current.direction_ne == b.current.direction_ne;
}

TEST(ConfigError, FormatsFileKeyValueRule) {
  const ConfigError e("config/mpc.yaml", "horizon_steps", "-3", "must be >= 1");
  EXPECT_STREQ(e.what(), "config/mpc.yaml: horizon_steps = -3: must be >= 1");
  EXPECT_EQ(e.file(), "config/mpc.yaml");
  EXPECT_EQ(e.key(), "horizon_steps");
  EXPECT_EQ(e.value(), "-3");
  EXPECT_EQ(e.rule(), "must be >= 1");
  EXPECT_STREQ(ConfigError("f.yaml", "k", "", "is required").what(), "f.yaml: k: is required");
  EXPECT_STREQ(ConfigError("f.yaml", "", "", "cannot be opened").what(), "f.yaml: cannot be opened");
  EXPECT_STREQ(ConfigError("", "k", "3", "too big").what(), "k = 3: too big");
  const ConfigError plain("one message");
  EXPECT_STREQ(plain.what(), "one message");
  EXPECT_EQ(plain.file(), "");
  // A std::runtime_error for callers that catch those.
  EXPECT_THROW(throw ConfigError("x"), std::runtime_error);
}

TEST(Config, ReadsEveryType) {
  const MpcParams p = Load(R"(
enabled: false
horizon_steps: 30
seed: -9000000000
count: 12
dt: 0.1
gain: 1
model_vehicle_config: "vehicles/other.yaml"
waypoints: [1.5, -2, 3e-1]
ids: [4, 5, 6]
names: [x, "y z"]
xy: [1, 2]
position_weights: [10, 20, 30.5]
current: {model: sinusoidal, speed: 0.25, direction_ne: [0, 1]}
thrusters:
  - {name: a, position: [1, 2, 3], direction: [0, 0, 1]}
)");
  EXPECT_FALSE(p.enabled);
  EXPECT_EQ(p.horizon_steps, 30);
  EXPECT_EQ(p.seed, -9000000000LL);
  EXPECT_EQ(p.count, 12u);
  EXPECT_EQ(p.dt, 0.1);
  EXPECT_EQ(p.gain, 1.0);
  EXPECT_EQ(p.model_vehicle_config, "vehicles/other.yaml");
  EXPECT_EQ(p.waypoints, (std::vector<double>{1.5, -2.0, 0.3}));
  EXPECT_EQ(p.ids, (std::vector<int>{4, 5, 6}));
  EXPECT_EQ(p.names, (std::vector<std::string>{"x", "y z"}));
  EXPECT_EQ(p.xy, Eigen::Vector2d(1, 2));
  EXPECT_EQ(p.position_weights, Eigen::Vector3d(10, 20, 30.5));
  EXPECT_EQ(p.current.model, "sinusoidal");
  EXPECT_EQ(p.current.speed, 0.25);
  EXPECT_EQ(p.current.direction_ne, Eigen::Vector2d(0, 1));
  // A list given in YAML replaces the default list; its elements start from Thruster{}.
  ASSERT_EQ(p.thrusters.size(), 1u);
  EXPECT_EQ(p.thrusters[0].name, "a");
  EXPECT_EQ(p.thrusters[0].position, Eigen::Vector3d(1, 2, 3));
  EXPECT_EQ(p.thrusters[0].direction, Eigen::Vector3d(0, 0, 1));
  const MpcParams partial = Load("thrusters: [{name: b}]");
  EXPECT_EQ(partial.thrusters[0].direction, Eigen::Vector3d(1, 0, 0));
  EXPECT_EQ(partial.thrusters[0].position, Eigen::Vector3d(0, 0, 0));
}

TEST(Config, MissingKeysKeepDefaults) {
  const MpcParams d;
  EXPECT_TRUE(Same(Load("{}"), d));
  EXPECT_TRUE(Same(Load(""), d));          // empty document
  EXPECT_TRUE(Same(Load("current:"), d));  // empty section
  const MpcParams p = Load("dt: 0.2\ncurrent: {speed: 1.0}");
  EXPECT_EQ(p.dt, 0.2);
  EXPECT_EQ(p.current.speed, 1.0);
  EXPECT_EQ(p.current.model, "constant");
  EXPECT_EQ(p.horizon_steps, 20);
  EXPECT_EQ(p.thrusters.size(), 2u);
  // Start values are those of *out, not of a default-constructed struct.
  MpcParams q;
  q.horizon_steps = 77;
  uc::LoadYaml(YAML::Load("dt: 0.3"), "f.yaml", &q);
  EXPECT_EQ(q.horizon_steps, 77);
  EXPECT_EQ(q.dt, 0.3);
}

TEST(Config, UnknownKeyNamesFileKeyAndAllowedKeys) {
  const ConfigError e = LoadError("horizon_step: 30");
  EXPECT_EQ(e.file(), "config/mpc.yaml");
  EXPECT_EQ(e.key(), "horizon_step");
  EXPECT_EQ(e.value(), "30");
  EXPECT_STREQ(e.what(),
               "config/mpc.yaml: horizon_step = 30: unknown key; allowed keys: enabled, horizon_steps, seed, count, "
               "dt, gain, model_vehicle_config, waypoints, ids, names, xy, position_weights, current, thrusters");
  const ConfigError nested = LoadError("current: {sped: 1}");
  EXPECT_EQ(nested.key(), "current.sped");
  EXPECT_EQ(nested.rule(), "unknown key; allowed keys: model, speed, direction_ne");
  const ConfigError element = LoadError("thrusters: [{name: a}, {name: b, dirction: [1, 0, 0]}]");
  EXPECT_EQ(element.key(), "thrusters[1].dirction");
  EXPECT_EQ(element.value(), "[1, 0, 0]");
  EXPECT_EQ(element.rule(), "unknown key; allowed keys: name, position, direction");
}

TEST(Config, AKeyTwiceInOneMappingIsRefused) {
  const ConfigError e = LoadError("horizon_steps: 30\ngain: 1.0\nhorizon_steps: 40");
  EXPECT_EQ(e.key(), "horizon_steps");
  EXPECT_EQ(e.rule(), "appears twice in the same mapping");
  const ConfigError nested = LoadError("current: {speed: 1, speed: 2}");
  EXPECT_EQ(nested.key(), "current.speed");
}

TEST(Config, OutOfRangeNamesValueAndRule) {
  ConfigError e = LoadError("horizon_steps: -3");
  EXPECT_STREQ(e.what(), "config/mpc.yaml: horizon_steps = -3: must be in [1, 500]");
  EXPECT_STREQ(LoadError("horizon_steps: 501").what(), "config/mpc.yaml: horizon_steps = 501: must be in [1, 500]");
  EXPECT_EQ(Load("horizon_steps: 500").horizon_steps, 500);                         // inclusive
  EXPECT_STREQ(LoadError("dt: 0").what(), "config/mpc.yaml: dt = 0: must be > 0");  // exclusive
  EXPECT_STREQ(LoadError("dt: -0.5").what(), "config/mpc.yaml: dt = -0.5: must be > 0");
  EXPECT_STREQ(LoadError("gain: 1.5").what(), "config/mpc.yaml: gain = 1.5: must be in (0, 1]");
  EXPECT_STREQ(LoadError("count: 101").what(), "config/mpc.yaml: count = 101: must be <= 100");
  EXPECT_STREQ(LoadError("ids: [1, -2]").what(), "config/mpc.yaml: ids[1] = -2: must be >= 0");
  EXPECT_STREQ(LoadError("position_weights: [1, -1e-3, 0]").what(),
               "config/mpc.yaml: position_weights[1] = -1e-3: must be >= 0");
  EXPECT_STREQ(LoadError("current: {model: tidal}").what(),
               "config/mpc.yaml: current.model = tidal: must be one of {constant, sinusoidal}");
  EXPECT_STREQ(LoadError("current: {speed: -1}").what(), "config/mpc.yaml: current.speed = -1: must be >= 0");
}

TEST(Config, NanAndInfRejected) {
  for (const char* text : {"nan", ".nan", "NaN", ".NaN", "inf", ".inf", "-.inf", "+.inf", "-inf", "1e999"}) {
    const ConfigError e = LoadError(std::string("dt: ") + text);
    EXPECT_EQ(e.key(), "dt");
    EXPECT_EQ(e.value(), text);
    EXPECT_EQ(e.rule(), "must be finite (NaN/Inf rejected)") << text;
  }
  // No rule on waypoints: NaN is still rejected.
  EXPECT_STREQ(LoadError("waypoints: [1, .nan]").what(),
               "config/mpc.yaml: waypoints[1] = .nan: must be finite (NaN/Inf rejected)");
  EXPECT_EQ(LoadError("xy: [.inf, 0]").key(), "xy[0]");
  EXPECT_EQ(LoadError("current: {speed: .nan}").key(), "current.speed");
}

TEST(Config, WrongTypesNameTheRule) {
  EXPECT_STREQ(LoadError("horizon_steps: 2.5").what(), "config/mpc.yaml: horizon_steps = 2.5: must be an integer");
  EXPECT_STREQ(LoadError("horizon_steps: \"30\"").what(),
               "config/mpc.yaml: horizon_steps = \"30\": must be an integer");  // quoted: a string
  EXPECT_STREQ(LoadError("horizon_steps: 3000000000").what(),
               "config/mpc.yaml: horizon_steps = 3000000000: must be an integer in [-2147483648, 2147483647]");
  EXPECT_EQ(LoadError("seed: 99999999999999999999").rule(),
            "must be an integer in [-9223372036854775808, 9223372036854775807]");
  EXPECT_EQ(LoadError("count: -1").rule(), "must be an integer in [0, 4294967295]");
  EXPECT_STREQ(LoadError("enabled: 1").what(), "config/mpc.yaml: enabled = 1: must be true or false");
  EXPECT_STREQ(LoadError("enabled: yes").what(), "config/mpc.yaml: enabled = yes: must be true or false");
  EXPECT_STREQ(LoadError("dt: fast").what(), "config/mpc.yaml: dt = fast: must be a number");
  EXPECT_STREQ(LoadError("dt: [1]").what(), "config/mpc.yaml: dt = [1]: must be a number");
  EXPECT_STREQ(LoadError("dt:").what(), "config/mpc.yaml: dt = null: must be a number");
  EXPECT_STREQ(LoadError("model_vehicle_config: {a: 1}").what(),
               "config/mpc.yaml: model_vehicle_config = {a: 1}: must be a string");
  EXPECT_STREQ(LoadError("position_weights: [1, 2]").what(),
               "config/mpc.yaml: position_weights = [1, 2]: must be a list of 3 numbers (got 2)");
  EXPECT_STREQ(LoadError("position_weights: 3").what(),
               "config/mpc.yaml: position_weights = 3: must be a list of 3 numbers");
  EXPECT_STREQ(LoadError("waypoints: [1, x]").what(), "config/mpc.yaml: waypoints[1] = x: must be a number");
  EXPECT_STREQ(LoadError("ids: [1, 2.5]").what(), "config/mpc.yaml: ids[1] = 2.5: must be an integer");
  EXPECT_STREQ(LoadError("names: [a, [b]]").what(), "config/mpc.yaml: names[1] = [b]: must be a string");
  EXPECT_STREQ(LoadError("current: 3").what(), "config/mpc.yaml: current = 3: must be a mapping (a nested config)");
  EXPECT_STREQ(LoadError("thrusters: {name: a}").what(),
               "config/mpc.yaml: thrusters = {name: a}: must be a list of mappings");
  EXPECT_STREQ(LoadError("thrusters: [{name: a}, 3]").what(),
               "config/mpc.yaml: thrusters[1] = 3: must be a mapping (a list element)");
  // Accepted number spellings.
  EXPECT_EQ(Load("dt: +1.5e-2").dt, 0.015);
  EXPECT_EQ(Load("dt: .5").dt, 0.5);
  EXPECT_EQ(Load("dt: 2").dt, 2.0);
  EXPECT_EQ(Load("horizon_steps: +7").horizon_steps, 7);
  EXPECT_EQ(Load("enabled: False").enabled, false);
  EXPECT_EQ(Load("model_vehicle_config: 123").model_vehicle_config, "123");  // any scalar is a string
}

TEST(Config, NestedAndListKeyPaths) {
  const std::string four = "thrusters: [{name: a}, {name: b}, {name: c}, ";
  EXPECT_STREQ(LoadError(four + "{name: d, direction: [1, 0]}]").what(),
               "config/mpc.yaml: thrusters[3].direction = [1, 0]: must be a list of 3 numbers (got 2)");
  EXPECT_STREQ(LoadError(four + "{name: d, direction: [0, 2, 0]}]").what(),
               "config/mpc.yaml: thrusters[3].direction[1] = 2: must be in [-1, 1]");
  EXPECT_STREQ(LoadError("current: {direction_ne: [0, nan]}").what(),
               "config/mpc.yaml: current.direction_ne[1] = nan: must be finite (NaN/Inf rejected)");
}

TEST(Config, FailedLoadLeavesTargetUnchanged) {
  MpcParams p;
  p.dt = 0.7;
  EXPECT_THROW(uc::LoadYaml(YAML::Load("dt: 0.1\nhorizon_steps: 0"), "f.yaml", &p), ConfigError);
  EXPECT_EQ(p.dt, 0.7);
  EXPECT_EQ(p.horizon_steps, 20);
}

TEST(Config, RootSelectsASectionOfARos2ParamsFile) {
  const YAML::Node file = YAML::Load(R"(
mpc_controller:
  ros__parameters:
    horizon_steps: 12
    current: {speed: 0.5}
other_node:
  ros__parameters: {anything: 1}
)");
  MpcParams p;
  uc::LoadYaml(file, "params.yaml", &p, "mpc_controller.ros__parameters");
  EXPECT_EQ(p.horizon_steps, 12);
  EXPECT_EQ(p.current.speed, 0.5);
  try {
    uc::LoadYaml(YAML::Load("mpc_controller: {ros__parameters: {dt: -1}}"), "params.yaml", &p,
                 "mpc_controller.ros__parameters");
    ADD_FAILURE();
  } catch (const ConfigError& e) {
    EXPECT_STREQ(e.what(), "params.yaml: mpc_controller.ros__parameters.dt = -1: must be > 0");
  }
  try {
    uc::LoadYaml(file, "params.yaml", &p, "mpc.ros__parameters");
    ADD_FAILURE();
  } catch (const ConfigError& e) {
    EXPECT_STREQ(e.what(), "params.yaml: mpc: section not found (the file has no 'mpc.ros__parameters')");
  }
  EXPECT_THROW(uc::LoadYaml(YAML::Load("[1, 2]"), "list.yaml", &p), ConfigError);
}

class ConfigFile : public ::testing::Test {
 protected:
  std::string Write(const std::string& name, const std::string& text) { return tmp_.write(name, text); }
  uc::TempDir tmp_{"unav_common_config"};
  const std::string& dir_ = tmp_.path();
};

TEST_F(ConfigFile, LoadsFilesAndNamesBrokenOnes) {
  const std::string path = Write("mpc.yaml", "horizon_steps: 9\n");
  EXPECT_EQ(uc::LoadYamlFile<MpcParams>(path).horizon_steps, 9);
  MpcParams p;
  uc::LoadYamlFile(path, &p);
  EXPECT_EQ(p.horizon_steps, 9);
  const std::string ros = Write("ros.yaml", "mpc: {ros__parameters: {horizon_steps: 4}}\n");
  EXPECT_EQ(uc::LoadYamlFile<MpcParams>(ros, "mpc.ros__parameters").horizon_steps, 4);
  try {
    uc::LoadYamlFile<MpcParams>(dir_ + "/absent.yaml");
    ADD_FAILURE();
  } catch (const ConfigError& e) {
    EXPECT_EQ(std::string(e.what()), dir_ + "/absent.yaml: cannot be opened (missing or unreadable)");
  }
  const std::string bad = Write("bad.yaml", "dt: 0.1\nhorizon_steps: [1,\n");
  try {
    uc::LoadYamlFile<MpcParams>(bad);
    ADD_FAILURE();
  } catch (const ConfigError& e) {
    EXPECT_EQ(e.file(), bad);
    EXPECT_NE(e.rule().find("malformed YAML at line"), std::string::npos) << e.what();
  }
  const std::string wrong = Write("wrong.yaml", "dt: 0.1\ndtt: 3\n");
  try {
    uc::LoadYamlFile<MpcParams>(wrong);
    ADD_FAILURE();
  } catch (const ConfigError& e) {
    EXPECT_EQ(e.file(), wrong);
    EXPECT_EQ(e.key(), "dtt");
  }
}

TEST(Config, OverridesSetOneField) {
  MpcParams p;
  uc::ApplyOverride(&p, "horizon_steps", "30", "-p");
  uc::ApplyOverride(&p, "dt", "0.1", "-p");
  uc::ApplyOverride(&p, "position_weights", "[1, 2, 3]", "-p");
  uc::ApplyOverride(&p, "enabled", "false", "-p");
  uc::ApplyOverride(&p, "waypoints", "[]", "-p");
  uc::ApplyOverride(&p, "names", "[p, q]", "-p");
  uc::ApplyOverride(&p, "current.speed", "0.5", "-p");
  uc::ApplyOverride(&p, "current", "{model: sinusoidal}", "-p");
  uc::ApplyOverride(&p, "thrusters[1].direction", "[0, 0, -1]", "-p");
  uc::ApplyOverride(&p, "thrusters[0]", "{name: first}", "-p");
  uc::ApplyOverride(&p, "position_weights[2]", "7", "-p");
  uc::ApplyOverride(&p, "ids[0]", "9", "-p");
  EXPECT_EQ(p.horizon_steps, 30);
  EXPECT_EQ(p.dt, 0.1);
  EXPECT_EQ(p.position_weights, Eigen::Vector3d(1, 2, 7));
  EXPECT_FALSE(p.enabled);
  EXPECT_TRUE(p.waypoints.empty());
  EXPECT_EQ(p.names, (std::vector<std::string>{"p", "q"}));
  EXPECT_EQ(p.current.speed, 0.5);
  EXPECT_EQ(p.current.model, "sinusoidal");
  ASSERT_EQ(p.thrusters.size(), 2u);  // indexing keeps the other elements
  EXPECT_EQ(p.thrusters[1].direction, Eigen::Vector3d(0, 0, -1));
  EXPECT_EQ(p.thrusters[1].name, "t1");
  EXPECT_EQ(p.thrusters[0].name, "first");
  EXPECT_EQ(p.thrusters[0].position, Eigen::Vector3d(1, 0, 0));
  EXPECT_EQ(p.ids, (std::vector<int>{9, 2}));
  uc::ApplyOverride(&p, "thrusters", "[{name: only}]", "-p");  // the whole list
  ASSERT_EQ(p.thrusters.size(), 1u);
  EXPECT_EQ(p.thrusters[0].name, "only");
}

TEST(Config, OverrideErrorsNameSourceKeyValueRule) {
  EXPECT_STREQ(OverrideError("horizon_steps", "0").what(), "-p: horizon_steps = 0: must be in [1, 500]");
  EXPECT_STREQ(OverrideError("dt", ".nan").what(), "-p: dt = .nan: must be finite (NaN/Inf rejected)");
  const ConfigError unknown = OverrideError("horizon", "3");
  EXPECT_EQ(unknown.key(), "horizon");
  EXPECT_NE(unknown.rule().find("unknown key; allowed keys: enabled, horizon_steps,"), std::string::npos);
  EXPECT_EQ(OverrideError("current.sped", "1").rule(), "unknown key; allowed keys: model, speed, direction_ne");
  EXPECT_STREQ(OverrideError("thrusters[2].name", "x").what(),
               "-p: thrusters[2] = {name: x}: index out of range (the list has 2 elements)");
  EXPECT_STREQ(OverrideError("thrusters[1].direction", "[0, 5, 0]").what(),
               "-p: thrusters[1].direction[1] = 5: must be in [-1, 1]");
  EXPECT_STREQ(OverrideError("position_weights[3]", "1").what(),
               "-p: position_weights[3] = 1: index out of range (the list has 3 elements)");
  EXPECT_EQ(OverrideError("dt[0]", "1").rule(), "is a double, not a list: it has no elements to index");
  EXPECT_EQ(OverrideError("a..b", "1").rule(), "malformed parameter name (expected a key path like a.b or a[2].b)");
  EXPECT_EQ(OverrideError("thrusters[x]", "1").key(), "thrusters[x]");
  EXPECT_EQ(OverrideError("dt.", "1").key(), "dt.");
  EXPECT_EQ(OverrideError("dt", "[1,").rule().rfind("malformed YAML value", 0), 0u);
  MpcParams p;
  p.dt = 0.3;
  OverrideError("current.speed", "-1", &p);
  OverrideError("dt", "-1", &p);
  EXPECT_EQ(p.dt, 0.3);  // unchanged on error
  EXPECT_EQ(p.current.speed, 0.0);
}

TEST(Config, DescribeListsEveryFieldWithTypeDefaultRuleUnitDoc) {
  const std::vector<uc::FieldInfo> rows = uc::Describe(MpcParams{});
  std::vector<std::string> names;
  names.reserve(rows.size());
  for (const auto& r : rows) names.push_back(r.name);
  EXPECT_EQ(names, (std::vector<std::string>{"enabled",
                                             "horizon_steps",
                                             "seed",
                                             "count",
                                             "dt",
                                             "gain",
                                             "model_vehicle_config",
                                             "waypoints",
                                             "ids",
                                             "names",
                                             "xy",
                                             "position_weights",
                                             "current",
                                             "current.model",
                                             "current.speed",
                                             "current.direction_ne",
                                             "thrusters",
                                             "thrusters[i].name",
                                             "thrusters[i].position",
                                             "thrusters[i].direction"}));
  auto row = [&](const std::string& name) {
    for (const auto& r : rows)
      if (r.name == name) return r;
    return uc::FieldInfo{};
  };
  const uc::FieldInfo h = row("horizon_steps");
  EXPECT_EQ(h.type, "int");
  EXPECT_EQ(h.default_value, "20");
  EXPECT_EQ(h.rule, "[1, 500]");
  EXPECT_EQ(h.unit, "");
  EXPECT_EQ(h.doc, "N, prediction steps");
  EXPECT_EQ(row("dt").type, "double");
  EXPECT_EQ(row("dt").default_value, "0.05");
  EXPECT_EQ(row("dt").rule, "> 0");
  EXPECT_EQ(row("dt").unit, "s");
  EXPECT_EQ(row("gain").rule, "(0, 1]");
  EXPECT_EQ(row("enabled").type, "bool");
  EXPECT_EQ(row("enabled").default_value, "true");
  EXPECT_EQ(row("seed").type, "int64");
  EXPECT_EQ(row("count").type, "uint32");
  EXPECT_EQ(row("count").rule, "<= 100");
  EXPECT_EQ(row("model_vehicle_config").type, "string");
  EXPECT_EQ(row("model_vehicle_config").default_value, "vehicles/bluerov2_heavy.yaml");
  EXPECT_EQ(row("waypoints").type, "double[]");
  EXPECT_EQ(row("waypoints").default_value, "[]");
  EXPECT_EQ(row("ids").type, "int[]");
  EXPECT_EQ(row("ids").default_value, "[1, 2]");
  EXPECT_EQ(row("names").type, "string[]");
  EXPECT_EQ(row("xy").type, "double[2]");
  EXPECT_EQ(row("position_weights").type, "double[3]");
  EXPECT_EQ(row("position_weights").default_value, "[200.0, 200.0, 200.0]");
  EXPECT_EQ(row("position_weights").rule, ">= 0");
  EXPECT_EQ(row("current").type, "mapping");
  EXPECT_EQ(row("current").doc, "water current");
  EXPECT_EQ(row("current.model").rule, "{constant, sinusoidal}");
  EXPECT_EQ(row("current.speed").unit, "m/s");
  EXPECT_EQ(row("thrusters").type, "mapping[]");
  EXPECT_EQ(row("thrusters").default_value, "[2 elements]");
  EXPECT_EQ(row("thrusters[i].direction").default_value, "[1.0, 0.0, 0.0]");  // of Thruster{}
  EXPECT_EQ(row("thrusters[i].direction").rule, "[-1, 1]");

  const std::string help = uc::FormatHelp(rows);
  // Columns padded to the widest cell ("thrusters[i].direction", 22 characters) + 2 blanks.
  EXPECT_NE(help.find("\n  horizon_steps" + std::string(22 - 13 + 2, ' ') + "int  "), std::string::npos) << help;
  std::istringstream lines(help);
  std::string line, h_line;
  size_t doc_column = std::string::npos;
  bool aligned = true;
  while (std::getline(lines, line)) {
    EXPECT_EQ(line.rfind("  ", 0), 0u);
    if (line.find("  horizon_steps ") == 0) h_line = line;
    // The doc column starts at the same place in every row.
    const size_t col = line.rfind(row(line.substr(2, line.find(' ', 2) - 2)).doc);
    if (doc_column == std::string::npos) doc_column = col;
    aligned = aligned && col == doc_column;
  }
  EXPECT_TRUE(aligned) << help;
  // name, type, default, rule, unit ("-" when empty), doc, separated by at least two blanks.
  std::istringstream cells(h_line);
  std::vector<std::string> words;
  for (std::string w; cells >> w;) words.push_back(w);
  EXPECT_EQ(words,
            (std::vector<std::string>{"horizon_steps", "int", "20", "[1,", "500]", "-", "N,", "prediction", "steps"}));
  const std::string one = uc::FormatHelp({row("horizon_steps")});
  EXPECT_EQ(one, "  horizon_steps  int  20  [1, 500]  -  N, prediction steps\n");
}

TEST(Config, ToYamlRoundTrips) {
  MpcParams p;
  p.enabled = false;
  p.horizon_steps = 31;
  p.seed = -1234567890123LL;
  p.count = 99;
  p.dt = 0.1;
  p.gain = 1.0 / 3.0;
  p.model_vehicle_config = "true";  // a string that looks like a bool
  p.waypoints = {1e-300, -2.5, 123456789.125, 0.1 + 0.2};
  p.ids = {};
  p.names = {"", "a: b", "123", "null"};
  p.xy = {std::nextafter(1.0, 2.0), -0.0};
  p.position_weights = {5e-324, 1.7976931348623157e308, 3.0};
  p.current.model = "sinusoidal";
  p.current.speed = 2.0;
  p.thrusters = {Thruster{"x", {1, 2, 3}, {0, 0.6, 0.8}}};
  const YAML::Node y = uc::ToYaml(p);
  YAML::Emitter out;
  out << y;
  const std::string text = out.c_str();
  MpcParams back;
  uc::LoadYaml(YAML::Load(text), "manifest.yaml", &back);
  EXPECT_TRUE(Same(p, back)) << text;
  EXPECT_TRUE(std::signbit(back.xy.y()));
  // Declaration order and readable numbers.
  EXPECT_EQ(text.find("enabled:"), 0u) << text;
  EXPECT_NE(text.find("dt: 0.1\n"), std::string::npos) << text;
  EXPECT_NE(text.find("position_weights: [5e-324, 1.7976931348623157e+308, 3.0]"), std::string::npos) << text;
  EXPECT_EQ(y["current"]["speed"].as<double>(), 2.0);
  EXPECT_EQ(y["thrusters"][0]["name"].as<std::string>(), "x");
  // Defaults round-trip too.
  MpcParams d2;
  d2.dt = 9.0;
  uc::LoadYaml(uc::ToYaml(MpcParams{}), "defaults", &d2);
  EXPECT_TRUE(Same(d2, MpcParams{}));
}

TEST(Config, ValidateChecksCodeBuiltValues) {
  MpcParams p;
  EXPECT_NO_THROW(uc::Validate(p, "MpcParams{}"));
  p.dt = -1.0;
  try {
    uc::Validate(p, "code");
    ADD_FAILURE();
  } catch (const ConfigError& e) {
    EXPECT_STREQ(e.what(), "code: dt = -1.0: must be > 0");
  }
  p.dt = 0.1;
  p.thrusters[1].direction.y() = std::numeric_limits<double>::quiet_NaN();
  try {
    uc::Validate(p, "code");
    ADD_FAILURE();
  } catch (const ConfigError& e) {
    EXPECT_STREQ(e.what(), "code: thrusters[1].direction[1] = .nan: must be finite (NaN/Inf rejected)");
  }
  p.thrusters[1].direction.y() = 0.0;
  p.current.model = "tidal";
  EXPECT_THROW(uc::Validate(p, "code"), ConfigError);
  p.current.model = "constant";
  p.horizon_steps = 0;
  EXPECT_THROW(uc::Validate(p, "code"), ConfigError);
}

}  // namespace

// Square matrices (a vehicle's inertia, added mass, damping): n numbers are the diagonal, n lists
// of n the rows; written back as the diagonal when the matrix is one, else as rows, and read again
// to the same values. Wrong shapes and NaN are named with the element's key path.
struct Plant {
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Identity();
  Eigen::Matrix<double, 6, 6> damping = Eigen::Matrix<double, 6, 6>::Zero();
  template <class Archive>
  void Serialize(Archive* a) {
    a->Visit(uc::Field("inertia", &inertia).Doc("about the CG"));
    a->Visit(uc::Field("damping", &damping));
  }
};

TEST(Config, SquareMatricesReadAsDiagonalOrRowsAndRoundTrip) {
  Plant p;
  uc::LoadYaml(YAML::Load("inertia: [0.26, 0.23, 0.37]\n"
                          "damping: [[1, 2, 0, 0, 0, 0], [2, 3, 0, 0, 0, 0], [0, 0, 4, 0, 0, 0],\n"
                          "          [0, 0, 0, 5, 0, 0], [0, 0, 0, 0, 6, 0], [0, 0, 0, 0, 0, 7.5]]"),
               "v.yaml", &p);
  EXPECT_EQ(p.inertia, Eigen::Vector3d(0.26, 0.23, 0.37).asDiagonal().toDenseMatrix());
  EXPECT_EQ(p.damping(0, 1), 2.0);
  EXPECT_EQ(p.damping(1, 0), 2.0);
  EXPECT_EQ(p.damping(5, 5), 7.5);
  EXPECT_EQ(p.damping(2, 3), 0.0);
  const YAML::Node y = uc::ToYaml(p);
  EXPECT_TRUE(y["inertia"].IsSequence() && y["inertia"][0].IsScalar()) << y;       // the diagonal
  EXPECT_TRUE(y["damping"][0].IsSequence() && y["damping"][0].size() == 6u) << y;  // rows
  Plant q;
  uc::LoadYaml(y, "again.yaml", &q);
  EXPECT_EQ(q.inertia, p.inertia);
  EXPECT_EQ(q.damping, p.damping);

  const auto error = [](const std::string& yaml) {
    Plant t;
    try {
      uc::LoadYaml(YAML::Load(yaml), "v.yaml", &t);
    } catch (const ConfigError& e) {
      EXPECT_EQ(t.inertia, Eigen::Matrix3d::Identity());  // a failed read changes nothing
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_EQ(error("inertia: [1, 2]"),
            "v.yaml: inertia = [1, 2]: must be a list of 3 numbers (the diagonal) or 3 lists of 3 numbers (the rows)");
  EXPECT_NE(error("inertia: [[1, 0, 0], [0, 1], [0, 0, 1]]").find("3 lists of 3 numbers"), std::string::npos);
  EXPECT_NE(error("inertia: [1, .nan, 1]").find("inertia[1]"), std::string::npos);
  EXPECT_NE(error("inertia: [[1, 0, 0], [0, 1, x], [0, 0, 1]]").find("inertia[1][2] = x"), std::string::npos)
      << error("inertia: [[1, 0, 0], [0, 1, x], [0, 0, 1]]");
  const auto rows = uc::Describe(Plant{});
  EXPECT_EQ(rows.at(0).type, "double[3x3]");
}
