#include "unav_sim/episode.hpp"

#include "unav_physics/current.hpp"

#include <chrono>
#include <cmath>
#include <utility>

#include "unav_common/errors.hpp"
#include "unav_common/resources.hpp"
#include "unav_physics/vehicle.hpp"
#include "unav_scene/camera.hpp"

namespace unav::sim {
namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// A config path: absolute, or relative to a resource root's config/ folder.
std::string config_path(const std::string& p) {
  if (!p.empty() && p.front() == '/') return p;
  return unav::common::find_resource("config/" + p);
}

// SplitMix64: decorrelated 64-bit seeds for the noise sources from the episode seed.
std::uint64_t mix(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ULL;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ULL;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBULL;
  return x ^ (x >> 31);
}

}  // namespace

scene::CameraModel scale_camera(const scene::CameraModel& camera, int width, int height) {
  if (width <= 0 || height <= 0 || (width == camera.width && height == camera.height)) return camera;
  scene::CameraModel c = camera;
  const double sx = static_cast<double>(width) / camera.width, sy = static_cast<double>(height) / camera.height;
  c.width = width;
  c.height = height;
  c.fx *= sx;
  c.fy *= sy;
  // Pixel centres: u' + 0.5 = sx (u + 0.5).
  c.cx = sx * (camera.cx + 0.5) - 0.5;
  c.cy = sy * (camera.cy + 0.5) - 0.5;
  return c;
}

EpisodeSetup load_episode_setup(const EpisodeParams& params) {
  unav::common::Validate(params, "episode");
  EpisodeSetup s;
  s.params = params;
  s.plant = physics::load_vehicle(config_path(params.vehicle_config));
  s.simulator.dt = params.physics_dt;
  physics::parse_integrator(params.integrator, &s.simulator.integrator);
  // The episode sends a command every control period; the failsafe would only mask a bug.
  s.simulator.command_timeout = 0.0;
  const double ratio = params.control_period / params.physics_dt;
  if (std::abs(ratio - std::round(ratio)) > 1e-6)
    throw ConfigError("episode", "control_period", std::to_string(params.control_period),
                      "must be a whole multiple of physics_dt (" + std::to_string(params.physics_dt) + " s)");
  s.mpc = control::load_mpc_config(config_path(params.mpc_config));
  s.mpc.options.max_solve_time_ms = 0.0;  // iterations only: episodes repeat exactly
  s.allocator = control::load_allocator_config(config_path(params.allocator_config));
  const std::string cams = config_path(params.cameras_config);
  if (params.cameras.empty()) throw ConfigError(cams, "cameras", "[]", "at least one camera to render");
  for (const auto& name : params.cameras)
    s.cameras.push_back(scale_camera(scene::load_camera(cams, name), params.image_width, params.image_height));
  if ((params.image_width > 0) != (params.image_height > 0))
    throw ConfigError("episode", "image_width/image_height",
                      std::to_string(params.image_width) + "x" + std::to_string(params.image_height),
                      "give both or neither");
  s.render.marine_snow = params.marine_snow;
  s.render.forward_scatter = params.forward_scatter;
  s.render.noise = params.camera_noise;
  s.render.materials = params.materials;
  s.render.shadows = params.shadows;
  s.render.caustics = params.caustics;
  s.render.lamp_scatter_samples = params.lamp_scatter_samples;
  s.render.readback_slots = 1;
  return s;
}

