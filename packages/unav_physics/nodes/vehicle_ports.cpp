#include "unav_physics/vehicle_ports.hpp"

#include <cmath>
#include <limits>
#include <utility>

#include <fastdds/dds/publisher/DataWriter.hpp>

#include "unav_runtime/conversions.hpp"

namespace unav::physics {

VehiclePorts::VehiclePorts(unav::Node& node, const VehicleParams& vehicle, const PortFrames& frames,
                           const std::string& fleet_name)
    : world_frame_(frames.world_frame),
      body_frame_(fleet_name.empty() ? frames.body_frame : fleet_name + "/" + frames.body_frame),
      usbl_(vehicle.sensors.usbl),
      log_(node.logger()) {
  const SensorSuiteParams& sensors = vehicle.sensors;
  // A fleet vehicle's topics are under /<fleet_name>, the primary's under the node's namespace.
  const auto topic = [&](const std::string& relative) {
    return fleet_name.empty() ? relative : "/" + fleet_name + "/" + relative;
  };
  const std::string ns = node.get_namespace();
  const std::string own_name = fleet_name.empty() ? ns.substr(ns.rfind('/') + 1) : fleet_name;
  const std::string station = !sensors.modem.station_vehicle.empty()
                                  ? "/" + sensors.modem.station_vehicle + "/modem/" + own_name + "/"
                              : fleet_name.empty() ? "/surface/modem/"
                                                   : "/surface/" + fleet_name + "/modem/";
  station_topics_ = station;
  if (vehicle.tether.enabled) {
    tether_wrench_pub_ =
        node.create_publisher<geometry_msgs::msg::WrenchStamped>(topic("tether/wrench"), unav::QoS::sensor_data());
    tether_path_pub_ = node.create_publisher<nav_msgs::msg::Path>(topic("tether/path"), unav::QoS::reliable(1));
  }
  if (fleet_name.empty())  // one clock: the primary vehicle's
    clock_pub_ = node.create_publisher<rosgraph_msgs::msg::Clock>("/clock", unav::QoS::reliable(1));
  // 100 deep (5 s of lockstep barriers, ~80 kB): a consumer stalled for a while (or dropped from
  // the lockstep) catches up on what its own reader history can hold.
  odom_pub_ = node.create_publisher<nav_msgs::msg::Odometry>(topic("ground_truth/odom"), unav::QoS::reliable(100));
  path_pub_ = node.create_publisher<nav_msgs::msg::Path>(topic("ground_truth/path"), unav::QoS::reliable(1));
  tf_pub_ = node.create_publisher<tf2_msgs::msg::TFMessage>("/tf", unav::QoS::reliable(100));
  tf_.transforms().resize(1);
  thruster_pub_ = node.create_publisher<unav_msgs::msg::ThrusterState>(topic("thrusters/state"), unav::QoS::reliable());
  if (sensors.imu.enabled)
    imu_pub_ = node.create_publisher<sensor_msgs::msg::Imu>(topic("imu"), unav::QoS::sensor_data());
  if (sensors.pressure.enabled) {
    pressure_pub_ = node.create_publisher<sensor_msgs::msg::FluidPressure>(topic("pressure"), unav::QoS::sensor_data());
    depth_pub_ = node.create_publisher<geometry_msgs::msg::PointStamped>(topic("depth"), unav::QoS::sensor_data());
  }
  if (sensors.dvl.enabled)
    dvl_pub_ = node.create_publisher<unav_msgs::msg::Dvl>(topic("dvl"), unav::QoS::sensor_data());
  if (sensors.altimeter.enabled)
    range_pub_ = node.create_publisher<sensor_msgs::msg::Range>(topic("range"), unav::QoS::sensor_data());
  if (sensors.magnetometer.enabled)
    mag_pub_ = node.create_publisher<sensor_msgs::msg::MagneticField>(topic("mag"), unav::QoS::sensor_data());
  if (sensors.gps.enabled)
    gps_pub_ = node.create_publisher<sensor_msgs::msg::NavSatFix>(topic("gps"), unav::QoS::sensor_data());
  // Reliable: a fix comes once a second or less and a navigation filter must not miss one.
  if (sensors.usbl.enabled)
    usbl_pub_ = node.create_publisher<unav_msgs::msg::UsblFix>(topic("usbl/fix"), unav::QoS::reliable());
  if (sensors.modem.enabled) {
    const std::uint64_t seed = static_cast<std::uint64_t>(sensors.seed) * 0x9E3779B97F4A7C15ULL + 8;
    modem_ = std::make_unique<AcousticModem>(sensors.modem, seed);
    const unav::QoS qos = unav::QoS::reliable(100);
    vehicle_rx_pub_ = node.create_publisher<unav_msgs::msg::AcousticPacket>(topic("modem/rx"), qos);
    station_rx_pub_ = node.create_publisher<unav_msgs::msg::AcousticPacket>(station + "rx", qos);
    vehicle_tx_sub_ = node.create_subscription<unav_msgs::msg::AcousticPacket>(
        topic("modem/tx"), qos,
        [this](const unav_msgs::msg::AcousticPacket& m) { queue_packet(AcousticModem::End::kVehicle, m); });
    station_tx_sub_ = node.create_subscription<unav_msgs::msg::AcousticPacket>(
        station + "tx", qos,
        [this](const unav_msgs::msg::AcousticPacket& m) { queue_packet(AcousticModem::End::kStation, m); });
  }
  odom_.header().frame_id(world_frame_);
  odom_.child_frame_id(body_frame_);
  thruster_state_.header().frame_id(body_frame_);
}

std::vector<eprosima::fastdds::dds::DataWriter*> VehiclePorts::state_writers() const {
  if (!clock_pub_) return {odom_pub_->writer(), tf_pub_->writer()};
  return {odom_pub_->writer(), tf_pub_->writer(), clock_pub_->writer()};
}

void VehiclePorts::fill_header(std_msgs::msg::dds_::Header_& h, double t, const std::string& frame) const {
  const unav::Time stamp{std::llround(t * 1e9)};
  h.stamp().sec(stamp.sec());
  h.stamp().nanosec(stamp.nanosec());
  h.frame_id(frame);
}

void VehiclePorts::publish_state(const Simulator& sim) {
  const double t = sim.time();
  const unav::Time stamp{std::llround(t * 1e9)};
  if (clock_pub_) {
    clock_.clock().sec(stamp.sec());
    clock_.clock().nanosec(stamp.nanosec());
    clock_pub_->publish(clock_);
  }
  const RigidBodyState& x = sim.state();
  fill_header(odom_.header(), t, world_frame_);
  odom_.pose().pose() = unav::to_msg(x.p_WB_W, x.q_WB);
  odom_.twist().twist().linear() = unav::to_vector3_msg(x.v_WB_B);
  odom_.twist().twist().angular() = unav::to_vector3_msg(x.w_WB_B);
  odom_pub_->publish(odom_);
  if (path_t_ < 0.0 || t >= path_t_ + kPathPeriod - 1e-9 || t < path_t_) {  // (1e-9: steps sum to 0.5 inexactly)
    if (t < path_t_) path_.poses().clear();                                 // time went back: a new run
    path_t_ = t;
    auto& poses = path_.poses();
    if (poses.size() >= kPathPoses) poses.erase(poses.begin());
    geometry_msgs::msg::PoseStamped pose;
    pose.header() = odom_.header();
    pose.pose() = odom_.pose().pose();
    poses.push_back(pose);
    path_.header() = odom_.header();
    path_pub_->publish(path_);
  }
  // The vehicle on /tf (world_frame -> body_frame), for RViz, Foxglove and tf2 users.
  auto& tf = tf_.transforms()[0];
  tf.header() = odom_.header();
  tf.child_frame_id(body_frame_);
  tf.transform().translation() = unav::to_vector3_msg(x.p_WB_W);
  tf.transform().rotation() = odom_.pose().pose().orientation();
  tf_pub_->publish(tf_);
}

void VehiclePorts::publish_thruster_state(const Simulator& sim) {
  const auto& bank = sim.thrusters();
  const int n = bank.size();
  thruster_state_.commanded().resize(static_cast<size_t>(n));
  thruster_state_.filtered().resize(static_cast<size_t>(n));
  thruster_state_.thrust().resize(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) {
    thruster_state_.commanded()[static_cast<size_t>(i)] = sim.command()[i];
    thruster_state_.filtered()[static_cast<size_t>(i)] = bank.filtered_command()[i];
    thruster_state_.thrust()[static_cast<size_t>(i)] = bank.thrust()[i];
  }
  fill_header(thruster_state_.header(), sim.time(), body_frame_);
  thruster_pub_->publish(thruster_state_);
  if (tether_wrench_pub_ && sim.tether() != nullptr) publish_tether(sim);
}

void VehiclePorts::publish_tether(const Simulator& sim) {
  // The pull on the vehicle at the thruster-state rate, in body axes about the body origin.
  const Eigen::Vector3d f_B = sim.state().q_WB.conjugate() * sim.tether_force_W();
  const Eigen::Vector3d m_B = sim.tether()->params().attach_xyz_m.cross(f_B);
  geometry_msgs::msg::WrenchStamped w;
  fill_header(w.header(), sim.time(), body_frame_);
  w.wrench().force().x(f_B.x());
  w.wrench().force().y(f_B.y());
  w.wrench().force().z(f_B.z());
  w.wrench().torque().x(m_B.x());
  w.wrench().torque().y(m_B.y());
  w.wrench().torque().z(m_B.z());
  tether_wrench_pub_->publish(w);
  if (tether_calls_++ % 10 != 0) return;  // the shape at a tenth of that rate
  nav_msgs::msg::Path path;
  fill_header(path.header(), sim.time(), world_frame_);
  for (const auto& n : sim.tether()->nodes()) {
    geometry_msgs::msg::PoseStamped p;
    p.header(path.header());
    p.pose().position().x(n.x());
    p.pose().position().y(n.y());
    p.pose().position().z(n.z());
    p.pose().orientation().w(1.0);
    path.poses().push_back(p);
  }
  tether_path_pub_->publish(path);
}

void VehiclePorts::queue_packet(AcousticModem::End from, const unav_msgs::msg::AcousticPacket& m) {
  const auto r = modem_->send(modem_t_, from, m.data());
  const std::string end = from == AcousticModem::End::kVehicle ? std::string("modem/tx") : station_topics_ + "tx";
  if (r == AcousticModem::Send::kTooLong)
    log_->warn("{}: a {}-byte packet refused (max_packet_bytes {})", end, m.data().size(),
               modem_->params().max_packet_bytes);
  else if (r == AcousticModem::Send::kQueueFull)
    log_->warn("{}: packet refused, {} already queued (queue_packets)", end, modem_->params().queue_packets);
}

void VehiclePorts::carry_packets(const Simulator& sim) {
  const RigidBodyState& x = sim.state();
  modem_t_ = sim.time();
  arrivals_.clear();
  if (modem_carrier_ != nullptr)
    modem_->set_station_position(modem_carrier_->pose() * modem_->params().station_position);
  modem_->step(modem_t_, x.p_WB_W + x.q_WB * modem_->params().modem_xyz_m, &arrivals_);
  for (const auto& pk : arrivals_) {
    const bool to_vehicle = pk.to == AcousticModem::End::kVehicle;
    unav_msgs::msg::AcousticPacket m;
    fill_header(m.header(), pk.arrival, to_vehicle ? "modem" : "surface_modem");
    m.data(pk.data);
    m.travel_time(pk.arrival - pk.sent);
    m.range(pk.range_m);
    (to_vehicle ? vehicle_rx_pub_ : station_rx_pub_)->publish(m);
  }
}

void VehiclePorts::publish_sensors(const Simulator& sim) {
  if (modem_) carry_packets(sim);
  const SensorReadings& r = sim.sensors();
  if (imu_pub_ && r.imu.valid && r.imu.seq != last_seq_[0]) {
    last_seq_[0] = r.imu.seq;
    sensor_msgs::msg::Imu m;
    fill_header(m.header(), r.imu.stamp, body_frame_);
    m.orientation().x(r.imu.q_WB.x());
    m.orientation().y(r.imu.q_WB.y());
    m.orientation().z(r.imu.q_WB.z());
    m.orientation().w(r.imu.q_WB.w());
    m.angular_velocity().x(r.imu.angular_rate_B.x());
    m.angular_velocity().y(r.imu.angular_rate_B.y());
    m.angular_velocity().z(r.imu.angular_rate_B.z());
    m.linear_acceleration().x(r.imu.specific_force_B.x());
    m.linear_acceleration().y(r.imu.specific_force_B.y());
    m.linear_acceleration().z(r.imu.specific_force_B.z());
    imu_pub_->publish(m);
  }
  if (pressure_pub_ && r.pressure.valid && r.pressure.seq != last_seq_[1]) {
    last_seq_[1] = r.pressure.seq;
    sensor_msgs::msg::FluidPressure p;
    fill_header(p.header(), r.pressure.stamp, body_frame_);
    p.fluid_pressure(r.pressure.pressure_pa);
    pressure_pub_->publish(p);
    geometry_msgs::msg::PointStamped d;
    fill_header(d.header(), r.pressure.stamp, world_frame_);
    d.point().z(r.pressure.depth_m);
    depth_pub_->publish(d);
  }
  if (dvl_pub_ && r.dvl.seq != last_seq_[2] && r.dvl.seq > 0) {
    last_seq_[2] = r.dvl.seq;
    unav_msgs::msg::Dvl d;
    fill_header(d.header(), r.dvl.stamp, body_frame_);
    d.velocity().x(r.dvl.velocity_B.x());
    d.velocity().y(r.dvl.velocity_B.y());
    d.velocity().z(r.dvl.velocity_B.z());
    d.altitude(r.dvl.altitude_m);
    d.valid(r.dvl.valid);
    d.locked_beams(r.dvl.locked_beams);
    for (std::size_t i = 0; i < 4; ++i) {
      d.beam_valid()[i] = r.dvl.beam_valid[i];
      d.beam_range()[i] = r.dvl.beam_valid[i] ? r.dvl.beam_range_m[i] : 0.0;
      d.beam_velocity()[i] = r.dvl.beam_valid[i] ? r.dvl.beam_velocity[i] : 0.0;
    }
    dvl_pub_->publish(d);
  }
  if (range_pub_ && r.altimeter.seq != last_seq_[3] && r.altimeter.seq > 0) {
    last_seq_[3] = r.altimeter.seq;
    sensor_msgs::msg::Range m;
    fill_header(m.header(), r.altimeter.stamp, body_frame_);
    m.radiation_type(0);  // ULTRASOUND
    m.field_of_view(0.1f);
    m.range(r.altimeter.valid ? static_cast<float>(r.altimeter.range_m) : std::numeric_limits<float>::infinity());
    range_pub_->publish(m);
  }
  if (mag_pub_ && r.magnetometer.valid && r.magnetometer.seq != last_seq_[4]) {
    last_seq_[4] = r.magnetometer.seq;
    sensor_msgs::msg::MagneticField m;
    fill_header(m.header(), r.magnetometer.stamp, body_frame_);
    m.magnetic_field().x(r.magnetometer.field_B.x());
    m.magnetic_field().y(r.magnetometer.field_B.y());
    m.magnetic_field().z(r.magnetometer.field_B.z());
    mag_pub_->publish(m);
  }
  if (gps_pub_ && r.gps.seq != last_seq_[5] && r.gps.seq > 0) {
    last_seq_[5] = r.gps.seq;
    sensor_msgs::msg::NavSatFix m;
    fill_header(m.header(), r.gps.stamp, "gps");
    m.status().status(r.gps.valid ? 0 : -1);  // STATUS_FIX / STATUS_NO_FIX
    m.status().service(1);                    // SERVICE_GPS
    m.latitude(r.gps.latitude_deg);
    m.longitude(r.gps.longitude_deg);
    m.altitude(r.gps.altitude_m);
    gps_pub_->publish(m);
  }
  if (usbl_pub_ && r.usbl.seq != last_seq_[6] && r.usbl.seq > 0) {
    last_seq_[6] = r.usbl.seq;
    unav_msgs::msg::UsblFix m;
    fill_header(m.header(), r.usbl.stamp, "usbl_transceiver");
    m.travel_time(r.usbl.stamp - r.usbl.ping_stamp);
    m.valid(r.usbl.valid);
    if (r.usbl.valid) {
      m.range(r.usbl.range_m);
      m.azimuth(r.usbl.azimuth_rad);
      m.elevation(r.usbl.elevation_rad);
      m.position().x(r.usbl.p_X.x());
      m.position().y(r.usbl.p_X.y());
      m.position().z(r.usbl.p_X.z());
      const Eigen::Matrix3d cov = usbl_fix_covariance(usbl_, r.usbl);
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
          m.position_covariance()[(3 * static_cast<std::size_t>(i)) + static_cast<std::size_t>(j)] = cov(i, j);
      m.position_world().x(r.usbl.p_W.x());
      m.position_world().y(r.usbl.p_W.y());
      m.position_world().z(r.usbl.p_W.z());
    }
    usbl_pub_->publish(m);
  }
}

}  // namespace unav::physics
