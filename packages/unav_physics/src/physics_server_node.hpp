// physics_server: the simulated vehicle as a node. Owns simulated time and publishes /clock.
//
// Ports (names relative to the node namespace, default /rov; frames world_ned / base_link_frd):
//   sub  thrusters/command     unav_msgs/ThrusterCommand          reliable     u_i in [-1, 1]; NaN/Inf, a wrong
//                                                                             length or a stamp > 1 s ahead of
//                                                                             simulated time: rejected, counted
//   sub  /lockstep/ack         unav_msgs/LockstepAck              reliable     (lockstep mode)
//   sub  /lockstep/drop        std_msgs/String                    reliable     stop waiting for a participant
//   sub  sim/reset             geometry_msgs/Pose                 reliable     new episode: the vehicle to
//                                                                             this pose at rest, time runs on
//   pub  /clock                rosgraph_msgs/Clock                reliable     every publish tick
//   pub  ground_truth/odom     nav_msgs/Odometry                  reliable 100 publish_rate
//   pub  /tf                   tf2_msgs/TFMessage                 reliable     publish_rate, world_frame -> body_frame
//   pub  thrusters/state       unav_msgs/ThrusterState            reliable     thruster_state_rate
//   pub  imu                   sensor_msgs/Imu                    sensor_data  per vehicle config
//   pub  pressure              sensor_msgs/FluidPressure          sensor_data
//   pub  depth                 geometry_msgs/PointStamped         sensor_data  z = depth [m]
//   pub  dvl                   unav_msgs/Dvl                      sensor_data
//   pub  range                 sensor_msgs/Range                  sensor_data  altimeter
//   pub  mag                   sensor_msgs/MagneticField          sensor_data
//   pub  gps                   sensor_msgs/NavSatFix              sensor_data  NO_FIX below 0.1 m
//   pub  usbl/fix              unav_msgs/UsblFix                  reliable     after the acoustic round trip
//   sub  modem/tx, /surface/modem/tx   unav_msgs/AcousticPacket   reliable 100 bytes to send (acoustic modem)
//   pub  /surface/modem/rx, modem/rx   unav_msgs/AcousticPacket   reliable 100 what arrived, in simulated time
//   sub  tether/length         std_msgs/Float64                   reliable     length paid out [m] (> 0)
//   pub  tether/wrench         geometry_msgs/WrenchStamped        sensor_data  the tether's pull, body frame
//   pub  tether/path           nav_msgs/Path                      reliable 1   its nodes, anchor first (10 Hz)
//
// Time modes:
//   realtime  simulated time follows the wall clock times real_time_factor.
//   lockstep  simulated time advances as fast as the participants allow. Every lockstep_period
//             seconds of simulated time is a barrier t_k: the server publishes /clock and the
//             odometry stamped t_k, then does not step past t_k until (a) every name in
//             lockstep_participants has published a LockstepAck stamped >= t_k (each participant
//             acks every barrier, after publishing whatever it had due at t_k) and (b), when
//             lockstep_wait_for_command is true, a ThrusterCommand stamped >= t_k has arrived
//             (the controller chain stamps its command with the state's time).
//             With no participants and no command wait, it runs as fast as it can. While it
//             holds, the barrier's state is published again every wall second (late joiners)
//             and a warning names the missing participants 3 s into a hold, then every 5 s.
//             A participant that hung or died for good can be dropped from the barrier while
//             the run goes on: `unav topic pub --once /lockstep/drop std_msgs/msg/String
//             '{data: recorder}'`.
// Failsafe: no command for command_timeout seconds of simulated time -> zero thrust, logged once.
// Fleet: a scenario's `fleet` vehicles are stepped with the primary one, in the same world and
// water, each with the ports above under /<name>/ (its own thrusters/command, ground_truth/odom,
// sensors, ...), its body frame <name>/base_link_frd on /tf and its modem's station side on
// /surface/<name>/modem/{tx,rx}; one /clock. With lockstep_wait_for_command, a barrier waits for
// every vehicle's command stamped at it; sim/reset moves the primary vehicle only.
// World: with `world` set, the world file's seabed (flat, relief, heightmap; the renderer's scene)
// is the contact surface and the DVL/altimeter target, and its `current` is the water current.
#pragma once

#include <memory>
#include <set>
#include <string>
#include <vector>

