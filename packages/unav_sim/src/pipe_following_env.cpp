#include "unav_sim/pipe_following_env.hpp"

#include <algorithm>
#include <cmath>
#include <exception>
#include <filesystem>
#include <functional>
#include <future>
#include <mutex>
#include <random>
#include <thread>

#include "unav_common/errors.hpp"
#include "unav_common/resources.hpp"
#include "unav_control/pipe_action.hpp"

namespace unav::sim {
namespace {

constexpr double kDeg = M_PI / 180.0;
constexpr std::uint64_t kSceneSeedMask = (std::uint64_t{1} << 62U) - 1U;

double wrap(double a) { return std::remainder(a, 2.0 * M_PI); }  // (-pi, pi]

// The random scenes' spec drawn with `seed`, its cross-field rules checked and its paths
// resolved (relative to the file that holds it, then the resource roots). Throws ConfigError.
scene::WorldGenerator draw_scene(const unav::common::Stochastic<scene::WorldGenerator>& scenes, std::uint64_t seed) {
  scene::WorldGenerator g = scenes.Sample(seed);
  scene::check_world_generator(g, scenes.file(), "pipe_scenes.");
  scene::resolve_world_generator_paths(&g, std::filesystem::path(scenes.file()).parent_path().string(), scenes.file(),
                                       "pipe_scenes.");
  return g;
}

double yaw_of(const Eigen::Quaterniond& q) {
  const Eigen::Vector3d f = q * Eigen::Vector3d::UnitX();
  return std::atan2(f.y(), f.x());
}

RigidBodyState level_state(const Eigen::Vector3d& p, double yaw) {
  RigidBodyState x;
  x.p_WB_W = p;
  x.q_WB = Eigen::Quaterniond(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()));
  return x;
}

// Centre-line point and heading at arc length s (clamped to the pipe).
std::pair<Eigen::Vector3d, double> point_at(const scene::Pipeline& pipe, double s) {
  const auto& a = pipe.arc_length_m;
  const auto& c = pipe.centerline_W;
  if (c.size() < 2) return {c.empty() ? Eigen::Vector3d::Zero() : c.front(), 0.0};
  s = std::clamp(s, 0.0, a.back());
  std::size_t k = static_cast<std::size_t>(std::upper_bound(a.begin(), a.end(), s) - a.begin());
  k = std::clamp<std::size_t>(k, 1, c.size() - 1);
  const double seg = a[k] - a[k - 1];
  const double t = seg > 0 ? (s - a[k - 1]) / seg : 0.0;
  const Eigen::Vector3d d = c[k] - c[k - 1];
  return {c[k - 1] + t * d, std::atan2(d.y(), d.x())};
}

// A learning config's scenario as {file: F, set: [key=value, ...]}: a scenario file with some of
// its keys replaced (the language of a node's scenario_set), e.g. a render profile for learning.
struct ScenarioReference {
  std::string file;
  std::vector<std::string> set;
  template <class Archive>
  void Serialize(Archive* a) {
    using unav::common::Field;
    a->Visit(Field("file", &file).Doc("scenario file (config/scenarios/*.yaml)"));
    a->Visit(Field("set", &set).Doc("its keys replaced: [key.path=value, ...]"));
  }
};

}  // namespace

PipeFollowingConfig load_pipe_following_config(const std::string& path) {
  const YAML::Node root = unav::common::detail::ReadYamlFile(path);
  PipeFollowingConfig c;
  if (!root || root.IsNull()) return c;
  if (!root.IsMap()) throw ConfigError(path, "", "", "expected a mapping with env, scenario, pipe_scenes");
  for (const auto& kv : root) {
    const auto key = kv.first.as<std::string>();
    if (key != "env" && key != "scenario" && key != "pipe_scenes")
      throw ConfigError(path, key, "", "unknown section (allowed: env, scenario, pipe_scenes)");
  }
  if (root["env"]) unav::common::LoadYaml(root, path, &c.env, "env");
  const std::string dir = std::filesystem::path(path).parent_path().string();
  const YAML::Node sc = root["scenario"];
  if (sc && sc.IsScalar()) {  // a scenario file, as the deploy launch takes it
    c.scenario = scene::load_scenario(scene::find_scenario_file(sc.as<std::string>(), dir, path, "scenario"));
  } else if (sc && sc.IsMap() && sc["file"]) {
    ScenarioReference ref;
    unav::common::LoadYaml(root, path, &ref, "scenario");
    c.scenario =
        scene::load_scenario_param(scene::find_scenario_file(ref.file, dir, path, "scenario.file"), -1, ref.set);
  } else if (sc) {
    unav::common::LoadYaml(root, path, &c.scenario, "scenario");
    scene::resolve_scenario_paths(&c.scenario, path, dir);
  }
  if (root["pipe_scenes"]) c.scenes = unav::common::Stochastic<scene::WorldGenerator>(root["pipe_scenes"], path);
  (void)draw_scene(c.scenes, 0);
  return c;
}

