// ardusub_bridge: ArduSub's SITL flies our vehicle through ArduPilot's JSON physics backend
// (unav_autopilot/ardupilot_json.hpp: the protocol, the motor map, lockstep). The node owns the
// scenario's simulator (physics::build_simulator, as the physics server): it must not run beside
// a physics_server of the same vehicle.
//
//   UDP  <address>:<port> (default 127.0.0.1:9002): ArduPilot's servo packets in, the state out
//        (to the sender's address and port)
//   pub  the physics server's vehicle topics (unav_physics/vehicle_ports.hpp): /clock,
//        ground_truth/odom, /tf and thrusters/state every publish_period of simulated time (the
//        autopilot's commands as thrusters/state.commanded), imu, pressure, depth, dvl, range,
//        mag, gps as their readings come
// Simulated time advances only with the autopilot's packets; malformed packets are counted by
// reason and logged at most once per second. A bridge bound to a non-loopback address warns.
#pragma once

#include <chrono>
#include <memory>
#include <string>

#include "unav_autopilot/ardupilot_json.hpp"
#include "unav_common/config.hpp"
#include "unav_physics/vehicle_ports.hpp"
#include "unav_runtime/runtime.hpp"
#include "unav_scene/scenario.hpp"

namespace unav::autopilot {

struct ArduSubBridgeParams {
  /// its world (seabed, current), vehicle, initial state and dt; default: the installed
  /// config/scenarios/ardusub_pipe.yaml
  unav::scene::ScenarioParam scenario;
  std::string motor_map;  ///< default: the installed config/autopilot/ardusub_bluerov2_heavy.yaml
  std::string address = "127.0.0.1";
  int64_t port = 9002;
  double publish_period = 0.02;
  physics::PortFrames frames;

  template <class Archive>
  void Serialize(Archive* a) {
    using unav::common::Field;
    scenario.Serialize(a);
    a->Visit(Field("motor_map", &motor_map).Doc("ArduSub motor -> thruster map (config/autopilot/*.yaml)"));
    a->Visit(Field("address", &address).Doc("UDP address to bind (loopback by default; others warn)"));
    a->Visit(Field("port", &port).Range(0, 65535).Doc("UDP port ArduPilot's JSON backend sends to (0: any free one)"));
    a->Visit(Field("publish_period", &publish_period)
                 .Above(0.0)
                 .Max(1.0)
                 .Unit("s")
                 .Doc("simulated time between published states"));
    frames.Serialize(a);
  }
};

class ArduSubBridge : public unav::Node {
 public:
  explicit ArduSubBridge(const unav::NodeOptions& options);
  ~ArduSubBridge() override;
  ArduSubBridge(const ArduSubBridge&) = delete;
  ArduSubBridge& operator=(const ArduSubBridge&) = delete;

  const JsonBackend& backend() const { return *backend_; }
  /// The UDP port bound (the parameter, or the one the system chose for port 0 in tests).
  int bound_port() const { return bound_port_; }
  /// Wall time of handle() per packet (decode, physics, reply), microseconds: p50 and p99 so far.
  double handle_us_percentile(double q) const;

 private:
  void drain();  // reads and answers every datagram waiting (bounded per call)
  void log_drops();

  std::unique_ptr<JsonBackend> backend_;
  int fd_ = -1;
  int bound_port_ = 0;
  double publish_period_ = 0.02, next_publish_ = 0.0;
  std::unique_ptr<physics::VehiclePorts> ports_;
  std::vector<float> handle_us_;
  std::uint64_t logged_drops_ = 0;
  std::chrono::steady_clock::time_point last_drop_log_{};
  std::shared_ptr<unav::Timer> timer_;
};

}  // namespace unav::autopilot
