#include "unav_autopilot/ardupilot_json.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <utility>

#include "unav_common/errors.hpp"
#include "unav_physics/scenario_builder.hpp"
#include "unav_physics/seabed.hpp"
#include "unav_physics/vehicle.hpp"

namespace unav::autopilot {
namespace {

// ArduSub's AP_Motors6DOF factors of SUB_FRAME_VECTORED_6DOF, per motor: roll, pitch, yaw,
// throttle (climb), forward, lateral. Positive motor output moves the vehicle along a positive
// factor (with MOT_n_DIRECTION = 1).
constexpr double kVectored6Dof[8][6] = {
    {0, 0, 1, 0, -1, 1},  {0, 0, -1, 0, -1, -1}, {0, 0, -1, 0, 1, 1}, {0, 0, 1, 0, 1, -1},
    {1, -1, 0, -1, 0, 0}, {-1, -1, 0, -1, 0, 0}, {1, 1, 0, -1, 0, 0}, {-1, 1, 0, -1, 0, 0},
};
constexpr const char* kFactorNames[6] = {"roll", "pitch", "yaw", "throttle", "forward", "lateral"};

std::uint16_t u16(const std::uint8_t* p) { return static_cast<std::uint16_t>(p[0] | (p[1] << 8)); }
std::uint32_t u32(const std::uint8_t* p) {
  return static_cast<std::uint32_t>(p[0]) | (static_cast<std::uint32_t>(p[1]) << 8) |
         (static_cast<std::uint32_t>(p[2]) << 16) | (static_cast<std::uint32_t>(p[3]) << 24);
}

void append_number(std::string* out, double v) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.10g", v);
  *out += buf;
}
void append_vector(std::string* out, const char* key, const double* v, int n) {
  *out += '"';
  *out += key;
  *out += "\":[";
  for (int i = 0; i < n; ++i) {
    if (i > 0) *out += ',';
    append_number(out, v[i]);
  }
  *out += ']';
}

}  // namespace

MotorMap load_motor_map(const std::string& path) { return unav::common::LoadYamlFile<MotorMap>(path); }

void check_motor_map(const MotorMap& map, const physics::VehicleParams& vehicle, const std::string& file) {
  if (map.motors.size() != 8)
    throw ConfigError(file, "motors", std::to_string(map.motors.size()) + " motors",
                      "the vectored_6dof frame drives 8 (M1-M4 horizontal, M5-M8 vertical)");
  std::vector<bool> used(vehicle.thrusters.size(), false);
  for (std::size_t k = 0; k < map.motors.size(); ++k) {
    const MotorChannel& m = map.motors[k];
    const std::string key = "motors[" + std::to_string(k) + "]";
    if (m.direction != 1 && m.direction != -1)
      throw ConfigError(file, key + ".direction", std::to_string(m.direction), "must be 1 or -1");
    const auto it = std::find_if(vehicle.thrusters.begin(), vehicle.thrusters.end(),
                                 [&](const physics::ThrusterParams& t) { return t.name == m.thruster; });
    if (it == vehicle.thrusters.end()) {
      std::string names;
      for (const auto& t : vehicle.thrusters) names += (names.empty() ? "" : ", ") + t.name;
      throw ConfigError(file, key + ".thruster", m.thruster,
                        "no thruster of that name in " + vehicle.name + " (" + names + ")");
    }
    const auto i = static_cast<std::size_t>(it - vehicle.thrusters.begin());
    if (used[i]) throw ConfigError(file, key + ".thruster", m.thruster, "drives a thruster another motor drives too");
    used[i] = true;
    // The body force and moment of PWM > 1500, against ArduSub's factors.
    const Eigen::Vector3d f = m.direction * it->direction_B.normalized();
    const Eigen::Vector3d tau = it->position_B.cross(f);
    const double effect[6] = {tau.x(), tau.y(), tau.z(), -f.z(), f.x(), f.y()};
    for (int j = 0; j < 6; ++j) {
      const double factor = kVectored6Dof[k][j];
      if (factor != 0.0 && !(factor * effect[j] > 1e-6))
        throw ConfigError(file, key, m.thruster + " direction " + std::to_string(m.direction),
                          std::string("motor ") + std::to_string(k + 1) + " of ArduSub's vectored_6dof has " +
                              kFactorNames[j] + " factor " + (factor > 0 ? "+1" : "-1") + ", but this thruster's " +
                              kFactorNames[j] + " effect is " + std::to_string(effect[j]) +
                              " (a motor wired to the wrong thruster or direction)");
    }
  }
}

