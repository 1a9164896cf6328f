#include "bag_trajectory.hpp"

#include <algorithm>
#include <map>
#include <numeric>
#include <set>

#include "unav_bag/bag.hpp"
#include "unav_introspection/cdr_codec.hpp"
#include "unav_introspection/type_registry.hpp"

namespace unav::evaluation {
namespace {

namespace intro = unav::introspection;

// IDL types of the workspace: environment and this executable's install
// (<install>/unav_evaluation/lib/unav_evaluation/unav_eval).
intro::TypeRegistry make_registry() {
  intro::TypeRegistry reg;
  reg.add_workspace(intro::executable_install_root(4));
  return reg;
}

double stamp_of(const YAML::Node& header) {
  return header["stamp"]["sec"].as<double>() + header["stamp"]["nanosec"].as<double>() * 1e-9;
}

Eigen::Isometry3d pose_of(const YAML::Node& position, const YAML::Node& orientation) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(position["x"].as<double>(), position["y"].as<double>(), position["z"].as<double>());
  Eigen::Quaterniond q(orientation["w"].as<double>(), orientation["x"].as<double>(), orientation["y"].as<double>(),
                       orientation["z"].as<double>());
  if (q.norm() < 1e-9) q = Eigen::Quaterniond::Identity();  // an unset orientation
  T.linear() = q.normalized().toRotationMatrix();
  return T;
}

std::string strip_slash(std::string f) {
  while (!f.empty() && f.front() == '/') f.erase(0, 1);
  return f;
}

}  // namespace

Trajectory read_bag_trajectory(const std::string& bag, const std::string& topic_or_tf) {
  const std::string& what = topic_or_tf;
  std::unique_ptr<unav::bag::BagReader> reader;
  try {
    reader = std::make_unique<unav::bag::BagReader>(bag);
  } catch (const unav::bag::BagError& e) {
    throw TrajectoryError(e.what());
  }
  const bool tf = what.rfind("/tf:", 0) == 0;
  std::string parent, child;
  if (tf) {
    const std::string pair = what.substr(4);
    const size_t dot = pair.find('.');
    if (dot == std::string::npos || dot == 0 || dot + 1 == pair.size())
      throw TrajectoryError("'" + what +
                            "': a frame pair is written /tf:PARENT.CHILD (e.g. /tf:world_ned.base_link_frd)");
    parent = strip_slash(pair.substr(0, dot));
    child = strip_slash(pair.substr(dot + 1));
  }
  std::map<size_t, std::string> wanted;  // topic index -> type
  std::string available;
  for (size_t i = 0; i < reader->topics().size(); ++i) {
    const auto& t = reader->topics()[i];
    available += " " + t.name + " [" + t.type + "]";
    if (tf ? (t.name == "/tf" || t.name == "/tf_static") : t.name == what) wanted[i] = t.type;
  }
  if (wanted.empty())
    throw TrajectoryError(bag + ": no topic " + (tf ? "/tf or /tf_static" : "'" + what + "'") +
                          " (topics:" + available + ")");
  static const std::set<std::string> supported = {"nav_msgs/msg/Odometry", "geometry_msgs/msg/PoseStamped",
                                                  "geometry_msgs/msg/PoseWithCovarianceStamped",
                                                  "geometry_msgs/msg/TransformStamped", "tf2_msgs/msg/TFMessage"};
  intro::TypeRegistry reg = make_registry();
  std::map<size_t, const intro::StructType*> types;
  for (const auto& [i, type] : wanted) {
    if (!supported.count(type))
      throw TrajectoryError(bag + ": topic '" + what + "' has type " + type +
                            " (supported: nav_msgs/msg/Odometry, geometry_msgs/msg/PoseStamped, "
                            "PoseWithCovarianceStamped, TransformStamped, or /tf:PARENT.CHILD)");
    try {
      types[i] = &reg.load(type);
    } catch (const std::exception& e) {
      throw TrajectoryError(std::string("no IDL for ") + type + ": " + e.what());
    }
  }
  std::vector<std::pair<double, Eigen::Isometry3d>> poses;
  std::set<std::string> pairs_seen;
  unav::bag::Message m;
  while (reader->next(m)) {
    const auto it = types.find(m.topic);
    if (it == types.end()) continue;
    YAML::Node msg;
    try {
      msg = intro::decode(*it->second, m.data.data(), m.data.size());
    } catch (const intro::CodecError& e) {
      throw TrajectoryError(bag + ": a message of '" + reader->topics()[m.topic].name +
                            "' does not decode: " + e.what());
    }
    const std::string& type = wanted[m.topic];
    if (type == "nav_msgs/msg/Odometry" || type == "geometry_msgs/msg/PoseWithCovarianceStamped") {
      poses.emplace_back(stamp_of(msg["header"]),
                         pose_of(msg["pose"]["pose"]["position"], msg["pose"]["pose"]["orientation"]));
    } else if (type == "geometry_msgs/msg/PoseStamped") {
      poses.emplace_back(stamp_of(msg["header"]), pose_of(msg["pose"]["position"], msg["pose"]["orientation"]));
    } else {
      YAML::Node list(YAML::NodeType::Sequence);
      if (type == "tf2_msgs/msg/TFMessage")
        list = msg["transforms"];
      else
        list.push_back(msg);
      for (const auto& t : list) {
        const std::string p = strip_slash(t["header"]["frame_id"].as<std::string>());
        const std::string c = strip_slash(t["child_frame_id"].as<std::string>());
        pairs_seen.insert(p + "." + c);
        if (tf ? (p == parent && c == child) : true)
          poses.emplace_back(stamp_of(t["header"]), pose_of(t["transform"]["translation"], t["transform"]["rotation"]));
      }
    }
  }
  if (poses.empty()) {
    std::string seen;
    for (const auto& s : pairs_seen) seen += " " + s;
    throw TrajectoryError(bag + ": no pose for '" + what + "'" + (tf ? " (frame pairs in the bag:" + seen + ")" : ""));
  }
  // Bag order is arrival order; the trajectory is in stamp order (stable for equal stamps).
  std::vector<size_t> order(poses.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return poses[a].first < poses[b].first; });
  Trajectory traj;
  for (const size_t k : order) traj.push_back(poses[k].first, poses[k].second);
  return traj;
}

}  // namespace unav::evaluation
