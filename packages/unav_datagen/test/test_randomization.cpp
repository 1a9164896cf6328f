#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "unav_common/errors.hpp"
#include "unav_datagen/randomization.hpp"
#include "unav_scene/water.hpp"

namespace fs = std::filesystem;
using unav::datagen::RandomizationSpec;

namespace {

const std::string kSpec = std::string(UNAV_REPO_ROOT) + "/config/datagen/pipe_survey.yaml";

std::string emit(const YAML::Node& n) {
  YAML::Emitter e;
  e.SetDoublePrecision(17);
  e << n;
  return e.c_str();
}

// The ConfigError a spec (the shipped one with `patch` merged in) raises, or "".
std::string error_of(const std::string& patch) {
  YAML::Node root = YAML::LoadFile(kSpec);
  const YAML::Node p = YAML::Load(patch);
  for (const auto& kv : p) {
    if (kv.second.IsMap() && root[kv.first.Scalar()] && root[kv.first.Scalar()].IsMap() &&
        !kv.second.begin()->first.Scalar().empty() && kv.second.size() >= 1 &&
        kv.second.begin()->first.Scalar() != "uniform" && kv.second.begin()->first.Scalar() != "choice") {
      for (const auto& sub : kv.second) root[kv.first.Scalar()][sub.first.Scalar()] = sub.second;
    } else {
      root[kv.first.Scalar()] = kv.second;
    }
  }
  try {
    RandomizationSpec::parse(root, kSpec);
  } catch (const unav::ConfigError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(RandomizationSpec, ShippedSpecLoads) {
  const auto spec = RandomizationSpec::load(kSpec);
  EXPECT_EQ(spec.seed_of(0), 1000u);
  EXPECT_EQ(spec.seed_of(7), 1007u);
  EXPECT_TRUE(fs::exists(spec.base_world()));
  EXPECT_TRUE(fs::exists(spec.cameras_config()));
}

TEST(RandomizationSpec, BadSpecsNameFileKeyValueAndRule) {
  struct Case {
    std::string patch, must_contain;
  };
  const Case cases[] = {
      {"{colour: red}", "colour"},                                     // unknown section
      {"{water: {turbidty: 1.0}}", "water.turbidty"},                  // typo in a key
      {"{water: {turbidity: {uniform: [2.0, 1.0]}}}", "empty range"},  // low > high
      {"{water: {turbidity: {gaussian: [1, 2]}}}", "unknown distribution 'gaussian'"},
      {"{water: {preset: jerlov_IX}}", "water.preset = jerlov_IX"},  // unknown preset
      {"{water: {preset: {choice: [jerlov_I, murky]}}}", "water.preset.choice[1] = murky"},
      {"{water: {turbidity: {uniform: [0.5, 20]}}}", "water.turbidity.uniform = 20"},  // support beyond the rule
      {"{water: {turbidity: .nan}}", "must be finite"},
      {"{pipeline: {segments: {uniform: [1, 3]}}}", "an int key takes"},
      {"{output: {format: rosbag}}", "one of: tum euroc kitti"},
      {"{objects: {count: 3}}", "needs objects.folder"},
      {"{seed: {uniform: [0, 5]}}", "takes a fixed value"},
      {"{base_world: no/such/world.yaml}", "no such file"},
      {"{render: {shadows: yes}}", "render.shadows = yes: must be one of: true false"},
      {"{render: {caustics: {choice: [true, 0]}}}", "render.caustics.choice[1] = 0"},
      {"{render: {shadow: false}}", "render.shadow"},  // typo
  };
  for (const auto& c : cases) {
    const std::string e = error_of(c.patch);
    EXPECT_NE(e.find(c.must_contain), std::string::npos) << c.patch << " -> '" << e << "'";
    EXPECT_NE(e.find("pipe_survey.yaml"), std::string::npos) << e;
  }
}

TEST(RandomizationSpec, SameSeedSameSampleBitForBit) {
  const auto a = RandomizationSpec::load(kSpec);
  const auto b = RandomizationSpec::load(kSpec);
  for (uint64_t k = 0; k < 20; ++k) EXPECT_EQ(emit(a.sample(k)), emit(b.sample(k)));
  EXPECT_NE(emit(a.sample(0)), emit(a.sample(1)));
  // A key's draw does not depend on the other keys: fixing the turbidity leaves the depth alone.
  YAML::Node root = YAML::LoadFile(kSpec);
  root["water"]["turbidity"] = 1.0;
  const auto c = RandomizationSpec::parse(root, kSpec);
  for (uint64_t k = 0; k < 5; ++k) {
    EXPECT_EQ(a.sample(k)["seabed"]["depth_m"].as<double>(), c.sample(k)["seabed"]["depth_m"].as<double>());
    EXPECT_EQ(c.sample(k)["water"]["turbidity"].as<double>(), 1.0);
  }
}

TEST(RandomizationSpec, DistributionsStayInTheirSupportAndCoverIt) {
  const auto spec = RandomizationSpec::load(kSpec);
  double sum = 0;
  std::set<int64_t> segments;
  std::set<std::string> presets;
  const int n = 2000;
  for (int k = 0; k < n; ++k) {
    const YAML::Node s = spec.sample(k);
    const double t = s["water"]["turbidity"].as<double>();
    ASSERT_GE(t, 0.7);
    ASSERT_LT(t, 1.6);
    sum += t;
    segments.insert(s["pipeline"]["segments"].as<int64_t>());
    ASSERT_EQ(s["pipeline"]["segment_length_m"].size(), s["pipeline"]["segments"].as<size_t>());
    presets.insert(s["water"]["preset"].as<std::string>());
    for (const auto& turn : s["pipeline"]["turn_deg"]) {
      ASSERT_GE(turn.as<double>(), -120.0);  // normal clipped to the key's rule
      ASSERT_LE(turn.as<double>(), 120.0);
    }
  }
  // Mean of U(0.7, 1.6) is 1.15; its standard error over 2000 draws is 0.26/sqrt(2000) = 0.006.
  EXPECT_NEAR(sum / n, 1.15, 0.03);
  EXPECT_EQ(segments, (std::set<int64_t>{1, 2, 3, 4}));  // both ends of {int: [1, 4]}
  EXPECT_EQ(presets.size(), 8u);
}

TEST(SampleWorld, LoadsAndCarriesTheSample) {
  const auto spec = RandomizationSpec::load(kSpec);
  YAML::Node s = spec.sample(3);
  s["current"]["speed_mps"] = 0.25;
  s["current"]["direction_deg"] = 90.0;
  const std::string dir = (fs::temp_directory_path() / ("unav_rand_" + std::to_string(::getpid()))).string();
  fs::remove_all(dir);
  const auto files = unav::datagen::write_sample_world(spec, s, dir);
  const unav::scene::World w = unav::scene::load_world(files.world_file);
  ASSERT_EQ(w.pipelines.size(), 1u);
  EXPECT_EQ(w.pipelines[0].points_W.size(), s["pipeline"]["segments"].as<size_t>() + 1);
  EXPECT_DOUBLE_EQ(w.seabed.depth_m, s["seabed"]["depth_m"].as<double>());
  const auto preset = unav::scene::jerlov_preset(s["water"]["preset"].as<std::string>());
  const double turb = s["water"]["turbidity"].as<double>();
  EXPECT_NEAR(w.water.beta_D.x(), turb * preset.beta_D.x(), 1e-12);
  EXPECT_NEAR(w.water.b_scatter.z(), turb * preset.b_scatter.z(), 1e-12);
  EXPECT_EQ(static_cast<int>(w.lamps.size()), s["lamps"]["count"].as<int>());
  ASSERT_FALSE(files.current_file.empty());
  EXPECT_EQ(w.current_file, fs::absolute(files.current_file).lexically_normal().string());
  const YAML::Node cur = YAML::LoadFile(files.current_file);
  EXPECT_NEAR(cur["current"]["velocity"][1].as<double>(), 0.25, 1e-12);  // east
  EXPECT_NEAR(cur["current"]["velocity"][0].as<double>(), 0.0, 1e-12);

  // The path: every point at the sample's altitude above the seabed, 0.1 m apart.
  for (const char* kind : {"follow_pipe", "lawnmower", "random_waypoints"}) {
    s["trajectory"]["kind"] = kind;
    const auto path = unav::datagen::plan_trajectory(s, w, 0.1);
    ASSERT_GT(path.size(), 10u) << kind;
    const double alt = s["trajectory"]["altitude_m"].as<double>();
    for (size_t i = 0; i < path.size(); ++i) {
      EXPECT_NEAR(w.seabed.depth_at(path[i].p_W.x(), path[i].p_W.y()) - path[i].p_W.z(), alt, 1e-9);
      // Consecutive points 0.1 m apart along the path (closer across a corner).
      if (i > 0) {
        EXPECT_LE((path[i].p_W.head<2>() - path[i - 1].p_W.head<2>()).norm(), 0.1 + 1e-9);
      }
    }
  }
  fs::remove_all(dir);
}

TEST(RandomizationSpec, RenderSwitchesDefaultOnAndRandomize) {
  const auto spec = RandomizationSpec::load(kSpec);
  for (const char* k : {"shadows", "caustics", "materials"})
    EXPECT_EQ(spec.sample(0)["render"][k].as<std::string>(), "true") << k;
  YAML::Node root = YAML::LoadFile(kSpec);
  root["render"]["shadows"] = false;
  root["render"]["caustics"] = YAML::Load("{choice: [true, false]}");
  const auto r = RandomizationSpec::parse(root, kSpec);
  int on = 0;
  const int n = 400;
  for (int k = 0; k < n; ++k) {
    const YAML::Node s = r.sample(k);
    EXPECT_EQ(s["render"]["shadows"].as<std::string>(), "false");
    EXPECT_EQ(s["render"]["materials"].as<std::string>(), "true");
    on += s["render"]["caustics"].as<std::string>() == "true";
    // The switches draw from their own generators: the scene of a sample stays the same.
    if (k < 5) {
      EXPECT_EQ(emit(s["water"]), emit(spec.sample(k)["water"]));
    }
  }
  // Binomial(400, 1/2): standard deviation 10; 5 sigma either side.
  EXPECT_NEAR(on, 0.5 * n, 50.0);
}

TEST(RandomizationSpec, DocumentationListsEveryKey) {
  const std::string doc = RandomizationSpec::documentation();
  for (const auto& k : RandomizationSpec::keys()) EXPECT_NE(doc.find("`" + k.path + "`"), std::string::npos) << k.path;
}

TEST(SampleWorld, PlacesMeshesFromTheObjectsFolder) {
  YAML::Node root = YAML::LoadFile(kSpec);
  root["objects"]["folder"] = std::string(UNAV_REPO_ROOT) + "/worlds/pipe_inspection/meshes";
  root["objects"]["count"] = 3;
  root["objects"]["scale"] = YAML::Load("{uniform: [0.5, 2.0]}");
  const auto spec = RandomizationSpec::parse(root, kSpec);
  ASSERT_FALSE(spec.object_meshes().empty());
  const YAML::Node s = spec.sample(1);
  const std::string dir = (fs::temp_directory_path() / ("unav_rand_obj_" + std::to_string(::getpid()))).string();
  fs::remove_all(dir);
  const auto files = unav::datagen::write_sample_world(spec, s, dir);
  const unav::scene::World w = unav::scene::load_world(files.world_file);  // meshes load through assimp
  ASSERT_EQ(w.objects.size(), 3u);
  for (const auto& o : w.objects) {
    EXPECT_NEAR(o.scale.x(), s["objects"]["scale"].as<double>(), 1e-12);
    EXPECT_NE(o.mesh_file.find("meshes/"), std::string::npos);
  }
  fs::remove_all(dir);
  // A folder without meshes is refused with the rule.
  root["objects"]["folder"] = std::string(UNAV_REPO_ROOT) + "/config";
  try {
    RandomizationSpec::parse(root, kSpec);
    FAIL();
  } catch (const unav::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("holds no mesh file"), std::string::npos) << e.what();
  }
}

// Found by fuzz_spec (scripts/fuzz.sh): {int: [1.0, 60]} passed the checker (1.0 is an integer)
// and then threw YAML::TypedBadConversion out of sample(); integral reals now draw like integers.
TEST(RandomizationSpec, IntRangeWrittenWithRealsDrawsIntegers) {
  YAML::Node root = YAML::LoadFile(kSpec);
  root["rocks"]["count"] = YAML::Load("{int: [1.0, 3.0]}");
  const auto spec = RandomizationSpec::parse(root, kSpec);
  std::set<int64_t> counts;
  for (int k = 0; k < 200; ++k) counts.insert(spec.sample(k)["rocks"]["count"].as<int64_t>());
  EXPECT_EQ(counts, (std::set<int64_t>{1, 2, 3}));
}

// Found by fuzz_spec: "seed: 0999" passed the integer check but yaml-cpp's as<uint64_t> reads a
// leading 0 as octal and threw a YAML exception instead of giving 999 (YAML 1.2 decimal).
TEST(RandomizationSpec, SeedWithLeadingZeroIsDecimal) {
  YAML::Node root = YAML::LoadFile(kSpec);
  root["seed"] = YAML::Load("0999");
  const auto spec = RandomizationSpec::parse(root, kSpec);
  EXPECT_EQ(spec.seed_of(0), 999u);
  EXPECT_EQ(spec.sample(0)["seed"].as<double>(), 999.0);
}
