// The paper's DRL pipe-following task (section V-B) as an environment core, DDS-free:
//   observation  the down camera's RGB image, uint8 H x W x 3 (180 x 320 by default)
//   action       a = (a1, a2) in [-1, 1]^2: a1 the direction of a step of step_length_m (1 m)
//                relative to the heading (+-max_step_angle_deg), a2 the heading change
//                (+-max_turn_deg); the resulting waypoint (depth held) is executed by the MPC
//                (dynamics "mpc") or reached exactly (dynamics "kinematic", the fast variant)
//   reward       r = alive_reward - position_weight e_p^2 - heading_weight e_psi (10, 2, 2):
//                e_p the horizontal distance to the pipe centre line [m], e_psi the heading
//                error to the pipe direction [rad, 0..pi]
//   terminated   e_p > termination_distance_m (2.5 m: the pipe leaves the view)
//   truncated    the end of the pipe reached (within end_margin_m) or max_steps actions
// Scenes: "random" draws a pipe world per reset: the `pipe_scenes` spec (a scene::WorldGenerator
// whose fields may be distributions) sampled by the one sampler and generated over the scenario's
// world; training seeds and evaluation seeds map to disjoint scene seeds (split train: [0, 2^62),
// eval: [2^62, 2^63)); "fixed" flies the scenario's world (the paper's ~20 m left + right pipe:
// the evaluation scene).
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "unav_common/config.hpp"
#include "unav_common/sampling.hpp"
#include "unav_control/pipe_action.hpp"
#include "unav_renderer/gl_thread.hpp"
#include "unav_scene/world_generator.hpp"
#include "unav_sim/episode.hpp"

namespace unav::sim {

struct PipeFollowingParams {
  std::string dynamics = "mpc";
  std::string scenes = "random";
  std::string split = "train";
  std::string camera = "down";
  control::PipeActionParams action;  ///< step_length_m, max_step_angle_deg, max_turn_deg
  double step_duration_s = 1.5;
  double height_above_pipe_m = 1.5;
  double termination_distance_m = 2.5;
  double end_margin_m = 1.0;
  int max_steps = 200;
  double start_offset_m = 0.5;
  double start_heading_deg = 20.0;
  double start_arc_fraction = 0.3;
  double alive_reward = 10.0;
  double position_weight = 2.0;
  double heading_weight = 2.0;

