// In-process episode: the physics Simulator (plant, 1 kHz), the MPC + allocator (the navigation
// stack's lower half), a renderer (one EGL context, one or more cameras) and a scene, stepped by
// the caller with no DDS and no lockstep. The gym environment and data generation embed it.
//
//   unav::sim::Episode ep(unav::sim::load_episode_setup(scenario), world);
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
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "unav_common/config.hpp"
#include "unav_common/time.hpp"
#include "unav_control/allocator.hpp"
#include "unav_control/config.hpp"
#include "unav_control/mpc.hpp"
#include "unav_physics/simulator.hpp"
#include "unav_physics/vehicle.hpp"
#include "unav_renderer/renderer.hpp"
#include "unav_scene/scenario.hpp"
#include "unav_scene/world.hpp"

namespace unav::sim {

using unav::physics::RigidBodyState;
using unav::renderer::Frame;
using unav::scene::World;

/// A scenario resolved and loaded for an episode (vehicle, controllers, cameras, renderer): the
/// in-process half of the one builder (the plant: physics::build_simulator, as the physics server).
struct EpisodeSetup {
  scene::Scenario scenario;      ///< with its file paths resolved
  physics::VehicleParams plant;  ///< scenario.vehicle.model, loaded once (reset() rebuilds from it)
  physics::SimulatorOptions simulator;
  control::MpcConfig mpc;
  control::AllocatorConfig allocator;
  std::vector<scene::CameraModel> cameras;
  unav::renderer::RenderOptions render;
};
/// Loads every file the scenario names (relative paths resolved as load_scenario() does);
/// throws ConfigError naming the file/key on any problem.
EpisodeSetup load_episode_setup(const scene::Scenario& scenario);

/// Wall time spent per part, accumulated since construction (for benchmarks).
struct EpisodeTimings {
  double physics_s = 0, control_s = 0, render_s = 0, readback_s = 0;
  std::uint64_t physics_steps = 0, control_steps = 0, frames = 0;
};

class Episode {
 public:
  /// Builds the simulator (physics::build_simulator: the world's seabed and current, as the
  /// physics server), controllers and renderer for `world`. `context`: an EGL context to
  /// share (vectorised environments); null = a new one. Throws ConfigError / EglError.
  Episode(EpisodeSetup setup, World world, std::shared_ptr<unav::renderer::EglContext> context = nullptr);
  ~Episode();
  Episode(const Episode&) = delete;
  Episode& operator=(const Episode&) = delete;

  /// Time 0, vehicle at `initial` at rest, controllers forgotten, setpoint = hold `initial`;
  /// every noise source (camera noise, marine snow phase) seeded from `seed`. `world`: replace
  /// the scene (geometry re-uploaded, GL context, shaders and targets kept; the plant rebuilt on
  /// its seabed and current); null = keep it.
  void reset(std::uint64_t seed, const RigidBodyState& initial, const World* world = nullptr);

  void set_setpoint(const control::PoseSetpoint& setpoint);
  const control::PoseSetpoint& setpoint() const { return setpoint_; }
  /// Closed loop for `duration` s (rounded to whole control periods, at least one): each period
  /// the MPC solves for the setpoint, the allocator maps the wrench to thruster commands, the
  /// physics integrates. `after_step`, when given, runs after every physics step (e.g. to record
  /// the sensors, which sample at their own rates: the pressure sensor at 50 Hz is faster than
  /// the 20 Hz control).
  void advance(double duration, const std::function<void()>& after_step = {});
  /// Places the vehicle at `x` (kinematic moves: no dynamics); time goes on by `duration` s.
  void teleport(const RigidBodyState& x, double duration);

  /// Renders `camera` at the current state and time (synchronous).
  Frame render(const std::string& camera);
  /// Pipelined rendering: submit() starts a frame, collect() waits for the oldest one.
  void submit(const std::string& camera);
  Frame collect();

  const RigidBodyState& state() const { return sim_->state(); }
  /// s since reset(), as a stamp on the wire carries it (whole nanoseconds, then seconds: what the
  /// nodes of the same scenario compute from their messages' stamps), so that the MPC, the mission
  /// and the renderer see the very same double in process and over DDS.
  double time() const { return unav::Time::from_seconds(time_offset_ + sim_->time()).seconds(); }
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
