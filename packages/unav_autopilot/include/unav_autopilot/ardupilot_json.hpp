// ArduPilot's JSON physics backend (libraries/SITL/examples/JSON in ArduPilot's sources), our
// side, DDS-free: ArduSub's SITL sends a servo packet per simulation frame over UDP and waits for
// the vehicle state in reply, so its clock is ours (lockstep).
//
//   servo packet (little-endian): uint16 magic (18458: 16 channels, 29569: 32 channels),
//                                 uint16 frame_rate [Hz], uint32 frame_count, uint16 pwm[16 | 32]
//   reply: "\n" + one compact JSON object + "\n":
//     {"timestamp":t,"imu":{"gyro":[p,q,r],"accel_body":[fx,fy,fz]},"position":[n,e,d],
//      "quaternion":[w,x,y,z],"attitude":[roll,pitch,yaw],"velocity":[vn,ve,vd],"rng_1":h}
//   timestamp in s; gyro rad/s and accel_body (specific force: level at rest [0,0,-9.81]) in body
//   FRD; position m and velocity m/s in NED from home; rng_1 the altitude above the seabed [m].
//
// Home is the world origin at the sea surface: ArduSub's SITL barometer derives the water
// pressure from the altitude relative to home, so depth = position.d only with home at sea level.
//
// Each new frame_count: the PWM of the motor map's channels becomes thruster commands
// (u = direction (pwm - 1500) / 400, 0 for a channel ArduPilot leaves at 0), the physics advances
// by 1 / frame_rate (whole physics steps, the remainder carried to the next frame: at 1000 Hz and
// dt = 1 ms one packet is one step) and the new state is the reply. A repeated frame_count (SITL
// resends after a 10 s silence) gets the same reply again without stepping; a frame_count lower
// than the last (SITL restarted) resets the vehicle to the scenario's initial state at time 0.
// Malformed packets (unknown magic, short, frame_rate 0, a mapped PWM outside [1000, 2000]) are
// counted by reason and dropped: nothing is integrated and nothing is answered.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "unav_common/config.hpp"
#include "unav_physics/simulator.hpp"
#include "unav_physics/vehicle.hpp"
#include "unav_scene/scenario.hpp"
#include "unav_scene/world.hpp"

namespace unav::autopilot {

constexpr std::uint16_t kMagic16 = 18458;
constexpr std::uint16_t kMagic32 = 29569;

/// One ArduPilot output channel driving one of our thrusters.
struct MotorChannel {
  std::string thruster;  ///< name in the vehicle file (e.g. T1)
  int direction = 1;     ///< +1: PWM > 1500 pushes along the thruster's direction; -1: against it

  template <class Archive>
  void Serialize(Archive* a) {
    using unav::common::Field;
    a->Visit(Field("thruster", &thruster).Doc("thruster name in the vehicle file"));
    a->Visit(Field("direction", &direction).Range(-1, 1).Doc("+1 / -1: sense of PWM > 1500 (0 is refused)"));
  }
};

/// The autopilot's motors in output order (motor k = servo channel k), for ArduSub's frame.
struct MotorMap {
  std::string frame = "vectored_6dof";  ///< ArduSub FRAME_CONFIG 2 (BlueROV2 Heavy)
  std::vector<MotorChannel> motors;

