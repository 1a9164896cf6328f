// The datagen spec: the shipped one loads, bad specs are named, samples are reproducible per seed
// and stay in their distributions, the sample's world and path follow its draw.
#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <set>

#include "unav_common/errors.hpp"
#include "unav_datagen/randomization.hpp"
#include "unav_scene/scenario.hpp"
#include "unav_scene/water.hpp"

namespace fs = std::filesystem;
using unav::datagen::DatagenSample;
using unav::datagen::RandomizationSpec;

namespace {

const std::string kSpec = std::string(UNAV_REPO_ROOT) + "/config/datagen/pipe_survey.yaml";

std::string emit(const DatagenSample& s) {
  YAML::Emitter e;
  e.SetDoublePrecision(17);
  e << unav::common::ToYaml(s);
  return e.c_str();
}

// The shipped spec with `overrides` (key.path=value) applied.
RandomizationSpec patched(const std::vector<std::string>& overrides) {
  return RandomizationSpec::parse(unav::scene::apply_scenario_overrides(YAML::LoadFile(kSpec), overrides, kSpec),
                                  kSpec);
}

std::string error_of(const std::string& override) {
  try {
    patched({override});
  } catch (const unav::ConfigError& e) {
    return e.what();
  }
  return "";
}

// The sample's world, as `unav datagen` builds it: a scenario generating over the base world.
unav::scene::World world_of(const DatagenSample& s) {
  unav::scene::Scenario sc;
  sc.seed = s.seed;
  sc.world = s.base_world;
  sc.generate = s.world;
  return unav::scene::scenario_world(sc);
}

}  // namespace

TEST(RandomizationSpec, ShippedSpecLoads) {
  const auto spec = RandomizationSpec::load(kSpec);
  EXPECT_EQ(spec.seed_of(0), 1000u);
  EXPECT_EQ(spec.seed_of(7), 1007u);
  const DatagenSample s = spec.sample(0);
  EXPECT_EQ(s.seed, 1000);
  EXPECT_TRUE(fs::exists(s.base_world));
  EXPECT_TRUE(fs::exists(s.cameras_config));
  EXPECT_TRUE(s.world.enabled);
  EXPECT_EQ(s.slurm.cpus_per_task, 2);
}

TEST(RandomizationSpec, BadSpecsNameFileKeyValueAndRule) {
  const std::pair<const char*, const char*> cases[] = {
      {"colour=red", "colour"},                              // unknown section
      {"world.water.turbidty=1.0", "world.water.turbidty"},  // typo in a key
      {"world.water.turbidity={uniform: [2.0, 1.0]}", "empty range"},
      {"world.water.turbidity={gaussian: [1, 2]}", "must be a number"},    // not a distribution
      {"world.water.preset=jerlov_IX", "world.water.preset = jerlov_IX"},  // unknown preset
      {"world.water.turbidity={uniform: [0.5, 20]}", "the distribution reaches 20"},
      {"world.water.turbidity=.nan", "must be finite"},
      {"world.pipeline.legs={repeat: {count: {uniform: [1, 3]}, each: {}}}", "a count takes"},
      {"output.format=rosbag", "output.format = rosbag"},
      {"world.objects.count=3", "needs objects.folder"},
      {"seed={int: [0, 5]}", "must be a fixed value"},
      {"base_world=no/such/world.yaml", "no such file"},
      {"render.shadows=maybe", "render.shadows = maybe"},
      {"render.caustics={choice: [true, 0]}", "render.caustics"},
      {"render.shadow=false", "render.shadow"},  // typo
  };
  for (const auto& [override, must_contain] : cases) {
    const std::string e = error_of(override);
    EXPECT_NE(e.find(must_contain), std::string::npos) << override << " -> '" << e << "'";
    EXPECT_NE(e.find("pipe_survey.yaml"), std::string::npos) << e;
  }
}

TEST(RandomizationSpec, SameSeedSameSampleBitForBit) {
  const auto a = RandomizationSpec::load(kSpec);
  const auto b = RandomizationSpec::load(kSpec);
  for (uint64_t k = 0; k < 20; ++k) EXPECT_EQ(emit(a.sample(k)), emit(b.sample(k)));
  EXPECT_NE(emit(a.sample(0)), emit(a.sample(1)));
  // A key's draw does not depend on the other keys: fixing the turbidity leaves the depth alone.
  const auto c = patched({"world.water.turbidity=1.0"});
  for (uint64_t k = 0; k < 5; ++k) {
    EXPECT_EQ(a.sample(k).world.seabed.depth_m, c.sample(k).world.seabed.depth_m);
    EXPECT_EQ(c.sample(k).world.water.turbidity, 1.0);
  }
}

