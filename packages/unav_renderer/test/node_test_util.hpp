// Shared by the renderer's and the sonar's node tests: a node started on a scenario file, and a
// probe that publishes the vehicles' ground truth.
#pragma once

#include <string>
#include <vector>

#include "nav_msgs/msg/odometry.hpp"
#include "unav_runtime/testing.hpp"

namespace unav::renderer::test {

// Node type N started with `-p scenario:=<scenario>` and `params` (more -p values), lockstep, and
// the probe's ground-truth publishers of the primary vehicle (/rov) and a fleet vehicle (/rov2).
template <class N>
struct ScenarioNode : unav::testing::NodeUnderTest<N> {
  ScenarioNode(const char* name, const std::string& scenario, const std::vector<std::string>& params = {})
      : unav::testing::NodeUnderTest<N>(name, args(scenario, params)) {}
  static std::vector<std::string> args(const std::string& scenario, const std::vector<std::string>& params) {
    std::vector<std::string> a = {"--ros-args", "-p", "scenario:=" + scenario, "-p", "lockstep:=true"};
    for (const auto& p : params) a.insert(a.end(), {"-p", p});
    return a;
  }
  std::shared_ptr<unav::Publisher<nav_msgs::msg::Odometry>> odom_pub =
      this->probe.template create_publisher<nav_msgs::msg::Odometry>("/rov/ground_truth/odom", unav::QoS::reliable());
  std::shared_ptr<unav::Publisher<nav_msgs::msg::Odometry>> other_pub =
      this->probe.template create_publisher<nav_msgs::msg::Odometry>("/rov2/ground_truth/odom", unav::QoS::reliable());
};

}  // namespace unav::renderer::test