PipeFollowingConfig evaluation_config(PipeFollowingConfig config, const std::string& dynamics, int width, int height) {
  config.env.scenes = "fixed";
  config.env.dynamics = dynamics;
  config.env.start_offset_m = 0.0;
  config.env.start_heading_deg = 0.0;
  config.env.start_arc_fraction = 0.0;
  config.scenario.cameras.width = width;
  config.scenario.cameras.height = height;
  return config;
}

void apply_override(PipeFollowingConfig* config, const std::string& key, const std::string& yaml_value,
                    const std::string& source) {
  PipeFollowingConfig c = *config;
  const auto dot = key.find('.');
  const std::string section = dot == std::string::npos ? "" : key.substr(0, dot);
  const std::string rest = dot == std::string::npos ? key : key.substr(dot + 1);
  if (section == "scenario") {
    unav::common::ApplyOverride(&c.scenario, rest, yaml_value, source);
  } else if (section == "pipe_scenes") {
    c.scenes = unav::common::Stochastic<scene::WorldGenerator>(
        scene::apply_scenario_overrides(c.scenes.spec(), {rest + "=" + yaml_value}, source), source);
    (void)draw_scene(c.scenes, 0);
  } else if (section == "env") {
    unav::common::ApplyOverride(&c.env, rest, yaml_value, source);
  } else {
    unav::common::ApplyOverride(&c.env, key, yaml_value, source);
  }
  *config = std::move(c);
}

PipeFollowingEnv::PipeFollowingEnv(PipeFollowingConfig config, std::shared_ptr<unav::renderer::EglContext> context)
    : config_(std::move(config)) {
  unav::common::Validate(config_.env, "env");
  const auto& cams = config_.scenario.cameras.names;
  if (std::find(cams.begin(), cams.end(), config_.env.camera) == cams.end())
    throw ConfigError("env", "camera", config_.env.camera, "must be one of scenario.cameras.names");
  EpisodeSetup setup = load_episode_setup(config_.scenario);
  base_world_ = scene::scenario_world(config_.scenario);
  scene::World first;
  if (config_.env.scenes == "fixed") {
    if (base_world_.pipelines.empty())
      throw ConfigError(config_.scenario.world, "pipelines", "[]", "the pipe-following world needs a pipeline");
    first = base_world_;
  } else {
    first = scene::generate_world(draw_scene(config_.scenes, 0), base_world_, 0);
  }
  episode_ = std::make_unique<Episode>(std::move(setup), std::move(first), std::move(context));
  reset(0);
}

PipeFollowingEnv::~PipeFollowingEnv() = default;

int PipeFollowingEnv::obs_width() const { return episode_->renderer().camera(config_.env.camera).width; }
int PipeFollowingEnv::obs_height() const { return episode_->renderer().camera(config_.env.camera).height; }

PipeFollowingInfo PipeFollowingEnv::reset(std::uint64_t seed) {
  const PipeFollowingParams& p = config_.env;
  std::mt19937_64 rng(seed * 0x9E3779B97F4A7C15ULL + 0x632BE59BD9B4E019ULL);
  auto U = [&rng](double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng); };
  scene::World world;
  const scene::World* new_world = nullptr;
  if (p.scenes == "random") {
    scene_seed_ = (seed & kSceneSeedMask) | (p.split == "eval" ? (std::uint64_t{1} << 62U) : 0U);
    world = scene::generate_world(draw_scene(config_.scenes, scene_seed_), base_world_, scene_seed_);
    new_world = &world;
  } else {
    scene_seed_ = 0;
  }
  const scene::World& w = new_world ? *new_world : episode_->world();
  const scene::Pipeline& pipe = w.pipelines.front();
  const double s0 = U(0.0, 1.0) * p.start_arc_fraction * pipe.length_m();
  const auto [c, h] = point_at(pipe, s0);
  const double offset = U(-1.0, 1.0) * p.start_offset_m;
  const double yaw = wrap(h + U(-1.0, 1.0) * p.start_heading_deg * kDeg);
  const Eigen::Vector3d right(-std::sin(h), std::cos(h), 0.0);
  Eigen::Vector3d p0 = c + offset * right;
  p0.z() = c.z() - p.height_above_pipe_m;
  hold_depth_ = p0.z();
  episode_->reset(seed, level_state(p0, yaw), new_world);
  steps_ = 0;
  pipe_end_ = false;
  return measure();
}

