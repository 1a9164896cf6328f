#include "physics_server_node.hpp"

#include <chrono>
#include <cmath>
#include <limits>
#include <optional>

#include <spdlog/fmt/fmt.h>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include "unav_common/resources.hpp"
#include "unav_scene/world.hpp"

#include "unav_runtime/conversions.hpp"
#include "unav_runtime/lockstep_ack.hpp"

namespace unav::physics {
namespace {

double wall_now_s() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// Number of physics steps in `period`; the period must be a whole number of steps.
int64_t steps_in(double period, double dt, const std::string& name) {
  const double n = period / dt;
  const int64_t rounded = std::max<int64_t>(1, std::llround(n));
  if (std::abs(n - static_cast<double>(rounded)) > 1e-6 * n)
    throw unav::ParameterError("parameter '" + name + "': period " + std::to_string(period) +
                               " s is not a whole number of physics steps (dt = " + std::to_string(dt) + " s)");
  return rounded;
}

}  // namespace

PhysicsServer::PhysicsServer(const unav::NodeOptions& options) : Node("physics_server", options, "rov") {
  PhysicsServerParams p;
  p.vehicle_config = unav::common::resource_or_empty("config/vehicles/bluerov2_heavy.yaml");
  declare_params(&p);
  // A scenario gives the plant (world, vehicle, step, initial state) as the in-process Episode
  // takes it, through the same builder (unav_physics/scenario_builder.hpp).
  std::optional<unav::scene::Scenario> scenario;
  if (p.scenario.given()) {
    scenario = p.scenario.load();
    p.vehicle_config = scenario->vehicle.model;
    p.world = scenario->world;
    p.dt = scenario->physics.dt;
    p.integrator = scenario->physics.integrator;
  }
  if (p.vehicle_config.empty())
    throw unav::ParameterError("node '" + name() +
                               "': parameter 'vehicle_config' is empty and the package "
                               "unav_resources is not installed: give the vehicle YAML path");
  SimulatorOptions so;
  so.dt = p.dt;
  if (!parse_integrator(p.integrator, &so.integrator))
    throw unav::ParameterError("node '" + name() + "': parameter 'integrator' = '" + p.integrator +
                               "': expected velocity_verlet or rk4");
  so.command_timeout = p.command_timeout;
  lockstep_ = p.mode == "lockstep";
  real_time_factor_ = p.real_time_factor;
  lockstep_period_ = p.lockstep_period;
  participants_ = p.lockstep_participants;
  wait_for_command_ = p.lockstep_wait_for_command;
  max_sim_time_ = p.max_sim_time;
  world_frame_ = p.frames.world_frame;
  body_frame_ = p.frames.body_frame;
  const double publish_rate = p.publish_rate;
  const double thruster_rate = p.thruster_state_rate;

  steps_per_publish_ = steps_in(1.0 / publish_rate, so.dt, "publish_rate");
  steps_per_thruster_state_ = steps_in(1.0 / thruster_rate, so.dt, "thruster_state_rate");
  steps_per_barrier_ = steps_in(lockstep_period_, so.dt, "lockstep_period");
  // Acks are integer-nanosecond stamps; half a physics step absorbs rounding from doubles.
  barrier_ = std::make_unique<unav::lockstep::Barrier>(participants_, std::llround(0.5 * so.dt * 1e9));

  VehicleParams vehicle = scenario ? scenario_vehicle(*scenario) : load_vehicle(p.vehicle_config);
  std::vector<VehicleParams> fleet_vehicles;
  if (scenario) {
    const unav::scene::World world = unav::scene::scenario_world(*scenario);
    apply_world_acoustics(world, &vehicle.sensors);  // the ports' modem too
    sim_ = build_simulator(*scenario, world, so, vehicle);
    for (size_t i = 0; i < scenario->fleet.size(); ++i) {
      const unav::scene::ScenarioFleetVehicle& f = scenario->fleet[i];
      if ("/" + f.name == get_namespace())
        throw unav::ParameterError("node '" + name() + "': " + p.scenario.file + ": fleet[" + std::to_string(i) +
                                   "].name = " + f.name + ": is this node's namespace (the primary vehicle's)");
      fleet_vehicles.push_back(scenario_vehicle(f.vehicle, "fleet[" + std::to_string(i) + "]"));
      apply_world_acoustics(world, &fleet_vehicles.back().sensors);
      FleetVehicle v;
      v.name = f.name;
      v.sim = build_simulator(*scenario, world, so, fleet_vehicles.back(), f.vehicle);
      fleet_.push_back(std::move(v));
      logger()->info("fleet vehicle '{}': {} at [{:.2f}, {:.2f}, {:.2f}] m", f.name, f.vehicle.model,
                     f.vehicle.initial_position.x(), f.vehicle.initial_position.y(), f.vehicle.initial_position.z());
    }
    logger()->info("scenario {} (seed {}): world {}, vehicle {}", p.scenario.file, scenario->seed, scenario->world,
                   scenario->vehicle.model);
    // Carried USBL transceivers and modem station ends: each names the vehicle that carries it
    // (this node's namespace for the primary vehicle, a fleet name).
    const std::string primary = get_namespace().substr(get_namespace().rfind('/') + 1);
    auto by_name = [&](const std::string& n) -> const Simulator* {
      if (n == primary) return sim_.get();
      for (const auto& f : fleet_)
        if (f.name == n) return f.sim.get();
      return nullptr;
    };
    auto carrier_of = [&](const Simulator* own, const std::string& carrier_name, const std::string& key,
                          const std::string& field, const std::string& who, const char* what) -> const Simulator* {
      const Simulator* carrier = by_name(carrier_name);
      if (carrier == nullptr || carrier == own)
        throw unav::ParameterError("node '" + name() + "': " + p.scenario.file + ": " + key + ".sensors." + field +
                                   " = " + carrier_name + ": " +
                                   (carrier == nullptr ? "no such vehicle (the primary is '" + primary + "')"
                                                       : "a vehicle cannot carry both ends"));
      logger()->info("{}'s {} is carried by {}", who, what, carrier_name);
      return carrier;
    };
    for (size_t i = 0; i <= fleet_.size(); ++i) {  // 0: the primary, then the fleet
      Simulator* own = i == 0 ? sim_.get() : fleet_[i - 1].sim.get();
      const SensorSuiteParams& s = i == 0 ? vehicle.sensors : fleet_vehicles[i - 1].sensors;
      const std::string key = i == 0 ? "vehicle" : "fleet[" + std::to_string(i - 1) + "]";
      const std::string who = i == 0 ? primary : fleet_[i - 1].name;
      if (s.usbl.enabled && !s.usbl.transceiver_vehicle.empty())
        usbl_carriers_.emplace_back(
            own, carrier_of(own, s.usbl.transceiver_vehicle, key, "usbl.transceiver_vehicle", who, "USBL transceiver"));
      if (s.modem.enabled && !s.modem.station_vehicle.empty())
        modem_carriers_.emplace_back(
            i, carrier_of(own, s.modem.station_vehicle, key, "modem.station_vehicle", who, "modem's other end"));
    }
  } else {
    build_from_params(p, so, vehicle);
  }

  // Ports.
  ports_ = std::make_unique<VehiclePorts>(*this, vehicle, p.frames);
  command_sub_ = create_subscription<unav_msgs::msg::ThrusterCommand>(
      "thrusters/command", unav::QoS::reliable(), [this](const unav_msgs::msg::ThrusterCommand& m) { on_command(m); });
  for (size_t i = 0; i < fleet_.size(); ++i) {
    FleetVehicle& f = fleet_[i];
    f.ports = std::make_unique<VehiclePorts>(*this, fleet_vehicles[i], p.frames, f.name);
    f.command_sub = create_subscription<unav_msgs::msg::ThrusterCommand>(
        "/" + f.name + "/thrusters/command", unav::QoS::reliable(),
        [this, i](const unav_msgs::msg::ThrusterCommand& m) {
          FleetVehicle& v = fleet_[i];
          if (!apply_command(*v.sim, v.command_sub->topic_name(), m, &v.rejected_logged)) return;
          v.last_command_ns = std::max(v.last_command_ns, unav::nanoseconds(m.header()));
          last_input_ = v.name + " thruster command";
          if (lockstep_ && barrier_t_ >= 0.0 && barrier_open()) run_steps();
        });
  }
  for (const auto& [i, carrier] : modem_carriers_)
    (i == 0 ? *ports_ : *fleet_[i - 1].ports).set_modem_station_carrier(carrier);
  reset_sub_ = create_subscription<geometry_msgs::msg::Pose>(
      "sim/reset", unav::QoS::reliable(), [this](const geometry_msgs::msg::Pose& m) { on_reset(m); });
  if (vehicle.tether.enabled)  // the winch: the length paid out
    length_sub_ = create_subscription<std_msgs::msg::Float64>(
        "tether/length", unav::QoS::reliable(), [this](const std_msgs::msg::Float64& m) {
          if (!(std::isfinite(m.data()) && m.data() > 0.0)) {
            rejections_.reject(length_sub_->topic_name(), "a length must be finite and > 0 m");
            return;
          }
          sim_->set_tether_length(m.data());
          logger()->info("tether paid out to {:.2f} m at t = {:.3f} s", m.data(), sim_->time());
        });
  if (lockstep_) {
    ack_sub_ = create_subscription<unav_msgs::msg::LockstepAck>(
        "/lockstep/ack", unav::lockstep::ack_qos(), [this](const unav_msgs::msg::LockstepAck& m) { on_ack(m); });
    drop_sub_ = create_subscription<std_msgs::msg::String>(
        "/lockstep/drop", unav::QoS::reliable(), [this](const std_msgs::msg::String& m) { on_drop(m.data()); });
  }

  publish_state();
  if (lockstep_) {
    barrier_t_ = 0.0;  // participants produce their outputs for t = 0 first
    timer_ = create_wall_timer(std::chrono::milliseconds(1), [this] { run_steps(); });
  } else {
    wall_start_ = wall_now_s();
    timer_ =
        create_wall_timer(std::chrono::nanoseconds(static_cast<int64_t>(1e9 / publish_rate)), [this] { run_steps(); });
  }
  logger()->info("{} ({} thrusters), {} at {:.0f} Hz ({}), {}{}", vehicle.name, vehicle.thrusters.size(), p.mode,
                 1.0 / so.dt, to_string(so.integrator), lockstep_ ? "barrier every " : "real_time_factor ",
                 lockstep_ ? lockstep_period_ : real_time_factor_);
}

int64_t PhysicsServer::barrier_ns() const { return std::llround(barrier_t_ * 1e9); }

bool PhysicsServer::barrier_open() const {
  if (barrier_t_ < 0.0) return true;
  if (!barrier_->open(barrier_ns())) return false;
  if (!wait_for_command_) return true;
  if (!barrier_->meets(last_command_ns_, barrier_ns())) return false;
  for (const auto& f : fleet_)  // every vehicle's controller answered this barrier
    if (!barrier_->meets(f.last_command_ns, barrier_ns())) return false;
  return true;
}

void PhysicsServer::run_steps() {
  if (finishing_) {
    finish();
    return;
  }
  if (lockstep_) {
    // Step until a barrier holds or this call's wall budget is spent (keeps the executor
    // responsive to acks and commands).
    const double budget_end = wall_now_s() + 0.002;
    while (context().ok()) {
      if (barrier_t_ >= 0.0) {
        if (!barrier_open()) {
          hold_at_barrier();
          return;
        }
        barrier_t_ = -1.0;
        hold_profile_.passed(last_input_, wall_now_s());
      }
      step_once();
      if (finishing_) return;  // max_sim_time: finish() takes over
      if (sim_->steps() % steps_per_barrier_ == 0) {
        barrier_t_ = sim_->time();
        if (sim_->steps() % steps_per_publish_ != 0) publish_state();  // the barrier's state is always published
      }
      if (wall_now_s() > budget_end) return;
    }
    return;
  }
  const double target = (wall_now_s() - wall_start_) * real_time_factor_;
  if (target - sim_->time() > 1.0) {
    logger()->warn("simulation is {:.2f} s behind the wall clock (x{} too fast for this machine): skipping ahead",
                   target - sim_->time(), real_time_factor_);
    wall_start_ = wall_now_s() - sim_->time() / real_time_factor_;
    return;
  }
  while (sim_->time() + 0.5 * sim_->options().dt < target && context().ok() && !finishing_) step_once();
}

void PhysicsServer::hold_at_barrier() {
  // Participants that joined late missed the barrier's state: send it again every second.
  const double now = wall_now_s();
  if (hold_profile_.holding_since() < 0.0) {
    hold_profile_.held(now);
    last_republish_ = now;
    return;
  }
  const double held_since = hold_profile_.holding_since();
  if (now - last_republish_ >= 1.0) {
    last_republish_ = now;
    publish_state();
  }
  // A participant that stopped answering is named 3 s into the hold (then every 5 s): well
  // within a barrier's normal wait on a loaded machine (~0.1 s), and soon enough to act on.
  if (now - held_since >= 3.0 && now - last_wait_log_ >= 5.0) {
    last_wait_log_ = now;
    logger()->warn("lockstep: holding at t = {:.3f} s for {:.0f} s, waiting for:{}", barrier_t_, now - held_since,
                   missing_with_acks());
  }
}

std::string PhysicsServer::missing_with_acks() const {
  // Each with what it acked last: a participant one frame short (an input lost on the way) reads
  // differently from one that never answered (not started, or acking under another name).
  std::string missing;
  for (const auto& p : barrier_->missing(barrier_ns()))
    missing += barrier_->has_acked(p)
                   ? fmt::format(" {} (acked t = {:.3f} s)", p, static_cast<double>(barrier_->last_ack(p)) * 1e-9)
                   : fmt::format(" {} (nothing acked)", p);
  if (wait_for_command_ && !barrier_->meets(last_command_ns_, barrier_ns()))
    missing += last_command_ns_ == INT64_MIN ? std::string(" (thruster command: none yet)")
                                             : fmt::format(" (thruster command: last stamped t = {:.3f} s)",
                                                           static_cast<double>(last_command_ns_) * 1e-9);
  for (const auto& f : fleet_)
    if (wait_for_command_ && !barrier_->meets(f.last_command_ns, barrier_ns()))
      missing += f.last_command_ns == INT64_MIN ? fmt::format(" ({} thruster command: none yet)", f.name)
                                                : fmt::format(" ({} thruster command: last stamped t = {:.3f} s)",
                                                              f.name, static_cast<double>(f.last_command_ns) * 1e-9);
  return missing;
}

void PhysicsServer::step_once() {
  // Carried USBL transceivers where their carriers are at the step's start (before any moves).
  for (auto& [tracked, carrier] : usbl_carriers_) tracked->set_usbl_carrier_pose(carrier->pose());
  sim_->step();
  for (auto& f : fleet_) f.sim->step();
  if (sim_->command_timed_out() && !timeout_logged_) {
    logger()->warn("no thruster command for {:.2f} s: thrust set to zero (failsafe)", sim_->options().command_timeout);
    timeout_logged_ = true;
  }
  publish_sensors();
  const int64_t n = static_cast<int64_t>(sim_->steps());
  if (max_sim_time_ > 0.0 && sim_->time() >= max_sim_time_ - 0.5 * sim_->options().dt) {
    publish_state();
    const RigidBodyState& x = sim_->state();
    const Eigen::Vector3d rpy = roll_pitch_yaw(x.q_WB);
    logger()->info(
        "max_sim_time reached: t = {:.3f} s, position NED [{:.4f}, {:.4f}, {:.4f}] m, rpy [{:.4f}, {:.4f}, "
        "{:.4f}] rad",
        sim_->time(), x.p_WB_W.x(), x.p_WB_W.y(), x.p_WB_W.z(), rpy.x(), rpy.y(), rpy.z());
    // The last state is a barrier too: stop only when every participant answered it and our own
    // samples reached their readers, so every run ends on the same instant with nothing lost.
    finishing_ = true;
    finish_started_ = wall_now_s();
    barrier_t_ = sim_->time();
    finish();
    return;
  }
  if (n % steps_per_publish_ == 0) publish_state();
  if (n % steps_per_thruster_state_ == 0) publish_thruster_state();
}

void PhysicsServer::finish() {
  const bool acked = !lockstep_ || barrier_->open(barrier_ns());
  if (!acked && wall_now_s() - finish_started_ < 10.0) {  // spin on: acks are on their way
    hold_profile_.held(wall_now_s());
    return;
  }
  if (!acked) {
    logger()->warn("lockstep: the last state was not acked within 10 s by:{}", missing_with_acks());
  }
  if (lockstep_) {
    hold_profile_.passed(last_input_, wall_now_s());
    logger()->info("lockstep: {}", hold_profile_.report(sim_->time(), wall_now_s()));
  }
  const eprosima::fastrtps::Duration_t wait(2, 0);
  for (auto* w : ports_->state_writers()) w->wait_for_acknowledgments(wait);
  for (const auto& f : fleet_)  // every vehicle's last state reaches its readers
    for (auto* w : f.ports->state_writers()) w->wait_for_acknowledgments(wait);
  finishing_ = false;
  context().shutdown();
}

void PhysicsServer::publish_state() {
  ports_->publish_state(*sim_);
  for (auto& f : fleet_) f.ports->publish_state(*f.sim);
}
void PhysicsServer::publish_thruster_state() {
  ports_->publish_thruster_state(*sim_);
  for (auto& f : fleet_) f.ports->publish_thruster_state(*f.sim);
}
void PhysicsServer::publish_sensors() {
  ports_->publish_sensors(*sim_);
  for (auto& f : fleet_) f.ports->publish_sensors(*f.sim);
}

void PhysicsServer::build_from_params(const PhysicsServerParams& p, const SimulatorOptions& so,
                                      const VehicleParams& vehicle) {
  // The world file (the renderer's scene) drives the seabed and the current unless a node
  // parameter names its own.
  unav::scene::World world;
  if (!p.world.empty()) world = unav::scene::load_world(p.world);
  std::string current_file = p.current_config;
  if (current_file.empty()) current_file = world.current_file;
  std::unique_ptr<CurrentModel> current = current_file.empty() ? nullptr : load_current(current_file);
  std::unique_ptr<Seabed> seabed;
  std::string seabed_from = "none";
  if (!p.seabed_config.empty()) {
    seabed = load_seabed(p.seabed_config);
    seabed_from = p.seabed_config;
  } else if (!p.world.empty()) {
    seabed = seabed_from_world(world);
    if (seabed) seabed_from = p.world + (world.seabed.is_flat() ? " (flat)" : " (sampled grid)");
  } else if (p.seabed_depth > 0.0) {
    seabed = std::make_unique<FlatSeabed>(p.seabed_depth);
    seabed_from = "flat at " + std::to_string(p.seabed_depth) + " m";
  }
  logger()->info("seabed: {}; current: {}", seabed_from, current_file.empty() ? "still water" : current_file);
  RigidBodyState x0;
  x0.p_WB_W = p.initial_position;
  x0.q_WB = quaternion_from_rpy(p.initial_rpy.x(), p.initial_rpy.y(), p.initial_rpy.z());
  sim_ = std::make_unique<Simulator>(vehicle, so, std::move(current), std::move(seabed), x0);
}

bool PhysicsServer::apply_command(Simulator& sim, const std::string& topic, const unav_msgs::msg::ThrusterCommand& msg,
                                  std::uint64_t* logged) {
  // A command answers a state already published: one stamped ahead of simulated time is garbage
  // (or an outsider's), and taken as is it would answer every lockstep barrier up to its stamp.
  if (const double stamp = unav::seconds(msg.header()); stamp > sim.time() + kMaxCommandLead) {
    rejections_.reject(topic, fmt::format("header.stamp = {:.3f} s is {:.3f} s after the simulated time {:.3f} s (more "
                                          "than {} s ahead: a command answers a state that was published)",
                                          stamp, stamp - sim.time(), sim.time(), kMaxCommandLead));
    return false;
  }
  const CommandStatus status = sim.set_command(sim.time(), msg.u());
  if (status == CommandStatus::kRejectedWrongLength || status == CommandStatus::kRejectedNonFinite) {
    const auto& st = sim.command_stats();
    const std::uint64_t rejected = st.rejected_wrong_length + st.rejected_non_finite;
    if (rejected == 1 || rejected >= 2 * *logged) {  // log the 1st, 2nd, 4th, 8th ...
      logger()->warn("thruster command rejected ({}): {} values for {} thrusters; {} rejected so far on {}",
                     to_string(status), msg.u().size(), sim.thrusters().size(), rejected, topic);
      *logged = rejected;
    }
    return false;
  }
  return true;
}

void PhysicsServer::on_command(const unav_msgs::msg::ThrusterCommand& msg) {
  if (!apply_command(*sim_, command_sub_->topic_name(), msg, &rejected_logged_)) return;
  if (timeout_logged_) {
    logger()->info("thruster commands resumed");
    timeout_logged_ = false;
  }
  last_command_ns_ = std::max(last_command_ns_, unav::nanoseconds(msg.header()));
  last_input_ = "thruster command";
  if (lockstep_ && barrier_t_ >= 0.0 && barrier_open()) run_steps();
}

void PhysicsServer::on_ack(const unav_msgs::msg::LockstepAck& msg) {
  const std::string& who = msg.participant();
  const bool known = barrier_->has_acked(who);
  last_input_ = who;
  if (!barrier_->on_ack(who, unav::nanoseconds(msg.header())) && !known)
    logger()->warn("lockstep ack from '{}', which is not in lockstep_participants", who);
  if (barrier_t_ >= 0.0 && barrier_open()) run_steps();
}

void PhysicsServer::on_drop(const std::string& who) {
  if (!barrier_->drop(who)) {
    std::string listed;
    for (const auto& p : barrier_->participants()) listed += " " + p;
    logger()->warn("/lockstep/drop '{}': not a lockstep participant (waiting for:{})", who,
                   listed.empty() ? " nobody" : listed);
    return;
  }
  logger()->warn("lockstep: no longer waiting for '{}' (dropped through /lockstep/drop)", who);
  if (barrier_t_ >= 0.0 && barrier_open()) run_steps();
}

void PhysicsServer::on_reset(const geometry_msgs::msg::Pose& pose) {
  if (const std::string why = unav::pose_problem(pose); !why.empty()) {
    rejections_.reject(reset_sub_->topic_name(), why);
    return;
  }
  RigidBodyState x;
  x.p_WB_W = unav::from_msg(pose.position());
  x.q_WB = unav::from_msg(pose.orientation());  // normalised by teleport()
  try {
    sim_->teleport(x);
  } catch (const ConfigError& e) {  // out of the tether's reach
    rejections_.reject(reset_sub_->topic_name(), e.what());
    return;
  }
  ++episodes_;
  logger()->info("episode {}: the vehicle is at [{:.3f}, {:.3f}, {:.3f}] m (NED), at rest, t = {:.3f} s", episodes_,
                 x.p_WB_W.x(), x.p_WB_W.y(), x.p_WB_W.z(), sim_->time());
}

}  // namespace unav::physics
