#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <optional>
#include <string>
#include <vector>

#include "unav_common/errors.hpp"
#include "unav_common/temp_dir.hpp"
#include "unav_sim/pipe_following_env.hpp"

using namespace unav::sim;

namespace {

// The paper's evaluation pipe, a fixed start on its first (northbound) run, small images.
PipeFollowingConfig fixed_config(const std::string& dynamics) {
  return evaluation_config(
      load_pipe_following_config(std::string(UNAV_REPO_ROOT) + "/config/learning/pipe_following.yaml"), dynamics, 80,
      45);
}

}  // namespace

// Kinematic steps on the straight northbound run (pipe along the north axis at east = 0):
// every quantity follows from geometry. a = (0, 0): 1 m north, on the pipe: r = 10.
// a2 = 1: heading +30 deg: e_psi = pi/6, r = 10 - 2 pi/6. a1 = 1 from heading 0: the step goes
// 60 deg right: e_p = sin 60 deg per step; the third such step passes 2.5 m and terminates.
TEST(PipeFollowingEnv, RewardAndTerminationFollowThePapersFormula) {
  PipeFollowingEnv env(fixed_config("kinematic"));
  PipeFollowingInfo i0 = env.reset(0);
  EXPECT_NEAR(i0.e_p, 0.0, 1e-9);
  EXPECT_NEAR(i0.e_psi, 0.0, 1e-9);
  PipeFollowingStep s = env.act({0.0, 0.0});
  EXPECT_NEAR(s.info.position_W[0], 1.0, 1e-9);
  EXPECT_NEAR(s.info.e_p, 0.0, 1e-9);
  EXPECT_NEAR(s.reward, 10.0, 1e-9);
  EXPECT_FALSE(s.terminated || s.truncated);
  s = env.act({0.0, 1.0});
  EXPECT_NEAR(s.info.e_psi, M_PI / 6, 1e-9);
  EXPECT_NEAR(s.reward, 10.0 - 2.0 * M_PI / 6, 1e-9);
  env.reset(0);
  for (int k = 1; k <= 3; ++k) {
    s = env.act({1.0, 0.0});
    const double e_p = k * std::sin(M_PI / 3);
    EXPECT_NEAR(s.info.e_p, e_p, 1e-6) << "step " << k;
    EXPECT_NEAR(s.info.lateral_m, e_p, 1e-6);  // east of a northbound pipe = right of it
    EXPECT_NEAR(s.reward, 10.0 - 2.0 * e_p * e_p, 1e-6);
    EXPECT_EQ(s.terminated, k == 3) << "step " << k;
  }
  EXPECT_FALSE(s.truncated);
}

TEST(PipeFollowingEnv, BadActionsAreClippedOrRejectedAndCounted) {
  PipeFollowingEnv env(fixed_config("kinematic"));
  env.reset(0);
  PipeFollowingStep s = env.act({std::nan(""), 5.0});  // NaN -> 0, 5 -> 1
  EXPECT_EQ(s.info.rejected_actions, 1u);
  EXPECT_EQ(s.info.clipped_actions, 1u);
  EXPECT_NEAR(s.info.position_W[0], 1.0, 1e-9);
  EXPECT_NEAR(s.info.e_psi, M_PI / 6, 1e-9);
  EXPECT_TRUE(std::isfinite(s.reward));
}

TEST(PipeFollowingEnv, TruncatesAtTheStepLimit) {
  PipeFollowingConfig c = fixed_config("kinematic");
  c.env.max_steps = 4;
  PipeFollowingEnv env(c);
  env.reset(0);
  for (int k = 1; k <= 4; ++k) {
    const auto s = env.act(env.expert_action());
    EXPECT_EQ(s.truncated, k == 4);
    EXPECT_FALSE(s.terminated);
  }
}