std::pair<Eigen::Vector3d, double> PipeFollowingEnv::waypoint_for(const std::array<double, 2>& a) const {
  const PipeFollowingParams& p = config_.env;
  const auto& x = episode_->state();
  const control::PoseSetpoint sp = control::waypoint_from_action(x.p_WB_W, yaw_of(x.q_WB), a, p.action, hold_depth_);
  return {sp.p_W, yaw_of(sp.q_WB)};
}

PipeFollowingStep PipeFollowingEnv::act(const std::array<double, 2>& action) {
  std::array<double, 2> a = action;
  for (double& v : a) {
    if (!std::isfinite(v)) {
      v = 0.0;
      ++rejected_;
    } else if (v < -1.0 || v > 1.0) {
      v = std::clamp(v, -1.0, 1.0);
      ++clipped_;
    }
  }
  const auto [wp, yaw] = waypoint_for(a);
  if (config_.env.dynamics == "kinematic") {
    episode_->teleport(level_state(wp, yaw), config_.env.step_duration_s);
  } else {
    episode_->set_setpoint(control::PoseSetpoint::FromPositionYaw(wp, yaw));
    episode_->advance(config_.env.step_duration_s);
  }
  ++steps_;
  PipeFollowingStep r;
  r.info = measure();
  const PipeFollowingParams& p = config_.env;
  r.reward = p.alive_reward - p.position_weight * r.info.e_p * r.info.e_p - p.heading_weight * r.info.e_psi;
  r.terminated = !(r.info.e_p <= p.termination_distance_m);  // NaN state terminates too
  pipe_end_ = r.info.arc_length_m >= r.info.pipe_length_m - p.end_margin_m;
  r.info.pipe_end = pipe_end_;
  r.truncated = !r.terminated && (pipe_end_ || steps_ >= p.max_steps);
  return r;
}

std::vector<std::uint8_t> PipeFollowingEnv::observe() {
  submit_observation();
  return collect_observation();
}

void PipeFollowingEnv::submit_observation() { episode_->submit(config_.env.camera); }

std::vector<std::uint8_t> PipeFollowingEnv::collect_observation() { return std::move(episode_->collect().rgb); }

std::array<double, 2> PipeFollowingEnv::expert_action() const {
  const PipeFollowingParams& p = config_.env;
  const auto& x = episode_->state();
  const double yaw = yaw_of(x.q_WB);
  const scene::PipeQuery q = scene::nearest_pipe_point(episode_->world(), x.p_WB_W, true);
  if (!q.valid) return {0.0, 0.0};
  const scene::Pipeline& pipe = episode_->world().pipelines[q.pipeline];
  const auto [target, heading] = point_at(pipe, q.arc_length_m + 2.0);
  const double dir = std::atan2(target.y() - x.p_WB_W.y(), target.x() - x.p_WB_W.x());
  auto ratio = [](double angle, double max_deg) {
    return max_deg > 0 ? std::clamp(angle / (max_deg * kDeg), -1.0, 1.0) : 0.0;
  };
  return {ratio(wrap(dir - yaw), p.action.max_step_angle_deg), ratio(wrap(heading - yaw), p.action.max_turn_deg)};
}

PipeFollowingInfo PipeFollowingEnv::measure() const {
  PipeFollowingInfo i;
  const auto& x = episode_->state();
  const double yaw = yaw_of(x.q_WB);
  const scene::PipeQuery q = scene::nearest_pipe_point(episode_->world(), x.p_WB_W, true);
  i.e_p = q.horizontal_distance_m;
  i.e_psi = std::abs(wrap(yaw - q.heading_rad));
  i.lateral_m = q.lateral_m;
  i.arc_length_m = q.arc_length_m;
  i.pipe_length_m = episode_->world().pipelines[q.pipeline].length_m();
  i.progress = i.pipe_length_m > 0 ? i.arc_length_m / i.pipe_length_m : 0.0;
  i.time_s = episode_->time();
  i.steps = steps_;
  i.pipe_end = pipe_end_;
  i.scene_seed = scene_seed_;
  i.clipped_actions = clipped_;
  i.rejected_actions = rejected_;
  i.position_W = {x.p_WB_W.x(), x.p_WB_W.y(), x.p_WB_W.z()};
  i.yaw = yaw;
  return i;
}