Episode::Episode(EpisodeSetup setup, World world, std::shared_ptr<unav::renderer::EglContext> context)
    : setup_(std::move(setup)) {
  // The world's water current (world.yaml `current: {file}`), as the physics server takes it.
  sim_ = std::make_unique<physics::Simulator>(
      setup_.plant, setup_.simulator, world.current_file.empty() ? nullptr : physics::load_current(world.current_file));
  control::MpcOptions mo = setup_.mpc.options;
  mpc_ = std::make_unique<control::Mpc>(setup_.mpc.model, mo, setup_.simulator.environment);
  allocator_ = std::make_unique<control::Allocator>(control::make_allocator(setup_.allocator));
  renderer_ =
      std::make_unique<unav::renderer::Renderer>(std::move(world), setup_.cameras, setup_.render, std::move(context));
  substeps_ = static_cast<int>(std::lround(setup_.params.control_period / setup_.params.physics_dt));
  reset(0, RigidBodyState{});
}

Episode::~Episode() = default;

const World& Episode::world() const { return renderer_->world(); }

void Episode::reset(std::uint64_t seed, const RigidBodyState& initial, const World* world) {
  if (world != nullptr) renderer_->set_world(*world);
  seed_ = seed;
  sim_->reset(initial);
  time_offset_ = 0.0;
  mpc_->Reset();
  unav::renderer::RenderOptions ro = renderer_->options();
  ro.seed = mix(seed);
  renderer_->set_options(ro);
  renderer_->set_next_sequence(0);
  const Eigen::Vector3d fwd = initial.q_WB * Eigen::Vector3d::UnitX();
  setpoint_ = control::PoseSetpoint::FromPositionYaw(initial.p_WB_W, std::atan2(fwd.y(), fwd.x()));
  solver_failures_ = 0;
}

void Episode::set_setpoint(const control::PoseSetpoint& setpoint) { setpoint_ = setpoint; }

void Episode::advance(double duration) {
  const int periods = std::max(1, static_cast<int>(std::lround(duration / setup_.params.control_period)));
  physics::ThrusterVector u;
  for (int k = 0; k < periods; ++k) {
    auto t0 = Clock::now();
    const double t = time();
    physics::Vector6d w;
    const control::MpcSummary ms = mpc_->Solve(sim_->state(), setpoint_, t, &w);
    if (!ms.ok()) ++solver_failures_;
    const control::AllocationSummary as = allocator_->Allocate(w, &u);
    if (as.status == control::AllocationStatus::kScaled || as.status == control::AllocationStatus::kInfeasible)
      mpc_->SetAppliedWrench(as.achieved);
    sim_->set_command(sim_->time(), u.data(), static_cast<std::size_t>(allocator_->num_thrusters()));
    timings_.control_s += seconds_since(t0);
    ++timings_.control_steps;
    t0 = Clock::now();
    for (int i = 0; i < substeps_; ++i) sim_->step();
    timings_.physics_s += seconds_since(t0);
    timings_.physics_steps += static_cast<std::uint64_t>(substeps_);
  }
}

void Episode::teleport(const RigidBodyState& x, double duration) {
  // Simulator::reset() zeroes its clock: the episode keeps the elapsed time as an offset.
  time_offset_ += sim_->time() + std::max(0.0, duration);
  sim_->reset(x);
  mpc_->Reset();
}

Frame Episode::render(const std::string& camera) {
  submit(camera);
  return collect();
}

void Episode::submit(const std::string& camera) {
  const auto t0 = Clock::now();
  const auto& x = sim_->state();
  scene::Pose X_WB = scene::Pose::Identity();
  X_WB.linear() = x.q_WB.toRotationMatrix();
  X_WB.translation() = x.p_WB_W;
  unav::renderer::BodyVelocity velocity;  // motion blur of cameras with an exposure time, as over DDS
  velocity.linear = x.v_WB_B;
  velocity.angular = x.w_WB_B;
  renderer_->submit(X_WB, camera, time(), velocity);
  timings_.render_s += seconds_since(t0);
}

Frame Episode::collect() {
  const auto t0 = Clock::now();
  std::optional<Frame> f = renderer_->collect();
  timings_.readback_s += seconds_since(t0);
  if (!f) throw std::logic_error("Episode::collect without submit");
  ++timings_.frames;
  return std::move(*f);
}

}  // namespace unav::sim