  template <class Archive>
  void Serialize(Archive* a) {
    using unav::common::Field;
    a->Visit(Field("frame", &frame).OneOf({"vectored_6dof"}).Doc("ArduSub frame the motors follow"));
    a->Visit(Field("motors", &motors).Doc("motor k = output channel k (MOT_k_DIRECTION = 1 on the autopilot)"));
  }
};

/// Reads a motor map file; ConfigError (file, key, value, rule) on bad input.
MotorMap load_motor_map(const std::string& path);

/// Checks `map` against the vehicle's thruster geometry and ArduSub's motor factors for the frame
/// (AP_Motors6DOF: forward, lateral, throttle, roll, pitch, yaw): every motor names a thruster of
/// the vehicle, no thruster twice, and each nonzero factor has the sign of the force or moment the
/// thruster makes for PWM > 1500. Throws ConfigError naming `file`, the motor and the factor.
void check_motor_map(const MotorMap& map, const physics::VehicleParams& vehicle, const std::string& file);

enum class PacketStatus { kOk, kShort, kUnknownMagic, kZeroFrameRate, kPwmOutOfRange };
const char* to_string(PacketStatus s);

struct ServoPacket {
  std::uint16_t magic = 0;
  std::uint16_t frame_rate = 0;
  std::uint32_t frame_count = 0;
  std::vector<std::uint16_t> pwm;  ///< 16 or 32 channels
};

/// Decodes a datagram. `checked_channels`: channels whose PWM must be 0 or in [1000, 2000].
PacketStatus parse_servo_packet(const std::uint8_t* data, std::size_t size, int checked_channels, ServoPacket* out);

/// The datagram ArduPilot sends (for tests and tools): 16 or 32 channels by `pwm`'s size.
std::vector<std::uint8_t> encode_servo_packet(std::uint16_t frame_rate, std::uint32_t frame_count,
                                              const std::vector<std::uint16_t>& pwm);

/// What the reply carries (frames as documented above).
struct FdmState {
  double timestamp = 0.0;
  Eigen::Vector3d gyro_B = Eigen::Vector3d::Zero();
  Eigen::Vector3d accel_B = Eigen::Vector3d::Zero();  ///< specific force
  Eigen::Vector3d position_N = Eigen::Vector3d::Zero();
  Eigen::Quaterniond q_NB = Eigen::Quaterniond::Identity();
  Eigen::Vector3d velocity_N = Eigen::Vector3d::Zero();
  double rangefinder_m = -1.0;  ///< < 0: no seabed below (rng_1 left out)
};
/// The state of a simulator as ArduPilot wants it.
FdmState fdm_state(const physics::Simulator& sim);
/// "\n{...}\n", compact (no spaces), numbers with 10 significant digits.
std::string format_state_json(const FdmState& s);

struct BackendStats {
  std::uint64_t packets = 0;               ///< datagrams received
  std::uint64_t frames = 0;                ///< new frames stepped
  std::uint64_t steps = 0;                 ///< physics steps
  std::uint64_t repeats = 0;               ///< repeated frame_count, answered again
  std::uint64_t resets = 0;                ///< frame_count went back: SITL restarted
  std::uint64_t gaps = 0;                  ///< frame_count jumped (frames lost on the way)
  std::array<std::uint64_t, 5> dropped{};  ///< by PacketStatus (index kOk unused)
  std::uint64_t dropped_total() const { return dropped[1] + dropped[2] + dropped[3] + dropped[4]; }
};

/// The physics end of the link: a scenario's simulator (physics::build_simulator: the world's
/// seabed and current) driven by servo packets.
class JsonBackend {
 public:
  /// Throws ConfigError when the motor map does not fit the vehicle (`map_file` names it).
  JsonBackend(const unav::scene::Scenario& scenario, const unav::scene::World& world, MotorMap map,
              const std::string& map_file);
  /// Handles one datagram; the reply to send back, or "" (dropped: see stats()).
  std::string handle(const std::uint8_t* data, std::size_t size);
  /// Status of the last handle() call.
  PacketStatus last_status() const { return last_status_; }
  const physics::Simulator& simulator() const { return *sim_; }
  /// The scenario's vehicle (loaded once; its sensors are what a node publishes).
  const physics::VehicleParams& vehicle() const { return vehicle_; }
  const BackendStats& stats() const { return stats_; }
  /// Thruster command of the last frame (our thruster order).
  const std::vector<double>& command() const { return u_; }

 private:
  void reset();
  unav::scene::Scenario scenario_;
  unav::scene::World world_;
  MotorMap map_;
  physics::VehicleParams vehicle_;
  std::vector<int> thruster_of_motor_;
  std::unique_ptr<physics::Simulator> sim_;
  std::vector<double> u_;
  BackendStats stats_;
  PacketStatus last_status_ = PacketStatus::kOk;
  bool started_ = false;
  std::uint32_t last_frame_ = 0;
  double target_time_ = 0.0;  // simulated time the frames so far add up to
  std::string reply_;
};

}  // namespace unav::autopilot