PipeFollowingInfo PipeFollowingEnv::info() const { return measure(); }

void PipeFollowingEnv::set_option(const std::string& key, const std::string& yaml_value) {
  if (key == "scenes" || key == "camera")
    throw ConfigError("reset options", key, yaml_value, "fixed when the environment is made (pass it to make())");
  PipeFollowingParams p = config_.env;
  unav::common::ApplyOverride(&p, key, yaml_value, "reset options");
  config_.env = p;
}

VectorPipeFollowingEnv::VectorPipeFollowingEnv(const PipeFollowingConfig& config, int num_envs, int num_threads,
                                               int contexts) {
  if (num_envs < 1) throw ConfigError("vector env", "num_envs", std::to_string(num_envs), "must be >= 1");
  if (contexts < 0 || contexts > 1)
    throw ConfigError("vector env", "contexts", std::to_string(contexts), "must be 0 (automatic) or 1");
  if (num_threads < 0) throw ConfigError("vector env", "num_threads", std::to_string(num_threads), "must be >= 0");
  threads_ = num_threads > 0 ? num_threads : std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  threads_ = std::min(threads_, num_envs);
  try {
    build(config, num_envs, contexts);
  } catch (...) {
    release();  // the envs built so far, each on its GL thread
    throw;
  }
}

void VectorPipeFollowingEnv::build(const PipeFollowingConfig& config, int num_envs, int contexts) {
  gl_.push_back(std::make_unique<unav::renderer::GlThread>());
  gl_[0]->run([&] { envs_.push_back(std::make_unique<PipeFollowingEnv>(config)); });
  std::shared_ptr<unav::renderer::EglContext> ctx[2] = {envs_[0]->episode().renderer().shared_context(), nullptr};
  if (num_envs > 1 && contexts == 0) {
    auto second = std::make_unique<unav::renderer::GlThread>();
    second->run([&] { ctx[1] = unav::renderer::second_llvmpipe_display(*ctx[0]); });
    if (ctx[1]) gl_.push_back(std::move(second));
  }
  for (int i = 1; i < num_envs; ++i) {
    const std::size_t g = static_cast<std::size_t>(i) % gl_.size();
    gl_[g]->run([&] { envs_.push_back(std::make_unique<PipeFollowingEnv>(config, ctx[g])); });
  }
  // The envs hold their contexts now; the last owner of each lets it go on its GL thread.
  if (ctx[1]) gl_[1]->run([&] { ctx[1].reset(); });
}

VectorPipeFollowingEnv::~VectorPipeFollowingEnv() { release(); }

void VectorPipeFollowingEnv::release() {
  for (std::size_t i = 0; i < envs_.size(); ++i) gl_of(i).run([this, i] { envs_[i].reset(); });
  envs_.clear();
}

std::vector<PipeFollowingInfo> VectorPipeFollowingEnv::reset(const std::vector<std::uint64_t>& seeds,
                                                             std::vector<std::uint8_t>* observations) {
  if (seeds.size() != envs_.size())
    throw std::invalid_argument("VectorPipeFollowingEnv::reset: " + std::to_string(seeds.size()) + " seeds for " +
                                std::to_string(envs_.size()) + " environments");
  std::vector<std::optional<PipeFollowingInfo>> some;
  reset_on_gl({seeds.begin(), seeds.end()}, &some);
  observe({}, observations);
  std::vector<PipeFollowingInfo> infos;
  infos.reserve(some.size());
  for (const auto& i : some) infos.push_back(*i);
  return infos;
}

std::vector<std::optional<PipeFollowingInfo>> VectorPipeFollowingEnv::reset_some(
    const std::vector<std::optional<std::uint64_t>>& seeds, std::vector<std::uint8_t>* observations) {
  if (seeds.size() != envs_.size())
    throw std::invalid_argument("VectorPipeFollowingEnv::reset_some: " + std::to_string(seeds.size()) +
                                " entries for " + std::to_string(envs_.size()) + " environments");
  std::vector<std::optional<PipeFollowingInfo>> infos;
  reset_on_gl(seeds, &infos);
  std::vector<bool> which(seeds.size());
  for (std::size_t i = 0; i < seeds.size(); ++i) which[i] = seeds[i].has_value();
  observe(which, observations);
  return infos;
}