TEST(RandomizationSpec, DistributionsStayInTheirSupportAndCoverIt) {
  const auto spec = RandomizationSpec::load(kSpec);
  double sum = 0;
  std::set<std::size_t> legs;
  std::set<std::string> presets;
  const int n = 2000;
  for (int k = 0; k < n; ++k) {
    const DatagenSample s = spec.sample(k);
    const double t = s.world.water.turbidity;
    ASSERT_GE(t, 0.7);
    ASSERT_LT(t, 1.6);
    sum += t;
    legs.insert(s.world.pipeline.legs.size());
    presets.insert(s.world.water.preset);
    for (const auto& leg : s.world.pipeline.legs) {
      ASSERT_GE(leg.turn_deg, -150.0);  // normal clipped to the field's rule
      ASSERT_LE(leg.turn_deg, 150.0);
      ASSERT_GE(leg.length_m, 5.0);
      ASSERT_LT(leg.length_m, 10.0);
    }
  }
  // Mean of U(0.7, 1.6) is 1.15; its standard error over 2000 draws is 0.26/sqrt(2000) = 0.006.
  EXPECT_NEAR(sum / n, 1.15, 0.03);
  EXPECT_EQ(legs, (std::set<std::size_t>{0, 1, 2, 3}));  // both ends of {int: [0, 3]}
  EXPECT_EQ(presets.size(), 8u);
}

TEST(SampleWorld, FollowsTheDrawAndCarriesTheCurrentAndThePath) {
  const auto spec = patched({"current.speed_mps=0.25", "current.direction_deg=90"});
  const DatagenSample s = spec.sample(3);
  const unav::scene::World w = world_of(s);
  ASSERT_EQ(w.pipelines.size(), 1u);
  EXPECT_EQ(w.pipelines[0].points_W.size(), s.world.pipeline.legs.size() + 2);
  EXPECT_DOUBLE_EQ(w.seabed.depth_m, s.world.seabed.depth_m);
  const auto preset = unav::scene::jerlov_preset(s.world.water.preset);
  const double turb = s.world.water.turbidity;
  EXPECT_NEAR(w.water.beta_D.x(), turb * preset.beta_D.x(), 1e-12);
  EXPECT_NEAR(w.water.b_scatter.z(), turb * preset.b_scatter.z(), 1e-12);
  EXPECT_EQ(static_cast<int>(w.lamps.size()), s.world.light.lamp_count);
  const std::string dir = (fs::temp_directory_path() / ("unav_rand_" + std::to_string(::getpid()))).string();
  fs::remove_all(dir);
  const std::string current = unav::datagen::write_sample_current(s, dir);
  ASSERT_FALSE(current.empty());
  const YAML::Node cur = YAML::LoadFile(current);
  EXPECT_NEAR(cur["current"]["velocity"][1].as<double>(), 0.25, 1e-12);  // east
  EXPECT_NEAR(cur["current"]["velocity"][0].as<double>(), 0.0, 1e-12);
  fs::remove_all(dir);
  EXPECT_EQ(unav::datagen::write_sample_current(spec.sample(3), dir).empty(), false);
  EXPECT_TRUE(unav::datagen::write_sample_current(patched({"current.speed_mps=0"}).sample(3), dir).empty());
  fs::remove_all(dir);

  // The path: every point at the sample's altitude above the seabed (no altitude wander here: the
  // wander has its own test), 0.1 m apart.
  for (const char* kind : {"follow_pipe", "lawnmower", "random_waypoints"}) {
    DatagenSample k = s;
    k.trajectory.kind = kind;
    k.trajectory.altitude_wander_m = 0.0;
    const auto path = unav::datagen::plan_trajectory(k, w, 0.1);
    ASSERT_GT(path.size(), 10u) << kind;
    for (size_t i = 0; i < path.size(); ++i) {
      EXPECT_NEAR(w.seabed.depth_at(path[i].p_W.x(), path[i].p_W.y()) - path[i].p_W.z(), k.trajectory.altitude_m, 1e-9);
      if (i > 0) {  // consecutive points 0.1 m apart along the path (closer across a corner)
        EXPECT_LE((path[i].p_W.head<2>() - path[i - 1].p_W.head<2>()).norm(), 0.1 + 1e-9);
      }
    }
  }
}