  template <class Archive>
  void Serialize(Archive* a) {
    using unav::common::Field;
    a->Visit(Field("dynamics", &dynamics)
                 .OneOf({"mpc", "kinematic"})
                 .Doc("mpc: the MPC flies each waypoint; kinematic: the vehicle is placed on it (fast)"));
    a->Visit(Field("scenes", &scenes)
                 .OneOf({"random", "fixed"})
                 .Doc("random pipe worlds (pipe_scenes over the scenario's world) or the scenario's world"));
    a->Visit(Field("split", &split).OneOf({"train", "eval"}).Doc("seed space of random scenes (disjoint)"));
    a->Visit(Field("camera", &camera).Doc("observation camera (of the episode's cameras)"));
    action.Serialize(a);
    a->Visit(
        Field("step_duration_s", &step_duration_s).Above(0.0).Max(30.0).Unit("s").Doc("simulated time per action"));
    a->Visit(Field("height_above_pipe_m", &height_above_pipe_m).Above(0.0).Unit("m").Doc("flight height (held)"));
    a->Visit(
        Field("termination_distance_m", &termination_distance_m).Above(0.0).Unit("m").Doc("e_p beyond: terminated"));
    a->Visit(Field("end_margin_m", &end_margin_m).Min(0.0).Unit("m").Doc("truncated this close to the pipe end"));
    a->Visit(Field("max_steps", &max_steps).Range(1, 1000000).Doc("truncated after this many actions"));
    a->Visit(Field("start_offset_m", &start_offset_m).Min(0.0).Unit("m").Doc("max lateral offset at reset"));
    a->Visit(
        Field("start_heading_deg", &start_heading_deg).Range(0.0, 180.0).Unit("deg").Doc("max heading error at reset"));
    a->Visit(Field("start_arc_fraction", &start_arc_fraction)
                 .Range(0.0, 0.9)
                 .Doc("random scenes start anywhere in this first fraction of the pipe"));
    a->Visit(Field("alive_reward", &alive_reward).Doc("r = alive - wp e_p^2 - wh e_psi"));
    a->Visit(Field("position_weight", &position_weight).Min(0.0));
    a->Visit(Field("heading_weight", &heading_weight).Min(0.0));
  }
};

/// A learning config file (config/learning/pipe_following.yaml): the sections `env`, `scenario`
/// (scene::Scenario: world, vehicle, physics, control, cameras, render; its mission is the
/// env's; a scenario file's path, e.g. scenarios/pipe_following.yaml, which the deploy launch
/// takes too, or the section itself) and `pipe_scenes` (the scene::WorldGenerator of random
/// scenes, any field a distribution); each absent section keeps its defaults.
struct PipeFollowingConfig {
  PipeFollowingParams env;
  scene::Scenario scenario;
  unav::common::Stochastic<scene::WorldGenerator> scenes{YAML::Node(YAML::NodeType::Map), "pipe_scenes"};
};
PipeFollowingConfig load_pipe_following_config(const std::string& path);
/// `config` for the paper's evaluation: the fixed world (the scenario's), the start on the pipe's
/// beginning heading along it (no random offset, heading or arc position), `dynamics` (mpc or
/// kinematic) and the camera at width x height (0 x 0: its own size).
PipeFollowingConfig evaluation_config(PipeFollowingConfig config, const std::string& dynamics, int width = 0,
                                      int height = 0);
/// Sets "env.max_steps", "scenario.cameras.width", "pipe_scenes.pipeline.legs" ... or a bare env key
/// ("max_steps") from YAML text. Unknown keys throw ConfigError listing the valid ones.
void apply_override(PipeFollowingConfig* config, const std::string& key, const std::string& yaml_value,
                    const std::string& source);

struct PipeFollowingInfo {
  double e_p = 0;           ///< horizontal distance to the centre line [m]
  double e_psi = 0;         ///< heading error [rad], 0..pi
  double lateral_m = 0;     ///< signed, > 0 right of the pipe
  double arc_length_m = 0;  ///< nearest point's arc length from the pipe start
  double progress = 0;      ///< arc_length / pipe length
  double pipe_length_m = 0;
  double time_s = 0;  ///< simulated time since reset
  int steps = 0;
  bool pipe_end = false;  ///< truncated at the pipe end
  std::uint64_t scene_seed = 0;
  std::uint64_t clipped_actions = 0;   ///< since construction: components outside [-1, 1]
  std::uint64_t rejected_actions = 0;  ///< since construction: NaN/Inf (replaced by 0, never integrated)
  std::array<double, 3> position_W{0, 0, 0};
  double yaw = 0;
};

struct PipeFollowingStep {
  double reward = 0;
  bool terminated = false;
  bool truncated = false;
  PipeFollowingInfo info;
};

class PipeFollowingEnv {
 public:
  /// Throws ConfigError (bad config), EglError (no context). `context`: share an EGL context.
  explicit PipeFollowingEnv(PipeFollowingConfig config, std::shared_ptr<unav::renderer::EglContext> context = nullptr);
  ~PipeFollowingEnv();

  int obs_width() const;
  int obs_height() const;

  /// New episode: scene (random: drawn from the seed and split), start pose from the seed.
  /// Returns the info; the observation is observe().
  PipeFollowingInfo reset(std::uint64_t seed);
  /// Applies the action (clipped; NaN/Inf components replaced by 0 and counted) and the dynamics;
  /// the observation of the new state is observe().
  PipeFollowingStep act(const std::array<double, 2>& action);
  /// The observation (H x W x 3 rgb8) of the current state.
  std::vector<std::uint8_t> observe();
  /// Split observe(): start the frame, then wait for it (vector envs overlap the N frames).
  void submit_observation();
  std::vector<std::uint8_t> collect_observation();

  /// Privileged expert (knows the pipe): the action steering to the centre line 2 m ahead and
  /// turning to the pipe direction there. Behaviour cloning and the upper-bound baseline.
  std::array<double, 2> expert_action() const;
  /// The waypoint an action leads to from the current state: NED position and yaw.
  std::pair<Eigen::Vector3d, double> waypoint_for(const std::array<double, 2>& action) const;
  PipeFollowingInfo info() const;

  /// Sets an env parameter for the next reset() ("max_steps", "start_offset_m", "split", ...;
  /// gymnasium reset options). Unknown keys, bad values and the keys fixed at construction
  /// (scenes, world, camera) throw ConfigError naming the key.
  void set_option(const std::string& key, const std::string& yaml_value);

