#include "unav_sim/episode.hpp"

#include <chrono>
#include <cmath>
#include <utility>

#include "unav_common/errors.hpp"
#include "unav_common/resources.hpp"
#include "unav_common/sampling.hpp"
#include "unav_physics/scenario_builder.hpp"
#include "unav_scene/camera.hpp"

namespace unav::sim {
namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

}  // namespace

EpisodeSetup load_episode_setup(const scene::Scenario& scenario) {
  EpisodeSetup s;
  s.scenario = scenario;
  unav::common::Validate(s.scenario, "scenario");
  scene::resolve_scenario_paths(&s.scenario, "scenario", "");
  const scene::Scenario& sc = s.scenario;
  if (!sc.fleet.empty())  // never fly a different run than the file describes
    throw unav::ConfigError(sc.name, "fleet", sc.fleet[0].name + (sc.fleet.size() > 1 ? ", ..." : ""),
                            "an in-process episode flies one vehicle: run a scenario with a fleet over DDS "
                            "(the physics server steps every vehicle)");
  // The episode sends a command every control period; the failsafe would only mask a bug.
  s.plant = physics::scenario_vehicle(sc);
  physics::require_fixed_usbl(s.plant, sc.name, "an in-process episode");
  s.simulator = physics::scenario_simulator_options(sc, 0.0);
  s.mpc = control::load_mpc_config(sc.control.mpc);
  s.mpc.options.max_solve_time_ms = 0.0;  // iterations only: episodes repeat exactly
  s.allocator = control::load_allocator_config(sc.control.allocator);
  s.cameras = scene::scenario_cameras(sc);
  static_cast<scene::RenderSettings&>(s.render) = sc.render;
  s.render.readback_slots = 1;
  return s;
}

Episode::Episode(EpisodeSetup setup, World world, std::shared_ptr<unav::renderer::EglContext> context)
    : setup_(std::move(setup)) {
  // The plant as the physics server builds it: the world's seabed and current.
  sim_ = physics::build_simulator(setup_.scenario, world, setup_.simulator, setup_.plant);
  control::MpcOptions mo = setup_.mpc.options;
  mpc_ = std::make_unique<control::Mpc>(setup_.mpc.model, mo, setup_.simulator.environment);
  allocator_ = std::make_unique<control::Allocator>(control::make_allocator(setup_.allocator));
  renderer_ =
      std::make_unique<unav::renderer::Renderer>(std::move(world), setup_.cameras, setup_.render, std::move(context));
  substeps_ = static_cast<int>(std::lround(setup_.scenario.control.period / setup_.scenario.physics.dt));
  reset(0, RigidBodyState{});
}

Episode::~Episode() = default;

const World& Episode::world() const { return renderer_->world(); }

void Episode::reset(std::uint64_t seed, const RigidBodyState& initial, const World* world) {
  if (world != nullptr) {
    renderer_->set_world(*world);
    sim_ = physics::build_simulator(setup_.scenario, *world, setup_.simulator, setup_.plant);  // its seabed and current
  }
  seed_ = seed;
  sim_->reset(initial);
  time_offset_ = 0.0;
  mpc_->Reset();
  unav::renderer::RenderOptions ro = renderer_->options();
  ro.seed = unav::common::MixSeed(seed);
  renderer_->set_options(ro);
  renderer_->set_next_sequence(0);
  const Eigen::Vector3d fwd = initial.q_WB * Eigen::Vector3d::UnitX();
  setpoint_ = control::PoseSetpoint::FromPositionYaw(initial.p_WB_W, std::atan2(fwd.y(), fwd.x()));
  solver_failures_ = 0;
}

void Episode::set_setpoint(const control::PoseSetpoint& setpoint) { setpoint_ = setpoint; }

void Episode::advance(double duration, const std::function<void()>& after_step) {
  const int periods = std::max(1, static_cast<int>(std::lround(duration / setup_.scenario.control.period)));
  physics::ThrusterVector u;
  for (int k = 0; k < periods; ++k) {
    auto t0 = Clock::now();
    const double t = time();
    physics::Vector6d w;
    const control::MpcSummary ms = mpc_->Solve(sim_->state(), setpoint_, t, &w);
    if (!ms.ok()) ++solver_failures_;
    const control::AllocationSummary as = allocator_->Allocate(w, &u);
    // The estimator's input: what the thrusters give (scaled when saturated), as the MPC node gets
    // it from the allocator node (control/wrench_achieved).
    mpc_->SetAppliedWrench(as.achieved);
    sim_->set_command(sim_->time(), u.data(), static_cast<std::size_t>(allocator_->num_thrusters()));
    timings_.control_s += seconds_since(t0);
    ++timings_.control_steps;
    t0 = Clock::now();
    for (int i = 0; i < substeps_; ++i) {
      sim_->step();
      if (after_step) after_step();
    }
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