const char* to_string(PacketStatus s) {
  switch (s) {
    case PacketStatus::kOk:
      return "ok";
    case PacketStatus::kShort:
      return "short packet";
    case PacketStatus::kUnknownMagic:
      return "unknown magic";
    case PacketStatus::kZeroFrameRate:
      return "frame_rate 0";
    case PacketStatus::kPwmOutOfRange:
      return "PWM outside [1000, 2000]";
  }
  return "?";
}

PacketStatus parse_servo_packet(const std::uint8_t* data, std::size_t size, int checked_channels, ServoPacket* out) {
  if (size < 8) return PacketStatus::kShort;
  const std::uint16_t magic = u16(data);
  std::size_t channels = 0;
  if (magic == kMagic16) {
    channels = 16;
  } else if (magic == kMagic32) {
    channels = 32;
  } else {
    return PacketStatus::kUnknownMagic;
  }
  if (size < 8 + 2 * channels) return PacketStatus::kShort;
  out->magic = magic;
  out->frame_rate = u16(data + 2);
  out->frame_count = u32(data + 4);
  if (out->frame_rate == 0) return PacketStatus::kZeroFrameRate;
  out->pwm.resize(channels);
  for (std::size_t c = 0; c < channels; ++c) out->pwm[c] = u16(data + 8 + 2 * c);
  for (int c = 0; c < checked_channels && c < static_cast<int>(channels); ++c) {
    const std::uint16_t p = out->pwm[static_cast<std::size_t>(c)];
    if (p != 0 && (p < 1000 || p > 2000)) return PacketStatus::kPwmOutOfRange;
  }
  return PacketStatus::kOk;
}

std::vector<std::uint8_t> encode_servo_packet(std::uint16_t frame_rate, std::uint32_t frame_count,
                                              const std::vector<std::uint16_t>& pwm) {
  const std::uint16_t magic = pwm.size() > 16 ? kMagic32 : kMagic16;
  const std::size_t channels = pwm.size() > 16 ? 32 : 16;
  std::vector<std::uint8_t> out(8 + 2 * channels, 0);
  auto put16 = [&](std::size_t at, std::uint16_t v) {
    out[at] = static_cast<std::uint8_t>(v & 0xFF);
    out[at + 1] = static_cast<std::uint8_t>(v >> 8);
  };
  put16(0, magic);
  put16(2, frame_rate);
  for (int b = 0; b < 4; ++b) out[4 + static_cast<std::size_t>(b)] = static_cast<std::uint8_t>(frame_count >> (8 * b));
  for (std::size_t c = 0; c < pwm.size() && c < channels; ++c) put16(8 + 2 * c, pwm[c]);
  return out;
}

FdmState fdm_state(const physics::Simulator& sim) {
  const auto& x = sim.state();
  FdmState s;
  s.timestamp = sim.time();
  s.gyro_B = x.w_WB_B;
  // Specific force in body axes: the inertial acceleration minus gravity (what an accelerometer
  // reads): nu_dot is d/dt of the body-axis velocity, so add w x v.
  const Eigen::Vector3d g_W(0.0, 0.0, sim.options().environment.gravity);
  s.accel_B = sim.acceleration().head<3>() + x.w_WB_B.cross(x.v_WB_B) - x.q_WB.conjugate() * g_W;
  s.position_N = x.p_WB_W;
  s.q_NB = x.q_WB;
  s.velocity_N = x.q_WB * x.v_WB_B;
  if (const physics::Seabed* sb = sim.seabed()) {
    const double h = sb->depth_at(x.p_WB_W.x(), x.p_WB_W.y()) - x.p_WB_W.z();
    s.rangefinder_m = std::max(0.0, h);
  }
  return s;
}