TEST(RandomizationSpec, RenderSwitchesDefaultOnAndRandomize) {
  const auto spec = RandomizationSpec::load(kSpec);
  EXPECT_TRUE(spec.sample(0).render.shadows);
  EXPECT_TRUE(spec.sample(0).render.caustics);
  EXPECT_TRUE(spec.sample(0).render.materials);
  const auto r = patched({"render.shadows=false", "render.caustics={choice: [true, false]}"});
  int on = 0;
  const int n = 400;
  for (int k = 0; k < n; ++k) {
    const DatagenSample s = r.sample(k);
    EXPECT_FALSE(s.render.shadows);
    EXPECT_TRUE(s.render.materials);
    on += s.render.caustics ? 1 : 0;
    // The switches draw from their own generators: the scene of a sample stays the same.
    if (k < 5) {
      EXPECT_EQ(s.world.water.preset, spec.sample(k).world.water.preset);
      EXPECT_EQ(s.world.water.turbidity, spec.sample(k).world.water.turbidity);
    }
  }
  // Binomial(400, 1/2): standard deviation 10; 5 sigma either side.
  EXPECT_NEAR(on, 0.5 * n, 50.0);
}

TEST(RandomizationSpec, CameraPipelineKeysRandomize) {
  // JPEG quality and white balance: off by default, drawn per sample when given a distribution
  // (each value of a two-way choice in 400 draws: Binomial(400, 1/2), 5 sigma = 50).
  EXPECT_EQ(RandomizationSpec::load(kSpec).sample(0).camera.jpeg_quality, 0);
  EXPECT_EQ(RandomizationSpec::load(kSpec).sample(0).camera.white_balance, "off");
  const auto r = patched({"camera.jpeg_quality={choice: [0, 90]}", "camera.white_balance={choice: [\"off\", auto]}"});
  int jpeg = 0, awb = 0;
  const int n = 400;
  for (int k = 0; k < n; ++k) {
    const DatagenSample s = r.sample(k);
    EXPECT_TRUE(s.camera.jpeg_quality == 0 || s.camera.jpeg_quality == 90) << s.camera.jpeg_quality;
    jpeg += s.camera.jpeg_quality == 90 ? 1 : 0;
    awb += s.camera.white_balance == "auto" ? 1 : 0;
  }
  EXPECT_NEAR(jpeg, 0.5 * n, 50.0);
  EXPECT_NEAR(awb, 0.5 * n, 50.0);
  const std::string e = error_of("camera.jpeg_quality=101");
  EXPECT_NE(e.find("camera.jpeg_quality"), std::string::npos) << e;
  EXPECT_NE(error_of("camera.white_balance=daylight").find("camera.white_balance"), std::string::npos);
}

TEST(SampleWorld, PilotWanderTurnsAndLiftsThePathSmoothly) {
  // follow_pipe with a heading wander of 20 deg and an altitude wander of 0.4 m over 4 m: the
  // path's points stay where they were across track, their yaw leaves the pipe's heading by at most
  // 20 deg (and by > 4 deg on average: it does wander), changes by < 1 deg per 5 cm point (smooth
  // over 4 m), and their height above the seabed stays within 1.5 +- 0.4 m; without wander the
  // path is the pipe's, heading and altitude exact.
  const auto plain =
      patched({"trajectory.kind=follow_pipe", "trajectory.altitude_m=1.5", "trajectory.lateral_offset_m=0.0",
               "trajectory.heading_wander_deg=0", "trajectory.altitude_wander_m=0"});
  const auto wander =
      patched({"trajectory.kind=follow_pipe", "trajectory.altitude_m=1.5", "trajectory.lateral_offset_m=0.0",
               "trajectory.heading_wander_deg=20", "trajectory.altitude_wander_m=0.4", "trajectory.wander_length_m=4"});
  const DatagenSample s0 = plain.sample(2), s1 = wander.sample(2);
  const unav::scene::World w = world_of(s0);
  const auto a = unav::datagen::plan_trajectory(s0, w, 0.05), b = unav::datagen::plan_trajectory(s1, w, 0.05);
  ASSERT_EQ(a.size(), b.size());
  double mean_off = 0.0, worst_step = 0.0, lo = 1e9, hi = -1e9;
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_NEAR(a[i].p_W.head<2>().x(), b[i].p_W.head<2>().x(), 1e-9);
    const double off = std::remainder(b[i].yaw - a[i].yaw, 2.0 * M_PI);
    EXPECT_LE(std::abs(off), 20.0 * M_PI / 180.0 + 1e-9);
    mean_off += std::abs(off) / static_cast<double>(a.size());
    if (i > 0 && a[i].yaw == a[i - 1].yaw)
      worst_step = std::max(worst_step, std::abs(std::remainder(b[i].yaw - b[i - 1].yaw, 2.0 * M_PI)));
    const double alt = w.seabed.depth_at(b[i].p_W.x(), b[i].p_W.y()) - b[i].p_W.z();
    lo = std::min(lo, alt);
    hi = std::max(hi, alt);
    EXPECT_NEAR(w.seabed.depth_at(a[i].p_W.x(), a[i].p_W.y()) - a[i].p_W.z(), 1.5, 1e-9);
  }
  std::printf("wander: mean heading offset %.1f deg, largest step %.2f deg, altitude %.2f..%.2f m\n",
              mean_off * 180.0 / M_PI, worst_step * 180.0 / M_PI, lo, hi);
  EXPECT_GT(mean_off, 4.0 * M_PI / 180.0);
  EXPECT_LT(worst_step, 1.0 * M_PI / 180.0);
  EXPECT_GE(lo, 1.1 - 1e-9);
  EXPECT_LE(hi, 1.9 + 1e-9);
  EXPECT_GT(hi - lo, 0.2);
}