  const PipeFollowingConfig& config() const { return config_; }
  Episode& episode() { return *episode_; }

 private:
  PipeFollowingInfo measure() const;
  PipeFollowingConfig config_;
  scene::World base_world_;  ///< the scenario's world: the fixed scene, or the base of random ones
  std::unique_ptr<Episode> episode_;
  double hold_depth_ = 0;
  int steps_ = 0;
  std::uint64_t scene_seed_ = 0;
  std::uint64_t clipped_ = 0, rejected_ = 0;
  bool pipe_end_ = false;
};

/// N environments stepped together in one process: the dynamics (MPC + physics) of the N envs on
/// `num_threads` threads, then the N frames submitted before any is read back. The frames are
/// rendered on GL threads that own the EGL contexts: one context, or on llvmpipe two on two EGL
/// displays (even envs on the first, odd on the second; each display has its own rasterizer
/// threads, and the two render at once: second_llvmpipe_display()). The observations are those of
/// single envs, bit for bit, whatever the split.
class VectorPipeFollowingEnv {
 public:
  /// num_threads: 0 = std::thread::hardware_concurrency(); 1 = all dynamics on the calling thread.
  /// contexts: 0 = two on llvmpipe (two displays) when there are two envs or more, else one; 1 = one.
  VectorPipeFollowingEnv(const PipeFollowingConfig& config, int num_envs, int num_threads = 0, int contexts = 0);
  ~VectorPipeFollowingEnv();  ///< each env is destroyed on its GL thread
  int size() const { return static_cast<int>(envs_.size()); }
  /// Env i, for what needs no GL (sizes, expert actions, options); its reset and frames go
  /// through reset()/reset_some()/step() (its context is current on its GL thread only).
  PipeFollowingEnv& env(int i) { return *envs_.at(static_cast<std::size_t>(i)); }
  /// How many EGL contexts render (1, or 2 on llvmpipe with 2 envs or more).
  int contexts() const { return static_cast<int>(gl_.size()); }
  /// act() on every env, then the N observations (concatenated, N x H x W x 3). `resets`
  /// (empty, or one entry per env): a seed resets that env instead of acting (its step has
  /// reward 0, no flags, the reset's info): gymnasium's next-step autoreset.
  std::vector<PipeFollowingStep> step(const std::vector<std::array<double, 2>>& actions,
                                      std::vector<std::uint8_t>* observations,
                                      const std::vector<std::optional<std::uint64_t>>& resets = {});
  /// Resets every env (one seed each) and observes all.
  std::vector<PipeFollowingInfo> reset(const std::vector<std::uint64_t>& seeds,
                                       std::vector<std::uint8_t>* observations);
  /// Resets the envs with a seed (nullopt: untouched); the N observations with zeros for the
  /// untouched envs.
  std::vector<std::optional<PipeFollowingInfo>> reset_some(const std::vector<std::optional<std::uint64_t>>& seeds,
                                                           std::vector<std::uint8_t>* observations);
  /// observe() of every env into one N x H x W x 3 buffer.
  void observe_all(std::vector<std::uint8_t>* observations);

 private:
  void build(const PipeFollowingConfig& config, int num_envs, int contexts);
  void release();  ///< destroys the envs, each on its GL thread
  unav::renderer::GlThread& gl_of(std::size_t env) { return *gl_[env % gl_.size()]; }
  /// Env i's reset for the seeds given, on its GL thread, every GL thread at once.
  void reset_on_gl(const std::vector<std::optional<std::uint64_t>>& seeds,
                   std::vector<std::optional<PipeFollowingInfo>>* infos);
  /// work(g) on GL thread g (its envs are g, g + contexts(), ...), every thread at once; rethrows
  /// the first error once all are done.
  void on_each_gl_thread(const std::function<void(std::size_t)>& work);
  /// The frames of the envs in `which` (all: empty), each GL thread rendering its own at once.
  void observe(const std::vector<bool>& which, std::vector<std::uint8_t>* observations);

  std::vector<std::unique_ptr<unav::renderer::GlThread>> gl_;  // before envs_: destroyed after them
  std::vector<std::unique_ptr<PipeFollowingEnv>> envs_;
  int threads_ = 1;
};

}  // namespace unav::sim