std::string format_state_json(const FdmState& s) {
  std::string o;
  o.reserve(320);
  o += "\n{\"timestamp\":";
  append_number(&o, s.timestamp);
  o += ",\"imu\":{";
  append_vector(&o, "gyro", s.gyro_B.data(), 3);
  o += ',';
  append_vector(&o, "accel_body", s.accel_B.data(), 3);
  o += "},";
  append_vector(&o, "position", s.position_N.data(), 3);
  o += ',';
  const double q[4] = {s.q_NB.w(), s.q_NB.x(), s.q_NB.y(), s.q_NB.z()};
  append_vector(&o, "quaternion", q, 4);
  o += ',';
  const Eigen::Vector3d rpy = unav::common::roll_pitch_yaw(s.q_NB);
  append_vector(&o, "attitude", rpy.data(), 3);
  o += ',';
  append_vector(&o, "velocity", s.velocity_N.data(), 3);
  if (s.rangefinder_m >= 0.0) {
    o += ",\"rng_1\":";
    append_number(&o, s.rangefinder_m);
  }
  o += "}\n";
  return o;
}

JsonBackend::JsonBackend(const unav::scene::Scenario& scenario, const unav::scene::World& world, MotorMap map,
                         const std::string& map_file)
    : scenario_(scenario), world_(world), map_(std::move(map)), vehicle_(physics::scenario_vehicle(scenario_)) {
  physics::require_fixed_usbl(vehicle_, scenario_.name, "the ArduPilot JSON backend");
  // The world's sound speed for the USBL and the modem, here as well as in the simulator: the
  // bridge's ports carry the modem's packets from this vehicle (as the physics server does).
  physics::apply_world_acoustics(world_, &vehicle_.sensors);
  check_motor_map(map_, vehicle_, map_file);
  for (const auto& m : map_.motors)
    for (std::size_t i = 0; i < vehicle_.thrusters.size(); ++i)
      if (vehicle_.thrusters[i].name == m.thruster) thruster_of_motor_.push_back(static_cast<int>(i));
  u_.assign(vehicle_.thrusters.size(), 0.0);
  reset();
}

void JsonBackend::reset() {
  // The autopilot's clock restarts at 0 with it; its commands are the only ones (no timeout).
  sim_ = physics::build_simulator(scenario_, world_, physics::scenario_simulator_options(scenario_, 0.0), vehicle_);
  std::fill(u_.begin(), u_.end(), 0.0);
  started_ = false;
  target_time_ = 0.0;
  reply_.clear();
}

std::string JsonBackend::handle(const std::uint8_t* data, std::size_t size) {
  ++stats_.packets;
  ServoPacket p;
  last_status_ = parse_servo_packet(data, size, static_cast<int>(map_.motors.size()), &p);
  if (last_status_ != PacketStatus::kOk) {
    ++stats_.dropped[static_cast<std::size_t>(last_status_)];
    return "";
  }
  if (started_ && p.frame_count == last_frame_) {
    ++stats_.repeats;
    return reply_;
  }
  if (started_ && p.frame_count < last_frame_) {
    ++stats_.resets;
    reset();
  }
  if (started_ && p.frame_count > last_frame_ + 1) ++stats_.gaps;
  started_ = true;
  last_frame_ = p.frame_count;
  for (std::size_t k = 0; k < map_.motors.size(); ++k) {
    const std::uint16_t pwm = p.pwm[k];
    const double u = pwm == 0 ? 0.0 : map_.motors[k].direction * (static_cast<double>(pwm) - 1500.0) / 400.0;
    u_[static_cast<std::size_t>(thruster_of_motor_[k])] = std::clamp(u, -1.0, 1.0);
  }
  sim_->set_command(sim_->time(), u_);
  // Whole physics steps up to the frames' total time; a remainder waits for the next frame.
  target_time_ += 1.0 / p.frame_rate;
  const double dt = sim_->options().dt;
  while (sim_->time() + 0.5 * dt <= target_time_) {
    sim_->step();
    ++stats_.steps;
  }
  ++stats_.frames;
  reply_ = format_state_json(fdm_state(*sim_));
  return reply_;
}

}  // namespace unav::autopilot
