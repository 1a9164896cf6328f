// Sensor mounts from /tf_static, the way tf2's StaticTransformBroadcaster/Buffer pair works: the
// mount's owner (the renderer for cameras) publishes it once, latched (transient local); any
// node looks it up here instead of reading the owner's YAML. A node that includes this links
// ros2_msgs (header-only here).
//
//   tf_ = std::make_unique<unav::StaticTransformListener>(*this);
//   tf_->on_update([this] { if (auto X_BC = tf_->lookup("base_link_frd", "down_optical")) ...; });
#pragma once

#include <functional>
#include <memory>
#include <optional>
#include <string>

#include "tf2_msgs/msg/tf_message.hpp"
#include "unav_common/frames.hpp"
#include "unav_runtime/conversions.hpp"
#include "unav_runtime/node.hpp"

namespace unav {

class StaticTransformListener {
 public:
  explicit StaticTransformListener(Node& node)
      : sub_(node.create_subscription<tf2_msgs::msg::TFMessage>(
            "/tf_static", QoS{QoS::Reliability::kReliable, QoS::Durability::kTransientLocal, 100},
            [this](const tf2_msgs::msg::TFMessage& m) {
              for (const auto& t : m.transforms())
                graph_.set(t.header().frame_id(), t.child_frame_id(), from_msg(t.transform()));
              if (on_update_) on_update_();
            })) {}
  StaticTransformListener(const StaticTransformListener&) = delete;  // the callback holds `this`
  StaticTransformListener& operator=(const StaticTransformListener&) = delete;

  /// X_TS (frame `source` in frame `target`) from what arrived so far; nullopt until connected.
  std::optional<Eigen::Isometry3d> lookup(const std::string& target, const std::string& source) const {
    return graph_.lookup(target, source);
  }
  /// Called (on the executor thread) after every /tf_static message.
  void on_update(std::function<void()> callback) { on_update_ = std::move(callback); }
  const common::TransformGraph& graph() const { return graph_; }
  /// The subscription (tests wait for it to match).
  const std::shared_ptr<Subscription<tf2_msgs::msg::TFMessage>>& subscription() const { return sub_; }

 private:
  common::TransformGraph graph_;
  std::function<void()> on_update_;
  std::shared_ptr<Subscription<tf2_msgs::msg::TFMessage>> sub_;
};

}  // namespace unav
