// In-process episode: the physics Simulator (plant, 1 kHz), the MPC + allocator (the navigation
// stack's lower half), a renderer (one EGL context, one or more cameras) and a scene, stepped by
// the caller with no DDS and no lockstep. The gym environment and data generation embed it.
//
//   unav::sim::Episode ep(unav::sim::load_episode_setup(params), world);
//   ep.reset(seed, initial_state);             // new scene: ep.reset(seed, x0, &other_world)
//   ep.set_setpoint(PoseSetpoint::FromPositionYaw(p, yaw));
//   ep.advance(1.5);                           // MPC at control_period, physics at dt
//   Frame f = ep.render("down");              // at the current state and time
//
// Determinism: the MPC is bounded by iterations only (max_solve_time_ms forced to 0), every noise
// source is seeded from reset()'s seed, so the same seed and the same calls give the same
// states and images on the same platform.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "unav_common/config.hpp"
#include "unav_control/allocator.hpp"
#include "unav_control/config.hpp"
#include "unav_control/mpc.hpp"
#include "unav_physics/simulator.hpp"
#include "unav_renderer/renderer.hpp"
#include "unav_scene/world.hpp"

namespace unav::sim {

using unav::physics::RigidBodyState;
using unav::renderer::Frame;
using unav::scene::World;

/// What an episode is made of, as files (relative paths: under the resource roots' config/,
/// see unav_common/resources.hpp) and switches. Config schema (config/learning/*.yaml `episode:`).
struct EpisodeParams {
  std::string vehicle_config = "vehicles/bluerov2_heavy.yaml";  ///< the plant
  std::string mpc_config = "controllers/mpc.yaml";
  std::string allocator_config = "controllers/allocator.yaml";
  std::string cameras_config = "sensors/bluerov2_cameras.yaml";
  std::vector<std::string> cameras{"down"};
  /// Render size of every camera (intrinsics scaled); 0 = as in cameras_config.
  int image_width = 0;
  int image_height = 0;
  double physics_dt = 0.001;
  std::string integrator = "velocity_verlet";
  double control_period = 0.05;
  bool marine_snow = true;
  bool forward_scatter = true;
  bool camera_noise = true;
  bool materials = true;  ///< RenderOptions::materials: relief, highlights, sediment
  bool shadows = true;    ///< RenderOptions::shadows: sun and lamp shadow maps
  bool caustics = true;   ///< RenderOptions::caustics: sunlight caustics on the seabed
  int lamp_scatter_samples = 8;

