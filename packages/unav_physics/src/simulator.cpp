// Simulator facade: command validation, failsafe and the fixed-step loop.
#include "unav_physics/simulator.hpp"

#include <cmath>
#include <sstream>
#include <utility>

namespace unav::physics {

const char* to_string(CommandStatus status) {
  switch (status) {
    case CommandStatus::kAccepted:
      return "accepted";
    case CommandStatus::kClamped:
      return "clamped";
    case CommandStatus::kRejectedWrongLength:
      return "rejected: wrong length";
    case CommandStatus::kRejectedNonFinite:
      return "rejected: NaN or Inf";
  }
  return "unknown";
}

bool SimulatorOptions::IsValid(std::string* msg) const {
  auto fail = [&](const std::string& m) {
    if (msg) *msg = m;
    return false;
  };
  if (!(std::isfinite(dt) && dt > 0.0 && dt <= 0.1)) {
    std::ostringstream os;
    os << "dt must be in (0, 0.1] s (got " << dt << ")";
    return fail(os.str());
  }
  if (!std::isfinite(command_timeout)) return fail("command_timeout must be finite (<= 0 disables it)");
  std::string env_msg;
  if (!environment.IsValid(&env_msg)) return fail("environment." + env_msg);
  return true;
}

namespace {
const SimulatorOptions& checked(const SimulatorOptions& o) {
  std::string msg;
  if (!o.IsValid(&msg)) throw ConfigError("simulator options: " + msg);
  return o;
}
}  // namespace

Simulator::Simulator(const VehicleParams& vehicle, const SimulatorOptions& options,
                     std::unique_ptr<CurrentModel> current, std::unique_ptr<Seabed> seabed,
                     const RigidBodyState& initial)
    : options_(checked(options)),
      dynamics_(vehicle, options.environment),
      thrusters_(vehicle.thrusters),
      sensors_(vehicle.sensors, options.environment),
      current_(current ? std::move(current) : std::make_unique<ConstantCurrent>()),
      seabed_(std::move(seabed)),
      timeout_(options.command_timeout) {
  if (vehicle.thrusters.empty()) throw ConfigError("vehicle '" + vehicle.name + "': thrusters must not be empty");
  if (vehicle.tether.enabled) tether_ = std::make_unique<Tether>(vehicle.tether, options.environment);
  reset(initial);
}

void Simulator::teleport(const RigidBodyState& x) {
  if (!(x.p_WB_W.allFinite() && x.q_WB.coeffs().allFinite() && x.v_WB_B.allFinite() && x.w_WB_B.allFinite() &&
        x.q_WB.norm() > 1e-9)) {
    throw ConfigError("initial state must be finite with a non-zero quaternion");
  }
  RigidBodyState y = x;
  y.q_WB.normalize();
  // The tether first: a vehicle out of its reach is refused before anything changes.
  if (tether_) tether_->reset(y.p_WB_W + y.q_WB * tether_->params().attach_xyz_m);
  x_ = y;
  thrusters_.reset();
  u_cmd_.setZero(thrusters_.size());
  u_zero_.setZero(thrusters_.size());
  if (tether_) update_tether_wrench();  // laid out anew from the anchor to the vehicle above
  nu_dot_fresh_ = false;
}

namespace {
// The attachment point of the tether on the vehicle: position and velocity, world NED.
std::pair<Eigen::Vector3d, Eigen::Vector3d> attachment(const RigidBodyState& x, const Eigen::Vector3d& r_B) {
  const Eigen::Matrix3d R = x.q_WB.toRotationMatrix();
  return {x.p_WB_W + R * r_B, R * (x.v_WB_B + x.w_WB_B.cross(r_B))};
}
}  // namespace

void Simulator::update_tether_wrench() {
  const auto [p, v] = attachment(x_, tether_->params().attach_xyz_m);
  update_tether_wrench(p, v);
}

void Simulator::update_tether_wrench(const Eigen::Vector3d& attach_W, const Eigen::Vector3d& attach_v_W) {
  const Eigen::Vector3d& r_B = tether_->params().attach_xyz_m;
  const Eigen::Vector3d f_B = x_.q_WB.conjugate() * tether_->force_on_vehicle_W(attach_W, attach_v_W);
  tether_tau_B_ << f_B, r_B.cross(f_B);
}

Eigen::Vector3d Simulator::tether_force_W() const {
  if (!tether_) return Eigen::Vector3d::Zero();
  const auto [p, v] = attachment(x_, tether_->params().attach_xyz_m);
  return tether_->force_on_vehicle_W(p, v);
}

void Simulator::set_tether_length(double length_m) {
  if (!tether_) throw ConfigError("simulator", "tether", "", "the vehicle has no tether (vehicle file: tether)");
  tether_->set_length(length_m);
}

void Simulator::reset(const RigidBodyState& x) {
  teleport(x);
  steps_ = 0;
  timeout_ = CommandTimeout(options_.command_timeout);
  timed_out_ = false;
  nu_dot_fresh_ = false;
  sensors_ = SensorSuite(sensors_.params(), options_.environment);
  sensors_.update(0.0, x_, acceleration(), seabed_.get());
}

DynamicsInputs Simulator::inputs_at(double t) const {
  DynamicsInputs in;
  in.tau_B = thrusters_.wrench_B() + external_tau_B_ + tether_tau_B_;
  in.v_c_W = current_->velocity_W(t);
  in.a_c_W = current_->acceleration_W(t);
  in.seabed = seabed_.get();
  return in;
}

const Vector6d& Simulator::acceleration() const {
  if (!nu_dot_fresh_) {
    nu_dot_ = dynamics_.acceleration(x_, inputs_at(time()));
    nu_dot_fresh_ = true;
  }
  return nu_dot_;
}

CommandStatus Simulator::set_command(double t, const double* u, std::size_t n) {
  if (n != static_cast<std::size_t>(thrusters_.size())) {
    ++stats_.rejected_wrong_length;
    return CommandStatus::kRejectedWrongLength;
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (!std::isfinite(u[i])) {
      ++stats_.rejected_non_finite;
      return CommandStatus::kRejectedNonFinite;
    }
  }
  bool clamped = false;
  for (std::size_t i = 0; i < n; ++i) {
    double v = u[i];
    if (v > 1.0 || v < -1.0) {
      v = v > 1.0 ? 1.0 : -1.0;
      clamped = true;
    }
    u_cmd_(static_cast<Eigen::Index>(i)) = v;
  }
  timeout_.on_command(t);
  ++stats_.accepted;
  if (clamped) ++stats_.clamped;
  return clamped ? CommandStatus::kClamped : CommandStatus::kAccepted;
}

void Simulator::step() {
  const double dt = options_.dt;
  const double t0 = time();
  const bool expired = timeout_.expired(t0);
  if (expired && !timed_out_) ++stats_.timeouts;
  timed_out_ = expired;
  // The lag filter advances first; the integrator sees the thrust as the lag makes it vary over
  // the step (start, middle, end: RK4 keeps its 4th order; holding the end value made thrust
  // lead by half a step and the integration first order).
  // The tether's pull is held over the step (it is stepped after the vehicle, with the vehicle's
  // end where the step took it).
  const Vector6d outer_B = external_tau_B_ + tether_tau_B_;
  const Vector6d tau_start_B = thrusters_.wrench_B() + outer_B;
  thrusters_.step(dt, expired ? u_zero_ : u_cmd_);
  DynamicsInputs in = inputs_at(t0);
  in.tau_staged = true;
  in.tau_B = tau_start_B;
  in.tau_B_half = thrusters_.wrench_at_B(0.5 * dt) + outer_B;
  in.tau_B_end = thrusters_.wrench_B() + outer_B;
  dynamics_.step(x_, dt, in, options_.integrator);
  current_->step(t0, dt);
  ++steps_;
  nu_dot_fresh_ = false;
  if (tether_) {
    const auto [p, v] = attachment(x_, tether_->params().attach_xyz_m);
    tether_->step(dt, p, v, current_->velocity_W(time()), seabed_.get());
    update_tether_wrench(p, v);  // the attachment where the step left it
  }

  const double t1 = time();
  // nu_dot only when the IMU samples (it costs one more model evaluation).
  sensors_.update(t1, x_, sensors_.imu_due(t1) ? acceleration() : nu_dot_, seabed_.get());
}

void Simulator::set_external_wrench_B(const Vector6d& tau_B) {
  external_tau_B_ = tau_B;
  nu_dot_fresh_ = false;
}

void Simulator::advance_to(double t_end) {
  while (time() < t_end - 1e-9) step();
}

}  // namespace unav::physics