// The privileged expert follows the whole evaluation pipe (both turns) to its end, kinematic and
// with the MPC flying each waypoint: the upper bound of the learned policy. The MPC's e_p bound
// (0.5 m, the target for the learned policy) leaves room for its lag in the bends.
TEST(PipeFollowingEnv, ExpertFollowsTheEvaluationPipeToItsEnd) {
  for (const std::string dyn : {"kinematic", "mpc"}) {
    PipeFollowingEnv env(fixed_config(dyn));
    PipeFollowingInfo info = env.reset(0);
    const double length = info.pipe_length_m;
    EXPECT_GT(length, 18.0);
    EXPECT_LT(length, 23.0);
    double max_ep = 0, sum_ep = 0;
    int n = 0;
    PipeFollowingStep s;
    do {
      s = env.act(env.expert_action());
      max_ep = std::max(max_ep, s.info.e_p);
      sum_ep += s.info.e_p;
      ++n;
    } while (!s.terminated && !s.truncated);
    EXPECT_FALSE(s.terminated) << dyn;
    EXPECT_TRUE(s.info.pipe_end) << dyn;
    EXPECT_GT(s.info.progress, (length - 1.5) / length) << dyn;
    EXPECT_LT(max_ep, dyn == "kinematic" ? 0.35 : 0.5) << dyn;
    std::printf("[%s] expert: %d steps, mean e_p %.3f m, max e_p %.3f m, %.1f s simulated\n", dyn.c_str(), n,
                sum_ep / n, max_ep, s.info.time_s);
  }
}

// Random scenes: the observation repeats for a seed (gymnasium's determinism check), the start
// is near the pipe, train and eval seeds give different scenes.
TEST(PipeFollowingEnv, RandomScenesRepeatPerSeedAndSplitsAreDisjoint) {
  PipeFollowingConfig c = fixed_config("kinematic");
  c.env.scenes = "random";
  c.env.start_offset_m = 0.5;
  c.env.start_heading_deg = 20.0;
  PipeFollowingEnv env(c);
  const PipeFollowingInfo a = env.reset(11);
  const auto obs_a = env.observe();
  EXPECT_EQ(obs_a.size(), 80u * 45u * 3u);
  EXPECT_LE(a.e_p, 0.5 + 1e-9);
  EXPECT_LE(a.e_psi, 20.0 * M_PI / 180 + 1e-9);
  env.reset(12);
  const PipeFollowingInfo b = env.reset(11);
  EXPECT_EQ(env.observe(), obs_a);
  EXPECT_EQ(a.scene_seed, b.scene_seed);
  c.env.split = "eval";
  PipeFollowingEnv eval(c);
  const PipeFollowingInfo e = eval.reset(11);
  EXPECT_NE(e.scene_seed, a.scene_seed);
  EXPECT_NE(eval.observe(), obs_a);
}

TEST(PipeFollowingEnv, VectorEnvSharesContextsAndMatchesSingleEnvs) {
  PipeFollowingConfig c = fixed_config("kinematic");
  c.env.scenes = "random";
  VectorPipeFollowingEnv vec(c, 3);
  // Even envs on one context; on llvmpipe the odd ones on a second display's context.
  EXPECT_EQ(&vec.env(0).episode().renderer().context(), &vec.env(2).episode().renderer().context());
  const bool llvmpipe = vec.env(0).episode().renderer().context().gl_renderer().find("llvmpipe") != std::string::npos;
  EXPECT_EQ(vec.contexts(), llvmpipe ? 2 : 1);
  if (vec.contexts() == 2) {
    EXPECT_NE(vec.env(0).episode().renderer().context().platform(),
              vec.env(1).episode().renderer().context().platform());
  }
  const std::size_t frame = std::size_t{80} * 45 * 3;
  std::vector<std::uint8_t> obs;
  const auto infos = vec.reset({100, 101, 102}, &obs);
  ASSERT_EQ(infos.size(), 3u);
  ASSERT_EQ(obs.size(), 3 * frame);
  const std::vector<std::uint8_t> reset_obs = obs;
  const auto steps = vec.step({{0.1, 0.0}, {0.0, -0.2}, {-0.3, 0.4}}, &obs);
  ASSERT_EQ(steps.size(), 3u);
  ASSERT_EQ(obs.size(), 3 * frame);
  // Each env's step and frame are a single env's, bit for bit, on either context.
  for (int i : {1, 2}) {
    PipeFollowingEnv single(c);
    const PipeFollowingInfo first = single.reset(100 + i);
    EXPECT_EQ(first.scene_seed, infos[static_cast<std::size_t>(i)].scene_seed);
    const auto o0 = single.observe();  // as the vector env's reset did (the noise follows the frame count)
    EXPECT_TRUE(std::equal(o0.begin(), o0.end(), reset_obs.begin() + static_cast<std::ptrdiff_t>(i * frame)))
        << "env " << i;
    const std::array<double, 2> a = i == 1 ? std::array<double, 2>{0.0, -0.2} : std::array<double, 2>{-0.3, 0.4};
    const auto s = single.act(a);
    EXPECT_EQ(s.reward, steps[static_cast<std::size_t>(i)].reward) << "env " << i;
    const auto o = single.observe();
    EXPECT_TRUE(std::equal(o.begin(), o.end(), obs.begin() + static_cast<std::ptrdiff_t>(i * frame))) << "env " << i;
  }
  // reset_some: the env given a seed is reset and observed, the others read as zeros.
  const auto some = vec.reset_some({std::nullopt, 101, std::nullopt}, &obs);
  ASSERT_EQ(obs.size(), 3 * frame);
  EXPECT_FALSE(some[0].has_value());
  ASSERT_TRUE(some[1].has_value());
  EXPECT_EQ(some[1]->scene_seed, infos[1].scene_seed);
  EXPECT_TRUE(
      std::all_of(obs.begin(), obs.begin() + static_cast<std::ptrdiff_t>(frame), [](auto v) { return v == 0; }));
  PipeFollowingEnv again(c);
  again.reset(101);
  const auto o1 = again.observe();
  EXPECT_TRUE(std::equal(o1.begin(), o1.end(), obs.begin() + static_cast<std::ptrdiff_t>(frame)));
}

