// The topics a simulated vehicle publishes (DDS adapter, node code): /clock, ground_truth/odom and
// /tf of its state, ground_truth/path (its last 10 minutes, a pose every 0.5 s: the trajectory for
// RViz and Foxglove; bounded, the full record is the recorders'), thrusters/state, and its sensors (imu, pressure +
// depth, dvl, range, mag, gps, usbl/fix), and the acoustic modem link (modem/tx -> /surface/modem/rx, /surface/modem/tx
// -> modem/rx, delivered in simulated time) and, with a tether, its pull (tether/wrench) and shape (tether/path) as
// their readings come. One set of ports for every node that owns a vehicle's simulator: the physics server and the
// autopilot bridge publish alike, so every consumer runs beside either.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "geometry_msgs/msg/point_stamped.hpp"
#include "geometry_msgs/msg/pose_stamped.hpp"
#include "geometry_msgs/msg/wrench_stamped.hpp"
#include "nav_msgs/msg/odometry.hpp"
#include "nav_msgs/msg/path.hpp"
#include "rosgraph_msgs/msg/clock.hpp"
#include "sensor_msgs/msg/fluid_pressure.hpp"
#include "sensor_msgs/msg/imu.hpp"
#include "sensor_msgs/msg/magnetic_field.hpp"
#include "sensor_msgs/msg/nav_sat_fix.hpp"
#include "sensor_msgs/msg/range.hpp"
#include "tf2_msgs/msg/tf_message.hpp"
#include "unav_common/config.hpp"
#include "unav_msgs/msg/acoustic_packet.hpp"
#include "unav_msgs/msg/dvl.hpp"
#include "unav_msgs/msg/thruster_state.hpp"
#include "unav_msgs/msg/usbl_fix.hpp"
#include "unav_physics/simulator.hpp"
#include "unav_runtime/runtime.hpp"

namespace eprosima::fastdds::dds {
class DataWriter;
}

namespace unav::physics {

/// The frames a vehicle's ports stamp: the `world_frame` and `body_frame` parameters of every node
/// that owns a vehicle (Serialize visits both at the node's level).
struct PortFrames {
  std::string world_frame = "world_ned";
  std::string body_frame = "base_link_frd";
  template <class Archive>
  void Serialize(Archive* a) {
    a->Visit(unav::common::Field("world_frame", &world_frame).Doc("odometry and /tf parent frame"));
    a->Visit(unav::common::Field("body_frame", &body_frame).Doc("vehicle body frame"));
  }
};

class VehiclePorts {
 public:
  /// Creates the publishers on `node` (names relative to its namespace; /clock and /tf absolute);
  /// a sensor's topic only when the vehicle has it enabled. A fleet vehicle (`fleet_name` given)
  /// publishes under /<fleet_name>/ instead, its body frame is <fleet_name>/<body_frame>, its modem's
  /// station side is /surface/<fleet_name>/modem/{tx,rx}, and it has no /clock (the primary's). A
  /// modem whose station end another vehicle carries has that end at /<carrier>/modem/<name>/{tx,rx}
  /// (name: fleet_name, or the node's namespace's for the primary).
  VehiclePorts(unav::Node& node, const VehicleParams& vehicle, const PortFrames& frames,
               const std::string& fleet_name = "");
  /// /clock, ground_truth/odom (world_frame -> body_frame), /tf at the simulator's time.
  void publish_state(const Simulator& sim);
  void publish_thruster_state(const Simulator& sim);
  /// The readings that are new since the last call.
  void publish_sensors(const Simulator& sim);
  /// The vehicle carrying this vehicle's modem's station end (sensors.modem.station_vehicle); its
  /// pose places that end at every step. Null: the station is fixed in the world.
  void set_modem_station_carrier(const Simulator* carrier) { modem_carrier_ = carrier; }
  /// The writers of publish_state() (to wait for their acknowledgments before exit).
  std::vector<eprosima::fastdds::dds::DataWriter*> state_writers() const;

 private:
  void fill_header(std_msgs::msg::dds_::Header_& h, double t, const std::string& frame) const;

  std::string world_frame_, body_frame_;
  std::uint64_t last_seq_[7] = {0, 0, 0, 0, 0, 0, 0};
  UsblParams usbl_;
  const Simulator* modem_carrier_ = nullptr;
  std::string station_topics_;  ///< the station end's topic prefix (its tx and rx)
  std::shared_ptr<unav::Publisher<rosgraph_msgs::msg::Clock>> clock_pub_;
  std::shared_ptr<unav::Publisher<nav_msgs::msg::Odometry>> odom_pub_;
  std::shared_ptr<unav::Publisher<nav_msgs::msg::Path>> path_pub_;
  std::shared_ptr<unav::Publisher<tf2_msgs::msg::TFMessage>> tf_pub_;
  std::shared_ptr<unav::Publisher<unav_msgs::msg::ThrusterState>> thruster_pub_;
  std::shared_ptr<unav::Publisher<sensor_msgs::msg::Imu>> imu_pub_;
  std::shared_ptr<unav::Publisher<sensor_msgs::msg::FluidPressure>> pressure_pub_;
  std::shared_ptr<unav::Publisher<geometry_msgs::msg::PointStamped>> depth_pub_;
  std::shared_ptr<unav::Publisher<unav_msgs::msg::Dvl>> dvl_pub_;
  std::shared_ptr<unav::Publisher<sensor_msgs::msg::Range>> range_pub_;
  std::shared_ptr<unav::Publisher<sensor_msgs::msg::MagneticField>> mag_pub_;
  std::shared_ptr<unav::Publisher<sensor_msgs::msg::NavSatFix>> gps_pub_;
  std::shared_ptr<unav::Publisher<unav_msgs::msg::UsblFix>> usbl_pub_;
  std::shared_ptr<unav::Publisher<geometry_msgs::msg::WrenchStamped>> tether_wrench_pub_;
  std::shared_ptr<unav::Publisher<nav_msgs::msg::Path>> tether_path_pub_;
  static constexpr double kPathPeriod = 0.5;       ///< [s] of simulated time between ground_truth/path poses
  static constexpr std::size_t kPathPoses = 1200;  ///< 10 minutes of them; older ones are dropped
  double path_t_ = -1.0;                           ///< time of the last path pose
  std::uint64_t tether_calls_ = 0;
  void publish_tether(const Simulator& sim);
  void carry_packets(const Simulator& sim);
  void queue_packet(AcousticModem::End from, const unav_msgs::msg::AcousticPacket& m);
  std::unique_ptr<AcousticModem> modem_;
  double modem_t_ = 0.0;  ///< simulated time of the last step: packets handed over now leave then
  std::vector<AcousticModem::Packet> arrivals_;
  std::shared_ptr<unav::Publisher<unav_msgs::msg::AcousticPacket>> vehicle_rx_pub_, station_rx_pub_;
  std::shared_ptr<unav::Subscription<unav_msgs::msg::AcousticPacket>> vehicle_tx_sub_, station_tx_sub_;
  unav::Logger log_;
  // Reused messages (no allocation per publish after the first).
  nav_msgs::msg::Odometry odom_;
  nav_msgs::msg::Path path_;
  tf2_msgs::msg::TFMessage tf_;
  rosgraph_msgs::msg::Clock clock_;
  unav_msgs::msg::ThrusterState thruster_state_;
};

}  // namespace unav::physics