#include "geometry_msgs/msg/point_stamped.hpp"
#include "geometry_msgs/msg/pose.hpp"
#include "nav_msgs/msg/odometry.hpp"
#include "rosgraph_msgs/msg/clock.hpp"
#include "sensor_msgs/msg/fluid_pressure.hpp"
#include "sensor_msgs/msg/imu.hpp"
#include "sensor_msgs/msg/magnetic_field.hpp"
#include "sensor_msgs/msg/nav_sat_fix.hpp"
#include "sensor_msgs/msg/range.hpp"
#include "std_msgs/msg/float64.hpp"
#include "std_msgs/msg/string.hpp"
#include "tf2_msgs/msg/tf_message.hpp"
#include "unav_common/config.hpp"
#include "unav_msgs/msg/dvl.hpp"
#include "unav_msgs/msg/lockstep_ack.hpp"
#include "unav_msgs/msg/thruster_command.hpp"
#include "unav_msgs/msg/thruster_state.hpp"
#include "unav_physics/scenario_builder.hpp"
#include "unav_physics/simulator.hpp"
#include "unav_physics/vehicle_ports.hpp"
#include "unav_runtime/lockstep.hpp"
#include "unav_runtime/runtime.hpp"
#include "unav_runtime/validation.hpp"
#include "unav_scene/scenario.hpp"
#include "unav_scene/world.hpp"

namespace unav::physics {

/// The physics_server's parameters (params file or `-p name:=value`; `physics_server --help`).
struct PhysicsServerParams {
  /// its world, vehicle, physics and initial state replace vehicle_config, world, dt, integrator,
  /// initial_position and initial_rpy (the in-process Episode builds the same)
  unav::scene::ScenarioParam scenario;
  std::string vehicle_config;  ///< default: the installed bluerov2_heavy.yaml
  std::string world;
  std::string current_config;
  double seabed_depth = 10.0;
  std::string seabed_config;
  Eigen::Vector3d initial_position{0.0, 0.0, 5.0};
  Eigen::Vector3d initial_rpy{0.0, 0.0, 0.0};
  double dt = 0.001;
  std::string integrator = "velocity_verlet";
  double command_timeout = 0.5;
  std::string mode = "realtime";
  double real_time_factor = 1.0;
  double publish_rate = 200.0;
  double thruster_state_rate = 100.0;
  double lockstep_period = 0.05;
  std::vector<std::string> lockstep_participants;
  bool lockstep_wait_for_command = false;
  double max_sim_time = 0.0;
  PortFrames frames;

  template <class Archive>
  void Serialize(Archive* a) {
    using unav::common::Field;
    scenario.Serialize(a);
    a->Visit(Field("vehicle_config", &vehicle_config).Doc("vehicle YAML (config/vehicles/*.yaml)"));
    a->Visit(Field("world", &world)
                 .Doc("world.yaml: its seabed (relief, heightmap) and current drive the physics; "
                      "current_config/seabed_config override them"));
    a->Visit(Field("current_config", &current_config).Doc("water current YAML; empty = the world's or still water"));
    a->Visit(Field("seabed_depth", &seabed_depth).Unit("m").Doc("flat seabed depth without a world; <= 0 = none"));
    a->Visit(
        Field("seabed_config", &seabed_config).Doc("seabed YAML (flat/grid/PGM); overrides world and seabed_depth"));
    a->Visit(Field("initial_position", &initial_position).Unit("m").Doc("initial position, NED"));
    a->Visit(Field("initial_rpy", &initial_rpy).Unit("rad").Doc("initial roll, pitch, yaw"));
    a->Visit(Field("dt", &dt).Range(1e-5, 0.1).Unit("s").Doc("physics step (1 kHz default)"));
    a->Visit(Field("integrator", &integrator).OneOf({"velocity_verlet", "rk4"}).Doc("velocity_verlet is the paper's"));
    a->Visit(Field("command_timeout", &command_timeout)
                 .Unit("s")
                 .Doc("zero thrust after this long without a command; <= 0 disables"));
    a->Visit(Field("mode", &mode).OneOf({"realtime", "lockstep"}).Doc("time mode (see physics_server_node.hpp)"));
    a->Visit(Field("real_time_factor", &real_time_factor).Range(1e-3, 1e4).Doc("simulated / wall time (realtime)"));
    a->Visit(Field("publish_rate", &publish_rate).Range(0.1, 1e4).Unit("Hz").Doc("odometry, /tf and /clock rate"));
    a->Visit(Field("thruster_state_rate", &thruster_state_rate).Range(0.1, 1e4).Unit("Hz").Doc("thruster state rate"));
    a->Visit(Field("lockstep_period", &lockstep_period).Range(1e-4, 10.0).Unit("s").Doc("barrier period"));
    a->Visit(Field("lockstep_participants", &lockstep_participants).Doc("names that ack every barrier"));
    a->Visit(Field("lockstep_wait_for_command", &lockstep_wait_for_command)
                 .Doc("hold each barrier until a command stamped at it arrives"));
    a->Visit(Field("max_sim_time", &max_sim_time).Min(0.0).Unit("s").Doc("stop (exit 0) here; 0 = run until stopped"));
    frames.Serialize(a);
  }
};

class PhysicsServer : public unav::Node {
 public:
  explicit PhysicsServer(const unav::NodeOptions& options);