TEST(PipeFollowingConfig, OverridesAreCheckedByName) {
  PipeFollowingConfig c;
  apply_override(&c, "max_steps", "50", "test");
  EXPECT_EQ(c.env.max_steps, 50);
  apply_override(&c, "scenario.cameras.width", "64", "test");
  EXPECT_EQ(c.scenario.cameras.width, 64);
  apply_override(&c, "pipe_scenes.pipeline.first_length_m", "{uniform: [11, 12]}", "test");
  EXPECT_GE(c.scenes.Sample(3).pipeline.first_length_m, 11.0);
  apply_override(&c, "pipe_scenes.pipeline.legs", "[{turn_deg: 30, length_m: 4}]", "test");
  EXPECT_EQ(c.scenes.Sample(3).pipeline.legs.size(), 1u);
  EXPECT_EQ(c.scenes.Sample(3).pipeline.legs[0].turn_deg, 30.0);
  EXPECT_THROW(apply_override(&c, "max_stepz", "5", "test"), unav::ConfigError);
  EXPECT_THROW(apply_override(&c, "dynamics", "teleport", "test"), unav::ConfigError);
  EXPECT_THROW(apply_override(&c, "pipe_scenes.pipeline.radius_m", "{uniform: [0.1, 5]}", "test"), unav::ConfigError);
  // A cross-field rule: a bend tighter than the pipe.
  EXPECT_THROW(apply_override(&c, "pipe_scenes.pipeline.bend_radius_m", "0.1", "test"), unav::ConfigError);
  EXPECT_EQ(c.scenes.Sample(3).pipeline.bend_radius_m, 0.0);  // a rejected override changes nothing
}

// A learning config may name its scenario with keys replaced ({file, set}): e.g. a render profile.
TEST(PipeFollowingConfig, ScenarioReferenceWithReplacedKeys) {
  unav::common::TempDir dir("pipe_cfg");
  const std::string scenario = std::string(UNAV_REPO_ROOT) + "/config/scenarios/pipe_following.yaml";
  {
    std::ofstream f(dir.path() + "/learn.yaml");
    f << "scenario: {file: " << scenario << ", set: [render.shadows=false, render.lamp_scatter_samples=0]}\n";
  }
  const PipeFollowingConfig c = load_pipe_following_config(dir.path() + "/learn.yaml");
  EXPECT_FALSE(c.scenario.render.shadows);
  EXPECT_EQ(c.scenario.render.lamp_scatter_samples, 0);
  EXPECT_TRUE(c.scenario.render.marine_snow);  // the file's other keys kept
  EXPECT_EQ(c.scenario.cameras.names, std::vector<std::string>{"down"});
  {
    std::ofstream f(dir.path() + "/bad.yaml");
    f << "scenario: {file: " << scenario << ", set: [render.shadowz=false]}\n";
  }
  EXPECT_THROW(load_pipe_following_config(dir.path() + "/bad.yaml"), unav::ConfigError);
  {
    std::ofstream f(dir.path() + "/bad2.yaml");
    f << "scenario: {file: " << scenario << ", sett: []}\n";
  }
  try {
    load_pipe_following_config(dir.path() + "/bad2.yaml");
    FAIL() << "an unknown key was accepted";
  } catch (const unav::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("scenario.sett"), std::string::npos) << e.what();
  }
}