  template <class Archive>
  void Serialize(Archive* a) {
    using unav::common::Field;
    a->Visit(Field("vehicle_config", &vehicle_config).Doc("plant vehicle YAML, relative to config/ or absolute"));
    a->Visit(Field("mpc_config", &mpc_config).Doc("mpc_controller params file, relative to config/ or absolute"));
    a->Visit(Field("allocator_config", &allocator_config).Doc("control_allocator params file"));
    a->Visit(Field("cameras_config", &cameras_config).Doc("camera set (mounts, intrinsics)"));
    a->Visit(Field("cameras", &cameras).Doc("cameras of cameras_config to render"));
    a->Visit(Field("image_width", &image_width).Range(0, 8192).Unit("px").Doc("render width, 0 = camera's"));
    a->Visit(Field("image_height", &image_height).Range(0, 8192).Unit("px").Doc("render height, 0 = camera's"));
    a->Visit(Field("physics_dt", &physics_dt).Above(0.0).Max(0.05).Unit("s").Doc("physics step"));
    a->Visit(Field("integrator", &integrator).OneOf({"velocity_verlet", "rk4"}));
    a->Visit(Field("control_period", &control_period)
                 .Above(0.0)
                 .Max(1.0)
                 .Unit("s")
                 .Doc("MPC + allocator period; a multiple of physics_dt"));
    a->Visit(Field("marine_snow", &marine_snow));
    a->Visit(Field("forward_scatter", &forward_scatter));
    a->Visit(Field("camera_noise", &camera_noise));
    a->Visit(Field("materials", &materials).Doc("relief (bump), GGX highlights and sediment in the images"));
    a->Visit(Field("shadows", &shadows).Doc("shadow maps of the sun and of every lamp"));
    a->Visit(Field("caustics", &caustics).Doc("animated sunlight caustics on the seabed"));
    a->Visit(Field("lamp_scatter_samples", &lamp_scatter_samples).Range(0, 64).Doc("0 = no lamp in-scattering"));
  }
};

/// EpisodeParams resolved and loaded (vehicle, controllers, cameras).
struct EpisodeSetup {
  EpisodeParams params;
  physics::VehicleParams plant;
  physics::SimulatorOptions simulator;
  control::MpcConfig mpc;
  control::AllocatorConfig allocator;
  std::vector<scene::CameraModel> cameras;
  unav::renderer::RenderOptions render;
};
/// Loads every file of `params`; throws ConfigError naming the file/key on any problem.
EpisodeSetup load_episode_setup(const EpisodeParams& params);

/// The camera scaled to width x height (same field of view, principal point and distortion
/// scaled with the image).
scene::CameraModel scale_camera(const scene::CameraModel& camera, int width, int height);

/// Wall time spent per part, accumulated since construction (for benchmarks).
struct EpisodeTimings {
  double physics_s = 0, control_s = 0, render_s = 0, readback_s = 0;
  std::uint64_t physics_steps = 0, control_steps = 0, frames = 0;
};

class Episode {
 public:
  /// Builds the simulator, controllers and renderer for `world`. `context`: an EGL context to
  /// share (vectorised environments); null = a new one. Throws ConfigError / EglError.
  Episode(EpisodeSetup setup, World world, std::shared_ptr<unav::renderer::EglContext> context = nullptr);
  ~Episode();
  Episode(const Episode&) = delete;
  Episode& operator=(const Episode&) = delete;

  /// Time 0, vehicle at `initial` at rest, controllers forgotten, setpoint = hold `initial`;
  /// every noise source (camera noise, marine snow phase) seeded from `seed`. `world`: replace
  /// the scene (geometry re-uploaded, GL context, shaders and targets kept); null = keep it.
  void reset(std::uint64_t seed, const RigidBodyState& initial, const World* world = nullptr);

  void set_setpoint(const control::PoseSetpoint& setpoint);
  const control::PoseSetpoint& setpoint() const { return setpoint_; }
  /// Closed loop for `duration` s (rounded to whole control periods, at least one): each period
  /// the MPC solves for the setpoint, the allocator maps the wrench to thruster commands, the
  /// physics integrates.
  void advance(double duration);
  /// Places the vehicle at `x` (kinematic moves: no dynamics); time goes on by `duration` s.
  void teleport(const RigidBodyState& x, double duration);

  /// Renders `camera` at the current state and time (synchronous).
  Frame render(const std::string& camera);
  /// Pipelined rendering: submit() starts a frame, collect() waits for the oldest one.
  void submit(const std::string& camera);
  Frame collect();

  const RigidBodyState& state() const { return sim_->state(); }
  double time() const { return time_offset_ + sim_->time(); }  ///< s since reset()
  const World& world() const;
  const EpisodeSetup& setup() const { return setup_; }
  const EpisodeTimings& timings() const { return timings_; }
  physics::Simulator& simulator() { return *sim_; }
  unav::renderer::Renderer& renderer() { return *renderer_; }
  /// MPC solver failures and allocator saturations since reset().
  int solver_failures() const { return solver_failures_; }

 private:
  EpisodeSetup setup_;
  std::unique_ptr<physics::Simulator> sim_;
  std::unique_ptr<control::Mpc> mpc_;
  std::unique_ptr<control::Allocator> allocator_;
  std::unique_ptr<unav::renderer::Renderer> renderer_;
  control::PoseSetpoint setpoint_;
  EpisodeTimings timings_;
  std::uint64_t seed_ = 0;
  int solver_failures_ = 0;
  int substeps_ = 50;
  double time_offset_ = 0.0;  // time before the last teleport()
};

}  // namespace unav::sim
