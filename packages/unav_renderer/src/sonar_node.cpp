#include "sonar_node.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <optional>

#include "unav_common/resources.hpp"
#include "unav_runtime/conversions.hpp"
#include "unav_scene/sonar.hpp"
#include "unav_scene/water.hpp"
#include "unav_scene/world.hpp"

namespace unav::renderer {
namespace {

using marine_acoustic_msgs::msg::dds_::SonarImageData_;
using unav::scene::Pose;
using unav::scene::SonarModel;
using unav::scene::World;
namespace dtype = marine_acoustic_msgs::msg::SonarImageData_Constants;

// Samples of a ping into SonarImageData (row-major by range, `channels` values per row).
void fill_image_data(SonarImageData_& d, const SonarPing& ping, bool float32) {
  d.is_bigendian(false);
  d.beam_count(static_cast<uint32_t>(ping.channels));
  if (float32) {
    d.dtype(dtype::DTYPE_FLOAT32);
    d.data().resize(ping.intensity.size() * sizeof(float));
    std::memcpy(d.data().data(), ping.intensity.data(), d.data().size());  // little-endian hosts only
  } else {
    d.dtype(dtype::DTYPE_UINT8);
    d.data() = ping.image;
  }
}

void fill_mono8(sensor_msgs::msg::Image& m, int w, int h, const std::vector<std::uint8_t>& px) {
  m.width(static_cast<uint32_t>(w));
  m.height(static_cast<uint32_t>(h));
  m.encoding("mono8");
  m.is_bigendian(0);
  m.step(static_cast<uint32_t>(w));
  m.data() = px;
}

}  // namespace

SonarNode::SonarNode(const unav::NodeOptions& options) : Node("sonar", options, "rov") {
  SonarNodeParams prm;
  prm.scene.world = unav::common::resource_or_empty("worlds/pipe_inspection/world.yaml");
  prm.sonars_config = unav::common::resource_or_empty("config/sensors/bluerov2_sonars.yaml");
  declare_params(&prm);
  std::optional<unav::scene::Scenario> scenario;
  if (prm.scene.scenario.given()) {  // the sonar's part of the scenario
    scenario = prm.scene.scenario.load();
    const unav::scene::Scenario& sc = *scenario;
    if (sc.sonars.names.empty())
      throw unav::ConfigError(prm.scene.scenario.file, "sonars.names", "[]",
                              "the sonar node needs at least one sonar of the scenario's sonars.config");
    prm.scene.world = sc.world;
    prm.sonars_config = sc.sonars.config;
    prm.sonars = sc.sonars.names;
  }
  if (prm.scene.world.empty() || prm.sonars_config.empty())
    throw unav::ParameterError("node '" + name() +
                               "': 'world' and 'sonars_config' are required (unav_resources is not installed, so "
                               "there is no default)");
  fan_width_ = prm.fan_width;
  World world;
  std::vector<SonarModel> models;
  std::vector<std::string> others;  // the other vehicles of the scenario, drawn (fleet_bodies)
  try {
    world = load_sensor_world(prm.scene, scenario, get_namespace(), &others);
    if (prm.sonars.empty()) {
      models = unav::scene::load_sonars(prm.sonars_config);
    } else {
      for (const auto& n : prm.sonars) models.push_back(unav::scene::load_sonar(prm.sonars_config, n));
    }
  } catch (const std::exception& e) {
    throw unav::ConfigError(e.what());  // world/sonar/water errors name the file and key
  }
  lockstep_ = prm.lockstep.enabled;
  SonarOptions so;
  so.noise = prm.noise;
  so.seed = static_cast<std::uint64_t>(prm.seed);
  sonar_ = std::make_unique<SonarRenderer>(std::move(world), models, so);

  const unav::QoS qos = unav::QoS::reliable(5);
  for (const auto& m : models) {
    Ports p;
    p.name = m.name;
    p.side_scan = m.side_scan();
    p.period = 1.0 / m.ping_rate_hz;
    const std::string base = "sonar/" + m.name;
    if (m.side_scan()) {
      p.raw = create_publisher<marine_acoustic_msgs::msg::RawSonarImage>(base + "/raw", qos);
      if (prm.waterfall_lines > 0) {
        p.view = create_publisher<sensor_msgs::msg::Image>(base + "/waterfall", qos);
        p.waterfall = std::make_unique<Waterfall>(m.bins, prm.waterfall_lines);
      }
    } else {
      p.image = create_publisher<marine_acoustic_msgs::msg::ProjectedSonarImage>(base + "/image", qos);
      if (fan_width_ > 0) p.view = create_publisher<sensor_msgs::msg::Image>(base + "/image_fan", qos);
      if (m.profiling()) p.points = create_publisher<sensor_msgs::msg::PointCloud2>(base + "/points", qos);
    }
    ports_.push_back(std::move(p));
  }
  odom_sub_ = create_subscription<nav_msgs::msg::Odometry>("ground_truth/odom", unav::QoS::reliable(),
                                                           [this](const nav_msgs::msg::Odometry& m) { on_odom(m); });
  if (prm.lockstep.enabled) acker_ = std::make_unique<unav::lockstep::Acker>(*this, prm.lockstep.name);
  if (!others.empty())
    fleet_ = std::make_unique<FleetPoses>(
        *this, others, [this](const std::string& n, const Pose& X) { sonar_->set_object_pose(n, X); }, &rejections_);
  // Sonar mounts, latched, in marine_acoustic_msgs' frame (z forward, x up).
  tf_static_pub_ = create_publisher<tf2_msgs::msg::TFMessage>("/tf_static", unav::QoS::static_latched());
  tf2_msgs::msg::TFMessage mounts;
  for (const auto& m : models)
    mounts.transforms().push_back(
        unav::to_transform_stamped(m.frame_acoustic(), 0.0, prm.scene.body_frame, m.name + "_link"));
  tf_static_pub_->publish(mounts);
  std::string list;
  for (const auto& m : models)
    list += (list.empty() ? "" : ", ") + m.name + (m.side_scan() ? " (side-scan " : " (FLS ") +
            std::to_string(m.channels()) + "x" + std::to_string(m.bins) + ", " +
            std::to_string(m.ping_rate_hz).substr(0, 4) + " Hz)";
  logger()->info("world '{}', sonars {} on {}{}", prm.scene.world, list,
                 sonar_->context().gl_renderer() + " (EGL " + sonar_->context().platform() + ")",
                 prm.lockstep.enabled ? ", lockstep" : "");
}

SonarNode::~SonarNode() = default;

void SonarNode::on_odom(const nav_msgs::msg::Odometry& odom) {
  if (const std::string why = unav::odometry_problem(odom); !why.empty()) {
    rejections_.reject(odom_sub_->topic_name(), why);  // neither rendered nor acked
    return;
  }
  const double t = unav::seconds(odom.header());
  const double eps = 1e-6;  // stamps are integer nanoseconds
  const Pose X_WB = unav::from_msg(odom.pose().pose());
  const bool due = std::any_of(ports_.begin(), ports_.end(), [&](const Ports& p) { return t + eps >= p.next_t; });
  // Lockstep: the other vehicles as they are at this stamp (their states come in beside ours).
  if (due && lockstep_ && fleet_) {
    fleet_->when_current(unav::nanoseconds(odom.header()),
                         [this, X_WB, h = odom.header()] { ping_state(X_WB, h); });  // pinged and acked then
    return;
  }
  ping_state(X_WB, odom.header());
}

void SonarNode::ping_state(const Pose& X_WB, const std_msgs::msg::Header& header) {
  const double t = unav::seconds(header);
  const double eps = 1e-6;  // stamps are integer nanoseconds
  for (auto& p : ports_) {
    if (t + eps < p.next_t) continue;
    publish_ping(p, sonar_->ping(X_WB, p.name, t), header);
    p.next_t = (std::floor((t + eps) / p.period) + 1.0) * p.period;  // next multiple: no drift
  }
  if (acker_) acker_->ack(header);
}

void SonarNode::publish_profile(Ports& p, const SonarPing& ping, double detection_db, const std_msgs::msg::Header& h) {
  const auto points = detect_profile(ping, detection_db);
  sensor_msgs::msg::PointCloud2 cloud;
  cloud.header() = h;
  cloud.height(1);
  cloud.width(static_cast<std::uint32_t>(points.size()));
  const char* names[] = {"x", "y", "z", "intensity"};
  for (std::uint32_t i = 0; i < 4; ++i) {
    sensor_msgs::msg::PointField f;
    f.name(names[i]);
    f.offset(4 * i);
    f.datatype(7);  // FLOAT32
    f.count(1);
    cloud.fields().push_back(f);
  }
  cloud.is_bigendian(false);
  cloud.point_step(16);
  cloud.row_step(16 * cloud.width());
  cloud.is_dense(true);
  cloud.data().resize(static_cast<std::size_t>(cloud.row_step()));
  for (std::size_t i = 0; i < points.size(); ++i) {
    const float v[4] = {static_cast<float>(points[i].p_S.x()), static_cast<float>(points[i].p_S.y()),
                        static_cast<float>(points[i].p_S.z()), points[i].intensity};
    std::memcpy(cloud.data().data() + 16 * i, v, sizeof(v));
  }
  p.points->publish(cloud);
}

void SonarNode::publish_ping(Ports& p, const SonarPing& ping, const std_msgs::msg::Header& header) {
  const SonarModel& m = sonar_->sonar(p.name);
  const bool f32 = m.data_type == "float32";
  std_msgs::msg::Header h = header;
  h.frame_id(p.name + "_link");
  marine_acoustic_msgs::msg::dds_::PingInfo_ info;
  info.frequency(static_cast<float>(ping.frequency_hz));
  info.sound_speed(static_cast<float>(ping.sound_speed_mps));
  if (p.side_scan) {
    marine_acoustic_msgs::msg::RawSonarImage msg;
    msg.header() = h;
    info.tx_beamwidths(std::vector<float>(2, static_cast<float>(m.horizontal_aperture_rad)));
    info.rx_beamwidths(std::vector<float>(2, static_cast<float>(m.vertical_aperture_rad)));
    msg.ping_info(info);
    // Bin k is range r_min + (k + 0.5) dr, received at 2 r / c after transmission.
    msg.sample_rate(static_cast<float>(ping.sound_speed_mps / (2.0 * m.bin_width_m())));
    msg.samples_per_beam(static_cast<uint32_t>(m.bins));
    msg.sample0(static_cast<uint32_t>(std::lround(m.min_range_m / m.bin_width_m())));
    msg.tx_delays(std::vector<float>(2, 0.0f));
    msg.tx_angles(ping.azimuth_rad);
    msg.rx_angles(ping.azimuth_rad);
    fill_image_data(msg.image(), ping, f32);
    p.raw->publish(msg);
    if (p.waterfall) {
      p.waterfall->add(ping);
      sensor_msgs::msg::Image view;
      view.header() = h;
      fill_mono8(view, p.waterfall->width(), p.waterfall->height(), p.waterfall->pixels());
      p.view->publish(view);
    }
  } else {
    marine_acoustic_msgs::msg::ProjectedSonarImage msg;
    msg.header() = h;
    info.tx_beamwidths(
        std::vector<float>(static_cast<std::size_t>(m.beams), static_cast<float>(m.vertical_aperture_rad)));
    info.rx_beamwidths(
        std::vector<float>(static_cast<std::size_t>(m.beams), static_cast<float>(m.horizontal_aperture_rad / m.beams)));
    msg.ping_info(info);
    // Beam directions in the sonar frame (z forward, x up, y = z x x): azimuth is a rotation
    // about x, positive towards -y; our azimuths are positive to starboard (+y).
    msg.beam_directions().resize(ping.azimuth_rad.size());
    for (std::size_t k = 0; k < ping.azimuth_rad.size(); ++k) {
      const double az = m.beam_azimuth_rad(static_cast<int>(k));  // double: unit vectors to 1e-16
      auto& d = msg.beam_directions()[k];
      d.x(0.0);
      d.y(std::sin(az));
      d.z(std::cos(az));
    }
    msg.ranges(ping.ranges_m);
    fill_image_data(msg.image(), ping, f32);
    p.image->publish(msg);
    if (p.view) {
      const FanImage fan = fan_image(ping, fan_width_);
      sensor_msgs::msg::Image view;
      view.header() = h;
      fill_mono8(view, fan.width, fan.height, fan.pixels);
      p.view->publish(view);
    }
    if (p.points) publish_profile(p, ping, m.detection_db, h);
  }
  ++pings_;
}

}  // namespace unav::renderer
