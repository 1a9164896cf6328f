#include "underwater_renderer_node.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <optional>

#include <spdlog/fmt/fmt.h>

#include "unav_common/resources.hpp"
#include "unav_common/sampling.hpp"
#include "unav_runtime/conversions.hpp"
#include "unav_scene/camera.hpp"
#include "unav_scene/scenario.hpp"
#include "unav_scene/water.hpp"
#include "unav_scene/world.hpp"

namespace unav::renderer {
namespace {

std::string join(const std::vector<std::string>& parts) {
  std::string out;
  for (const auto& p : parts) out += (out.empty() ? "" : ", ") + p;
  return out;
}

void fill_image(sensor_msgs::msg::Image& m, int w, int h, const char* encoding, int bytes_per_px) {
  m.width(static_cast<uint32_t>(w));
  m.height(static_cast<uint32_t>(h));
  m.encoding(encoding);
  m.is_bigendian(0);
  m.step(static_cast<uint32_t>(w * bytes_per_px));
}

// An image stream's QoS: reliable, data-sharing bounded by the serialized size of its images (data
// and frame id). A data-sharing reader's samples live in the writer's pool (depth + 1 payloads),
// so the depth is that of the deepest image reader (klt_vo: 20) — one that falls behind loses no
// more than by transport — within 64 MiB of shared memory a stream, and at least 5 frames.
unav::QoS image_qos(sensor_msgs::msg::Image proto, const std::string& frame_id) {
  proto.header().frame_id(frame_id);
  proto.data().resize(size_t{proto.step()} * proto.height());
  const uint32_t bound = unav::serialized_bytes(proto);
  const auto depth = static_cast<int32_t>(std::clamp<uint32_t>((64u << 20) / bound, 5, 20));
  return unav::QoS::reliable(depth).with_data_sharing(bound);
}

}  // namespace

UnderwaterRendererNode::UnderwaterRendererNode(const unav::NodeOptions& options)
    : Node("underwater_renderer", options, "rov") {
  UnderwaterRendererParams prm;
  prm.scene.world = unav::common::resource_or_empty("worlds/pipe_inspection/world.yaml");
  prm.cameras_config = unav::common::resource_or_empty("config/sensors/bluerov2_cameras.yaml");
  declare_params(&prm);
  std::vector<CameraModel> scenario_cams;
  auto noise_seed = static_cast<std::uint64_t>(prm.seed);
  std::optional<scene::Scenario> scenario;
  if (prm.scene.scenario.given()) {  // the renderer's part of the scenario, as the in-process Episode takes it
    scenario = prm.scene.scenario.load();
    const scene::Scenario& sc = *scenario;
    prm.scene.world = sc.world;
    prm.cameras_config = sc.cameras.config;
    prm.cameras = sc.cameras.names;
    prm.render = sc.render;
    prm.rate = sc.cameras.rate_hz;
    noise_seed = unav::common::MixSeed(static_cast<std::uint64_t>(sc.seed));  // as Episode::reset(sc.seed)
    scenario_cams = scene::scenario_cameras(sc);
  }
  const std::string& world_path = prm.scene.world;
  const std::string& cameras_path = prm.cameras_config;
  const std::vector<std::string>& only = prm.cameras;
  const double rate = prm.rate;
  lockstep_ = prm.lockstep.enabled;
  ack_name_ = prm.lockstep.name;
  publish_depth_ = prm.publish_depth;
  publish_seg_ = prm.publish_segmentation;
  RenderOptions ro;
  static_cast<scene::RenderSettings&>(ro) = prm.render;
  ro.seed = noise_seed;
  period_ = 1.0 / rate;
  if (world_path.empty() || cameras_path.empty())
    throw unav::ParameterError("node '" + name() +
                               "': 'world' and 'cameras_config' are required (unav_resources "
                               "is not installed, so there is no default)");

  World world;
  std::vector<CameraModel> cams;
  std::vector<std::string> others;  // the other vehicles of the scenario, drawn (fleet_bodies)
  try {
    world = load_sensor_world(prm.scene, scenario, get_namespace(), &others);  // built as every run path builds it
    cams = load_cameras(cameras_path);
    if (!scenario_cams.empty()) {
      cams = std::move(scenario_cams);
    } else if (!only.empty()) {
      std::vector<CameraModel> picked;
      picked.reserve(only.size());
      for (const auto& n : only) picked.push_back(load_camera(cameras_path, n));  // error lists the file's cameras
      cams = std::move(picked);
    }
  } catch (const std::exception& e) {
    throw unav::ConfigError(e.what());  // world/camera/water errors name the file and key
  }
  // Lockstep: a frame instant's cameras in parallel, at most one worker each (the next instant
  // waits for the acks). Free-running: the workers left over take the following instants.
  const auto ncams = static_cast<std::int64_t>(cams.size());
  const int workers = static_cast<int>(lockstep_ ? std::min(prm.render_workers, ncams) : prm.render_workers);
  max_in_flight_ = lockstep_ ? 1 : static_cast<std::size_t>(std::max<std::int64_t>(1, prm.render_workers / ncams));
  renderer_ = std::make_unique<RendererPool>(std::move(world), cams, ro, std::max(1, workers));

  odom_sub_ = create_subscription<nav_msgs::msg::Odometry>("ground_truth/odom", unav::QoS::reliable(),
                                                           [this](const nav_msgs::msg::Odometry& m) { on_odom(m); });
  if (lockstep_) acker_ = std::make_unique<unav::lockstep::Acker>(*this, ack_name_);  // answers every state
  if (!others.empty())
    fleet_ = std::make_unique<FleetPoses>(
        *this, others, [this](const std::string& n, const Pose& X) { renderer_->set_object_pose(n, X); }, &rejections_);
  // Free-running, frames finish between odometry messages: 2 ms polls publish them (and the next
  // odometry does too).
  if (!lockstep_) poll_timer_ = create_wall_timer(std::chrono::milliseconds(2), [this] { publish_rendered(false); });
  const unav::QoS qos = unav::QoS::reliable(5);
  for (const auto& cam : cams) {
    const CameraModel c = cam.water_equivalent();  // behind a port: what the water sees
    CameraPorts p;
    p.name = c.name;
    const std::string base = "camera/" + c.name;
    fill_image(p.image_msg, c.width, c.height, "rgb8", 3);
    fill_image(p.depth_msg, c.width, c.height, "32FC1", 4);
    fill_image(p.seg_msg, c.width, c.height, "mono8", 1);
    // Images go by data-sharing to the readers on this host that ask for it (VO, SLAM, dataset
    // recorder, DRL planner); ROS 2 tools and other hosts get them by transport.
    const std::string frame_id = c.name + "_optical";
    p.image = create_publisher<sensor_msgs::msg::Image>(base + "/image_raw", image_qos(p.image_msg, frame_id));
    p.info = create_publisher<sensor_msgs::msg::CameraInfo>(base + "/camera_info", qos);
    if (publish_depth_)
      p.depth = create_publisher<sensor_msgs::msg::Image>(base + "/depth/image_raw", image_qos(p.depth_msg, frame_id));
    if (publish_seg_)
      p.seg =
          create_publisher<sensor_msgs::msg::Image>(base + "/segmentation/image_raw", image_qos(p.seg_msg, frame_id));
    auto& ci = p.info_msg;
    ci.width(static_cast<uint32_t>(c.width));
    ci.height(static_cast<uint32_t>(c.height));
    ci.distortion_model("plumb_bob");
    ci.d({c.distortion[0], c.distortion[1], c.distortion[2], c.distortion[3], c.distortion[4]});
    const Eigen::Matrix3d K = c.K();
    for (int r = 0; r < 3; ++r)
      for (int k = 0; k < 3; ++k) {
        const auto rs = static_cast<size_t>(r), ks = static_cast<size_t>(k);
        ci.k()[rs * 3 + ks] = K(r, k);
        ci.r()[rs * 3 + ks] = r == k ? 1.0 : 0.0;
        ci.p()[rs * 4 + ks] = K(r, k);
      }
    cameras_.push_back(std::move(p));
  }
  // Camera mounts, published once and latched by their owner: ROS 2 tools (RViz, Foxglove, tf2)
  // and our estimators and evaluator look them up instead of reading the camera YAML.
  const std::string& body_frame = prm.scene.body_frame;
  tf_static_pub_ = create_publisher<tf2_msgs::msg::TFMessage>("/tf_static", unav::QoS::static_latched());
  tf2_msgs::msg::TFMessage mounts;
  for (const auto& c : cams)
    mounts.transforms().push_back(unav::to_transform_stamped(c.X_BC, 0.0, body_frame, c.name + "_optical"));
  tf_static_pub_->publish(mounts);
  logger()->info("world '{}' ({} triangles), {} camera(s) at {:.1f} Hz on {}{}", world_path,
                 renderer_->triangle_count(), cameras_.size(), rate,
                 renderer_->gl_renderer() + " (EGL " + join(renderer_->platforms()) + ")",
                 lockstep_ ? ", lockstep" : "");
}

UnderwaterRendererNode::~UnderwaterRendererNode() {
  // Nothing is lost on shutdown: the frames still rendering are published (callbacks run on the
  // spinning thread, which has stopped).
  try {
    publish_rendered(true);
  } catch (const std::exception& e) {
    logger()->error("frames in flight at shutdown not published: {}", e.what());
  }
}

void UnderwaterRendererNode::on_odom(const nav_msgs::msg::Odometry& odom) {
  if (const std::string why = unav::odometry_problem(odom); !why.empty()) {
    rejections_.reject(odom_sub_->topic_name(), why);  // neither rendered nor acked
    return;
  }
  if (!lockstep_) publish_rendered(false);  // frames that finished since the last call
  const double t = unav::seconds(odom.header());
  const std::int64_t t_ns = unav::nanoseconds(odom.header());
  if (lockstep_ && t_ns == last_state_ns_ && t_ns == last_frame_ns_) {
    republish_last_frame();  // the server repeats a held state: a reader may have missed the frame
    if (acker_) acker_->ack(odom.header());
    return;
  }
  last_state_ns_ = t_ns;
  const double eps = 1e-6;  // stamps are integer nanoseconds
  if (next_frame_t_ < 0.0) {
    // The first frame is on the grid of the period (k * period), also for a renderer that starts
    // (or is respawned) mid-run: a dataset's frames stay evenly spaced.
    next_frame_t_ = std::ceil((t - eps) / period_) * period_;
  }
  if (t + eps >= next_frame_t_) {
    // The twist is in the child frame (base_link_frd), as nav_msgs/Odometry defines it.
    BodyVelocity velocity;
    velocity.linear = unav::from_msg(odom.twist().twist().linear());
    velocity.angular = unav::from_msg(odom.twist().twist().angular());
    const Pose X_WB = unav::from_msg(odom.pose().pose());
    // Lockstep: the other vehicles as they are at this stamp (their states come in beside ours).
    if (lockstep_ && fleet_) {
      fleet_->when_current(t_ns, [this, X_WB, velocity, h = odom.header()] { render_state(X_WB, velocity, h); });
      return;
    }
    render_state(X_WB, velocity, odom.header());
    return;
  }
  if (acker_) acker_->ack(odom.header());
}

void UnderwaterRendererNode::render_state(const Pose& X_WB, const BodyVelocity& velocity,
                                          const std_msgs::msg::dds_::Header_& header) {
  const double eps = 1e-6;
  const double t = unav::seconds(header);
  submit(X_WB, velocity, header);
  if (lockstep_) publish_rendered(true);  // before the ack: the barrier holds until it is out
  last_frame_ns_ = unav::nanoseconds(header);
  // Next frame instant: the next multiple of the period after t (no drift, no bursts).
  next_frame_t_ = (std::floor((t + eps) / period_) + 1.0) * period_;
  if (acker_) acker_->ack(header);
}

void UnderwaterRendererNode::submit(const Pose& X_WB, const BodyVelocity& velocity,
                                    const std_msgs::msg::dds_::Header_& header) {
  // Full: the oldest instant is published first (waiting for it), so none is dropped.
  while (in_flight_.size() >= max_in_flight_) publish_next();
  const double t = unav::Time::from_msg(header.stamp().sec(), header.stamp().nanosec()).seconds();
  for (const auto& c : cameras_) renderer_->submit(X_WB, c.name, t, velocity);  // in parallel
  in_flight_.push_back({header, 0});
  peak_in_flight_ = std::max(peak_in_flight_, in_flight_.size());
}

void UnderwaterRendererNode::publish_rendered(bool wait) {
  while (!in_flight_.empty() && (wait || renderer_->ready())) publish_next();
}

void UnderwaterRendererNode::publish_next() {
  Instant& k = in_flight_.front();
  Frame f = renderer_->collect();  // in submission order: the oldest instant's next camera
  publish_frame(cameras_[k.published], f, k.header);
  renderer_->recycle(std::move(f));  // its buffers (the messages' previous ones) for a later frame
  if (++k.published == cameras_.size()) {
    in_flight_.pop_front();
    ++frames_;
  }
}

void UnderwaterRendererNode::publish_frame(CameraPorts& c, Frame& f, const std_msgs::msg::dds_::Header_& header) {
  const std::string frame_id = c.name + "_optical";
  for (auto* m : {&c.image_msg, &c.depth_msg, &c.seg_msg}) {
    m->header().stamp() = header.stamp();
    m->header().frame_id(frame_id);
  }
  c.info_msg.header().stamp() = header.stamp();
  c.info_msg.header().frame_id(frame_id);
  c.image_msg.data().swap(f.rgb);  // no copy: the frame's buffer becomes the message's
  c.image->publish(c.image_msg);
  if (c.depth) {
    c.depth_msg.data().resize(f.depth.size() * sizeof(float));
    std::memcpy(c.depth_msg.data().data(), f.depth.data(), c.depth_msg.data().size());
    c.depth->publish(c.depth_msg);
  }
  if (c.seg) {
    c.seg_msg.data().swap(f.seg);
    c.seg->publish(c.seg_msg);
  }
  c.info->publish(c.info_msg);
}

void UnderwaterRendererNode::republish_last_frame() {
  if (last_frame_ns_ != repeated_ns_) {
    repeated_ns_ = last_frame_ns_;
    repeats_ = 0;
  }
  ++repeats_;
  std::string refused;
  for (auto& c : cameras_) {
    if (!c.image->publish(c.image_msg)) refused += " " + c.image->topic_name();
    if (c.depth && !c.depth->publish(c.depth_msg)) refused += " " + c.depth->topic_name();
    if (c.seg && !c.seg->publish(c.seg_msg)) refused += " " + c.seg->topic_name();
    c.info->publish(c.info_msg);
  }
  if (republished_++ == 0)
    logger()->info(
        "lockstep: the state at t = {:.3f} s was sent again (the barrier holds): its frame published "
        "again for readers that missed it (said once)",
        static_cast<double>(last_frame_ns_) * 1e-9);
  // A barrier held this long on a frame that went out: who reads each stream now, and whether the
  // middleware still takes our samples (a stream that stopped reaching its readers shows here).
  if (repeats_ == 3 || repeats_ % 10 == 0) {
    std::string readers;
    for (const auto& c : cameras_) {
      readers += fmt::format(" {}: rgb {}", c.name, c.image->subscription_count());
      if (c.depth) readers += fmt::format(", depth {}", c.depth->subscription_count());
      if (c.seg) readers += fmt::format(", seg {}", c.seg->subscription_count());
      readers += ";";
    }
    logger()->warn(
        "lockstep: the state at t = {:.3f} s came {} times; its frame was published again each time ({}); "
        "readers matched:{}",
        static_cast<double>(last_frame_ns_) * 1e-9, repeats_,
        refused.empty() ? std::string("all accepted") : "refused on" + refused, readers);
  }
}

}  // namespace unav::renderer