void VectorPipeFollowingEnv::reset_on_gl(const std::vector<std::optional<std::uint64_t>>& seeds,
                                         std::vector<std::optional<PipeFollowingInfo>>* infos) {
  infos->assign(envs_.size(), std::nullopt);
  on_each_gl_thread([&](std::size_t first) {
    for (std::size_t i = first; i < envs_.size(); i += gl_.size())
      if (seeds[i]) (*infos)[i] = envs_[i]->reset(*seeds[i]);  // uploads the new scene: GL work
  });
}

void VectorPipeFollowingEnv::on_each_gl_thread(const std::function<void(std::size_t)>& work) {
  std::vector<std::future<void>> done;
  for (std::size_t g = 0; g < gl_.size(); ++g) done.push_back(gl_[g]->post([&work, g] { work(g); }));
  for (auto& d : done) d.wait();
  for (auto& d : done) d.get();  // the first error, once every thread is done
}

void VectorPipeFollowingEnv::observe(const std::vector<bool>& which, std::vector<std::uint8_t>* observations) {
  const std::size_t frame = static_cast<std::size_t>(envs_[0]->obs_width()) * envs_[0]->obs_height() * 3;
  observations->assign(frame * envs_.size(), 0);
  on_each_gl_thread([&](std::size_t first) {
    // All of this context's frames submitted before any is read back.
    for (std::size_t i = first; i < envs_.size(); i += gl_.size())
      if (which.empty() || which[i]) envs_[i]->submit_observation();
    for (std::size_t i = first; i < envs_.size(); i += gl_.size())
      if (which.empty() || which[i]) {
        const std::vector<std::uint8_t> o = envs_[i]->collect_observation();
        std::copy(o.begin(), o.end(), observations->begin() + static_cast<std::ptrdiff_t>(i * frame));
      }
  });
}

std::vector<PipeFollowingStep> VectorPipeFollowingEnv::step(const std::vector<std::array<double, 2>>& actions,
                                                            std::vector<std::uint8_t>* observations,
                                                            const std::vector<std::optional<std::uint64_t>>& resets) {
  if (!resets.empty() && resets.size() != envs_.size())
    throw std::invalid_argument("VectorPipeFollowingEnv::step: " + std::to_string(resets.size()) +
                                " reset entries for " + std::to_string(envs_.size()) + " environments");
  if (actions.size() != envs_.size())
    throw std::invalid_argument("VectorPipeFollowingEnv::step: " + std::to_string(actions.size()) + " actions for " +
                                std::to_string(envs_.size()) + " environments");
  std::vector<PipeFollowingStep> out;
  out.reserve(envs_.size());
  out.resize(envs_.size());
  // Env i's dynamics touch only env i (simulator, MPC, allocator): threads take every
  // threads_-th env; the results do not depend on the thread count.
  auto work = [&](std::size_t first) {
    for (std::size_t i = first; i < envs_.size(); i += static_cast<std::size_t>(threads_))
      if (resets.empty() || !resets[i]) out[i] = envs_[i]->act(actions[i]);
  };
  std::vector<std::thread> pool;
  std::exception_ptr error;
  std::mutex error_mutex;
  for (int t = 1; t < threads_; ++t)
    pool.emplace_back([&, t] {
      try {
        work(static_cast<std::size_t>(t));
      } catch (...) {
        const std::lock_guard<std::mutex> lock(error_mutex);
        error = std::current_exception();
      }
    });
  try {
    work(0);
  } catch (...) {
    const std::lock_guard<std::mutex> lock(error_mutex);
    error = std::current_exception();
  }
  for (auto& th : pool) th.join();
  if (error) std::rethrow_exception(error);
  if (!resets.empty()) {
    std::vector<std::optional<PipeFollowingInfo>> infos;
    reset_on_gl(resets, &infos);
    for (std::size_t i = 0; i < resets.size(); ++i)
      if (infos[i]) out[i].info = *infos[i];
  }
  observe({}, observations);
  return out;
}

void VectorPipeFollowingEnv::observe_all(std::vector<std::uint8_t>* observations) { observe({}, observations); }

}  // namespace unav::sim