TEST(RandomizationSpec, DocumentationListsEveryKey) {
  const std::string doc = RandomizationSpec::documentation();
  for (const auto& f : unav::common::Describe(DatagenSample{})) {
    if (f.type != "mapping") {
      EXPECT_NE(doc.find("`" + f.name + "`"), std::string::npos) << f.name;
    }
  }
  EXPECT_NE(doc.find("`world.pipeline.legs[i].turn_deg`"), std::string::npos);
}

TEST(SampleWorld, PlacesMeshesFromTheObjectsFolder) {
  const auto spec = patched({"world.objects.folder=" + std::string(UNAV_REPO_ROOT) + "/worlds/pipe_inspection/meshes",
                             "world.objects.count=3", "world.objects.scale={uniform: [0.5, 2.0]}"});
  const DatagenSample s = spec.sample(1);
  const unav::scene::World w = world_of(s);
  ASSERT_EQ(w.objects.size(), 3u);
  for (const auto& o : w.objects) {
    EXPECT_NEAR(o.scale.x(), s.world.objects.scale, 1e-12);
    EXPECT_NE(o.mesh_file.find("meshes/"), std::string::npos);
    EXPECT_NEAR(o.X_WO.translation().z(), w.seabed.depth_at(o.X_WO.translation().x(), o.X_WO.translation().y()) - 0.1,
                1e-9);
  }
  // A folder without meshes is refused with the rule.
  const std::string e = error_of("world.objects.folder=" + std::string(UNAV_REPO_ROOT) + "/config");
  EXPECT_NE(e.find("holds no mesh"), std::string::npos) << e;
}

// Found by fuzz_spec (scripts/fuzz.sh): integral reals in {int: [1.0, 3.0]} draw integers.
TEST(RandomizationSpec, IntRangeWrittenWithRealsDrawsIntegers) {
  const auto spec = patched({"trajectory.waypoints={int: [2.0, 4.0]}"});
  std::set<int> counts;
  for (int k = 0; k < 200; ++k) counts.insert(spec.sample(k).trajectory.waypoints);
  EXPECT_EQ(counts, (std::set<int>{2, 3, 4}));
  std::set<std::size_t> legs;
  const auto l = patched({"world.pipeline.legs={repeat: {count: {int: [1.0, 3.0]}, each: {turn_deg: 10}}}"});
  for (int k = 0; k < 200; ++k) legs.insert(l.sample(k).world.pipeline.legs.size());
  EXPECT_EQ(legs, (std::set<std::size_t>{1, 2, 3}));
}

// Found by fuzz_spec: "seed: 0999" is decimal 999 (YAML 1.2), not octal.
TEST(RandomizationSpec, SeedWithLeadingZeroIsDecimal) {
  YAML::Node root = YAML::LoadFile(kSpec);
  root["seed"] = YAML::Load("0999");
  const auto spec = RandomizationSpec::parse(root, kSpec);
  EXPECT_EQ(spec.seed_of(0), 999u);
  EXPECT_EQ(spec.sample(0).seed, 999);
}
