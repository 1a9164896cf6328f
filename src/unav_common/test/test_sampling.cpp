// Distributions in configs (sampling.hpp): draws per key path, reproducible by seed, support
// checked against the fields' rules, clear errors.
#include "unav_common/sampling.hpp"

#include <cmath>
#include <set>
#include <string>
#include <vector>

#include <gtest/gtest.h>

namespace uc = unav::common;
using unav::ConfigError;

namespace {

struct Leg {
  Eigen::Vector3d position{0.0, 0.0, 0.0};
  double yaw_deg = 0.0;
  template <class Archive>
  void Serialize(Archive* a) {
    a->Visit(uc::Field("position", &position).Range(-100.0, 100.0));
    a->Visit(uc::Field("yaw_deg", &yaw_deg).Range(-180.0, 180.0));
  }
};

struct Water {
  std::string preset = "I";
  double turbidity = 1.0;
  template <class Archive>
  void Serialize(Archive* a) {
    a->Visit(uc::Field("preset", &preset).OneOf({"I", "II", "3C"}));
    a->Visit(uc::Field("turbidity", &turbidity).Above(0.0).Max(10.0));
  }
};

struct Config {
  int64_t seed = 0;
  int lamps = 2;
  bool shadows = true;
  double depth_m = 10.0;
  Water water;
  std::vector<Leg> legs;
  std::vector<double> sizes;
  Eigen::Vector2d range{0.0, 1.0};
  template <class Archive>
  void Serialize(Archive* a) {
    a->Visit(uc::Field("seed", &seed).Min(0.0));
    a->Visit(uc::Field("lamps", &lamps).Range(0, 8));
    a->Visit(uc::Field("shadows", &shadows));
    a->Visit(uc::Field("depth_m", &depth_m).Range(1.0, 1000.0));
    a->Visit(uc::Field("water", &water));
    a->Visit(uc::Field("legs", &legs));
    a->Visit(uc::Field("sizes", &sizes).Range(0.0, 5.0));
    a->Visit(uc::Field("range", &range));
  }
};

uc::Stochastic<Config> Parse(const std::string& text) { return uc::Stochastic<Config>(YAML::Load(text), "s.yaml"); }

std::string ErrorOf(const std::string& text) {
  try {
    Parse(text);
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(Sampling, ValuesPassThroughAndDistributionsStayInTheirSupport) {
  const auto s = Parse(R"(
    lamps: {int: [1, 3]}
    shadows: {choice: [true, false]}
    depth_m: {uniform: [5.0, 7.5]}
    water: {preset: {choice: [I, 3C]}, turbidity: 2.0}
    legs:
      - {position: [1.0, {uniform: [-2.0, 2.0]}, 5.0], yaw_deg: {normal: {mean: 0.0, std: 30.0}}}
  )");
  std::set<int> lamps;
  std::set<std::string> presets;
  int shadows_on = 0;
  constexpr int kN = 2000;
  for (int seed = 0; seed < kN; ++seed) {
    const Config c = s.Sample(static_cast<std::uint64_t>(seed));
    lamps.insert(c.lamps);
    presets.insert(c.water.preset);
    shadows_on += c.shadows ? 1 : 0;
    EXPECT_GE(c.depth_m, 5.0);
    EXPECT_LT(c.depth_m, 7.5);
    EXPECT_EQ(c.water.turbidity, 2.0);
    ASSERT_EQ(c.legs.size(), 1u);
    EXPECT_EQ(c.legs[0].position.x(), 1.0);
    EXPECT_GE(c.legs[0].position.y(), -2.0);
    EXPECT_LE(c.legs[0].position.y(), 2.0);
    EXPECT_EQ(c.legs[0].position.z(), 5.0);
    EXPECT_LE(std::abs(c.legs[0].yaw_deg), 180.0);  // normal draws clipped to the rule
  }
  EXPECT_EQ(lamps, (std::set<int>{1, 2, 3}));
  EXPECT_EQ(presets, (std::set<std::string>{"I", "3C"}));
  // Binomial(2000, 0.5): mean 1000, sigma 22.4; 5 sigma (112) is a false alarm once in ~3.5e6 runs.
  EXPECT_NEAR(shadows_on, kN / 2.0, 112);
}

TEST(Sampling, SameSeedSameConfigAndAddingAKeyShiftsNoOther) {
  const auto a = Parse("depth_m: {uniform: [1, 100]}\nlamps: {int: [0, 8]}");
  const auto b = Parse("depth_m: {uniform: [1, 100]}\nlamps: {int: [0, 8]}\nwater: {turbidity: {uniform: [0.5, 2]}}");
  for (std::uint64_t seed : {0ULL, 1ULL, 77ULL, 123456789ULL}) {
    const Config x = a.Sample(seed), y = a.Sample(seed), z = b.Sample(seed);
    EXPECT_EQ(x.depth_m, y.depth_m);  // bit for bit
    EXPECT_EQ(x.lamps, y.lamps);
    EXPECT_EQ(x.depth_m, z.depth_m);  // the new key has its own generator
    EXPECT_EQ(x.lamps, z.lamps);
  }
  EXPECT_NE(a.Sample(0).depth_m, a.Sample(1).depth_m);
}

TEST(Sampling, DrawsAreUniformOverTheRange) {
  // Mean of N uniform draws on [0, 1]: sigma = 1 / sqrt(12 N) = 0.0029 for N = 10000; 5 sigma.
  const auto s = Parse("water: {turbidity: {uniform: [1.0, 2.0]}}");
  double sum = 0;
  constexpr int kN = 10000;
  for (int i = 0; i < kN; ++i) sum += s.Sample(static_cast<std::uint64_t>(i)).water.turbidity - 1.0;
  EXPECT_NEAR(sum / kN, 0.5, 5 * 0.0029);
}

TEST(Sampling, RepeatDrawsAListWhoseLengthAndElementsAreDistributions) {
  const auto s = Parse(R"(
    legs: {repeat: {count: {int: [0, 3]}, each: {position: [{uniform: [0, 10]}, 0, 5], yaw_deg: {choice: [-90, 90]}}}}
    sizes: {repeat: {count: 2, each: {uniform: [1, 2]}}}
  )");
  std::set<std::size_t> lengths;
  for (std::uint64_t seed = 0; seed < 200; ++seed) {
    const Config c = s.Sample(seed);
    lengths.insert(c.legs.size());
    for (const auto& leg : c.legs) {
      EXPECT_GE(leg.position.x(), 0.0);
      EXPECT_LT(leg.position.x(), 10.0);
      EXPECT_EQ(leg.position.z(), 5.0);
      EXPECT_EQ(std::abs(leg.yaw_deg), 90.0);
    }
    if (c.legs.size() >= 2) {
      EXPECT_NE(c.legs[0].position.x(), c.legs[1].position.x());  // each element drawn anew
    }
    ASSERT_EQ(c.sizes.size(), 2u);
    EXPECT_NE(c.sizes[0], c.sizes[1]);
    for (double v : c.sizes) EXPECT_TRUE(v >= 1.0 && v < 2.0) << v;
    // Element i of a list is keyed by its path ("sizes[1]"): the same draw whatever the count's.
    const Config d = Parse("sizes: {repeat: {count: 3, each: {uniform: [1, 2]}}}").Sample(seed);
    EXPECT_EQ(d.sizes[1], c.sizes[1]);
  }
  EXPECT_EQ(lengths, (std::set<std::size_t>{0, 1, 2, 3}));
}

// A file that is one distribution as a whole (a mapping like `choice: [...]`) is refused with the
// file named; it crashed the support check (fuzz_spec found it).
TEST(Sampling, AWholeFileThatIsADistributionIsRefused) {
  for (const char* text : {"choice: [1, 2]", "uniform: [0, 1]"}) {
    try {
      Parse(text);
      FAIL() << text << " was accepted";
    } catch (const unav::ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find("s.yaml"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("not the whole file"), std::string::npos) << e.what();
    }
  }
}

// A key twice in one mapping (yaml-cpp keeps both) is refused by path before anything is drawn;
// a repeated key next to a list of distributions crashed the support check (fuzz_spec found it).
TEST(Sampling, AKeyTwiceInOneMappingIsRefused) {
  try {
    Parse("sizes: [1, 2]\nsizes: [0.08, {uniform: [0.2, 0.6]}]");
    FAIL() << "a duplicate key was accepted";
  } catch (const unav::ConfigError& e) {
    EXPECT_EQ(e.key(), "sizes") << e.what();
    EXPECT_EQ(e.rule(), "appears twice in the same mapping") << e.what();
    EXPECT_NE(std::string(e.what()).find("s.yaml"), std::string::npos) << e.what();
  }
}

TEST(Sampling, BadRepeatsAreNamed) {
  const std::pair<const char*, const char*> cases[] = {
      {"sizes: {repeat: {count: 2}}",
       "s.yaml: sizes.repeat = {count: 2}: expected {count: n or {int: [lo, hi]} or {choice: [...]}, each: element}"},
      {"sizes: {repeat: {count: -1, each: 1}}",
       "s.yaml: sizes.repeat.count = -1: a count is a whole number in [0, 10000]"},
      {"sizes: {repeat: {count: {uniform: [1, 2]}, each: 1}}",
       "s.yaml: sizes.repeat.count = {uniform: [1, 2]}: a count takes n, {int: [lo, hi]} or {choice: [...]}"},
      {"depth_m: {repeat: {count: 2, each: 1}}",
       "s.yaml: depth_m = {repeat: {count: 2, each: 1}}: a repeat stands for a list, not a double"},
      {"sizes: {repeat: {count: {int: [1, 3]}, each: {uniform: [4, 6]}}}",
       "s.yaml: sizes[0] = {uniform: [4, 6]}: the distribution reaches 6, which must be in [0, 5]"},
      // The shortest and the longest list are both checked: a fixed-size field takes one length.
      {"range: {repeat: {count: {int: [2, 3]}, each: 1}}", "s.yaml: range"}};
  for (const auto& [yaml, error] : cases)
    EXPECT_EQ(ErrorOf(yaml).rfind(error, 0), 0u) << yaml << " -> " << ErrorOf(yaml);
}

TEST(Sampling, KeySeedIsSplitMixOfTheSeedAndThePathHash) {
  EXPECT_NE(uc::KeySeed(1, "a.b"), uc::KeySeed(1, "a.c"));
  EXPECT_NE(uc::KeySeed(1, "a.b"), uc::KeySeed(2, "a.b"));
  // SplitMix64's first output for state 0 (published reference value).
  EXPECT_EQ(uc::SplitMix64{0}.Next(), 0xE220A8397B1DCDAFULL);
}

TEST(Sampling, BadDistributionsAreNamedWithFileKeyValueAndRule) {
  const std::pair<const char*, const char*> cases[] = {
      {"depth_m: {uniform: [0.5, 20]}",
       "s.yaml: depth_m = {uniform: [0.5, 20]}: the distribution reaches 0.5, which must be in [1, 1000]"},
      {"depth_m: {uniform: [20, 5]}", "s.yaml: depth_m.uniform = [20, 5]: empty range: lo > hi"},
      {"lamps: {uniform: [1, 3]}",
       "s.yaml: lamps.uniform = [1, 3]: a int field takes {int: [lo, hi]} or {choice: [...]}"},
      {"water: {preset: {choice: [I, IX]}}",
       "s.yaml: water.preset = {choice: [I, IX]}: the distribution reaches IX, which must be one of {I, II, 3C}"},
      {"depth_m: {normal: {mean: 5}}", "s.yaml: depth_m.normal = {mean: 5}: needs mean and std"},
      {"depth_m: {normal: {mean: 5, std: -1}}", "s.yaml: depth_m.normal.std = -1: must be >= 0"},
      {"water: {uniform: [2, 3]}",
       "s.yaml: water = {uniform: [2, 3]}: a distribution stands for one value, not a mapping"},
      {"legs: [{yaw_deg: {int: [0, 400]}}]",
       "s.yaml: legs[0].yaw_deg = {int: [0, 400]}: the distribution reaches 400, which must be in [-180, 180]"},
      {"depth_m: {uniform: [2, .nan]}", "s.yaml: depth_m.uniform[1] = .nan: must be finite"},
      {"[1, 2]", "s.yaml: [1, 2]: must be a mapping of config keys"}};
  for (const auto& [yaml, error] : cases) EXPECT_EQ(ErrorOf(yaml), error) << yaml;
  EXPECT_EQ(ErrorOf("depht_m: {uniform: [2, 3]}").rfind("s.yaml: depht_m = 2: unknown key", 0), 0u);
}