  const Simulator& simulator() const { return *sim_; }
  /// The scenario's fleet vehicles, in its order.
  size_t fleet_size() const { return fleet_.size(); }
  const Simulator& fleet_simulator(size_t i) const { return *fleet_.at(i).sim; }
  /// Runs simulation steps now (normally driven by the timer and by acks).
  void run_steps();

 private:
  /// The simulator from the node's own parameters (no scenario): vehicle_config, world or
  /// seabed_config/seabed_depth, current_config, initial_position/initial_rpy.
  void build_from_params(const PhysicsServerParams& p, const SimulatorOptions& so, const VehicleParams& vehicle);
  void on_command(const unav_msgs::msg::ThrusterCommand& msg);
  /// A command to `sim` if it passes the checks (stamp, length, finite); rejections counted under
  /// `topic`, the 1st, 2nd, 4th ... logged (`*logged`: the count last logged). True if applied.
  bool apply_command(Simulator& sim, const std::string& topic, const unav_msgs::msg::ThrusterCommand& msg,
                     std::uint64_t* logged);
  static constexpr double kMaxCommandLead = 1.0;  ///< s a command's stamp may be ahead of simulated time
  void on_ack(const unav_msgs::msg::LockstepAck& msg);
  void on_drop(const std::string& who);
  void on_reset(const geometry_msgs::msg::Pose& pose);

 public:
  /// Rejected input messages by topic (sim/reset: NaN/Inf, not a unit quaternion).
  const unav::RejectionCounter& rejections() const { return rejections_; }

 private:
  bool barrier_open() const;
  int64_t barrier_ns() const;
  /// The participants the barrier waits for, each with its last ack (for the hold warnings).
  std::string missing_with_acks() const;
  void hold_at_barrier();
  void step_once();
  void publish_state();
  void publish_sensors();
  void publish_thruster_state();

  std::unique_ptr<Simulator> sim_;
  std::string world_frame_, body_frame_;
  bool lockstep_ = false;
  double max_sim_time_ = 0.0;
  double real_time_factor_ = 1.0;
  double publish_period_ = 0.005, thruster_state_period_ = 0.01, lockstep_period_ = 0.05;
  bool wait_for_command_ = false;
  std::vector<std::string> participants_;
  int64_t steps_per_publish_ = 5, steps_per_thruster_state_ = 10, steps_per_barrier_ = 50;

  // Lockstep bookkeeping (simulated seconds).
  double barrier_t_ = -1.0;                            ///< barrier the server is holding at, < 0 when running
  std::unique_ptr<unav::lockstep::Barrier> barrier_;   ///< who must ack (lockstep mode)
  int64_t last_command_ns_ = INT64_MIN;                ///< newest thruster command stamp
  std::string last_input_;                             ///< the last ack's participant or "thruster command"
  unav::lockstep::HoldProfile hold_profile_;           ///< wall time held at barriers, per input that ended it
  double last_republish_ = 0.0, last_wait_log_ = 0.0;  ///< wall s (the hold's start: hold_profile_)
  double wall_start_ = 0.0;                            ///< realtime: wall time [s] that maps to simulated time 0
  bool timeout_logged_ = false;
  bool finishing_ = false;       ///< max_sim_time reached: waiting for the last acks, then exit
  double finish_started_ = 0.0;  ///< wall time [s] the finishing began
  void finish();
  std::uint64_t rejected_logged_ = 0;

  std::unique_ptr<VehiclePorts> ports_;
  struct FleetVehicle {
    std::string name;
    std::unique_ptr<Simulator> sim;
    std::unique_ptr<VehiclePorts> ports;
    std::shared_ptr<unav::Subscription<unav_msgs::msg::ThrusterCommand>> command_sub;
    std::uint64_t rejected_logged = 0;
    int64_t last_command_ns = INT64_MIN;  ///< newest command stamp (lockstep_wait_for_command)
  };
  std::vector<FleetVehicle> fleet_;
  /// USBL transceivers carried by another vehicle: (tracked vehicle, carrier), set each step.
  std::vector<std::pair<Simulator*, const Simulator*>> usbl_carriers_;
  /// Modem station ends carried by another vehicle: (0 = primary, i + 1 = fleet[i]; the carrier).
  std::vector<std::pair<std::size_t, const Simulator*>> modem_carriers_;
  std::shared_ptr<unav::Subscription<unav_msgs::msg::ThrusterCommand>> command_sub_;
  std::shared_ptr<unav::Subscription<unav_msgs::msg::LockstepAck>> ack_sub_;
  std::shared_ptr<unav::Subscription<std_msgs::msg::String>> drop_sub_;
  std::shared_ptr<unav::Subscription<geometry_msgs::msg::Pose>> reset_sub_;
  std::shared_ptr<unav::Subscription<std_msgs::msg::Float64>> length_sub_;
  unav::RejectionCounter rejections_{logger()};
  int episodes_ = 1;
  std::shared_ptr<unav::Timer> timer_;
};

}  // namespace unav::physics
