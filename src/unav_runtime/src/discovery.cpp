#include "unav_runtime/discovery.hpp"

#include <arpa/inet.h>

#include <cstdlib>

#include "unav_runtime/errors.hpp"

namespace unav {

namespace {

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t");
  if (b == std::string::npos) return "";
  return s.substr(b, s.find_last_not_of(" \t") - b + 1);
}

}  // namespace

const char* to_string(DiscoveryRange range) {
  switch (range) {
    case DiscoveryRange::kSubnet:
      return "SUBNET";
    case DiscoveryRange::kLocalhost:
      return "LOCALHOST";
    case DiscoveryRange::kOff:
      return "OFF";
  }
  return "?";
}

DiscoveryPlan discovery_plan(const char* range, const char* static_peers, const char* localhost_only, bool secured) {
  DiscoveryPlan plan;
  const std::string r = range ? trim(range) : "";
  if (r.empty()) {
    if (localhost_only && std::string(localhost_only) == "1") {
      plan.range = DiscoveryRange::kLocalhost;
      plan.reason = "ROS_LOCALHOST_ONLY=1";
    } else if (secured) {
      plan.range = DiscoveryRange::kLocalhost;
      plan.reason =
          "secured: unicast discovery on this host (Fast DDS 2.9.1 can leave two secured participants that start "
          "together unauthenticated for good with multicast discovery; ROS_STATIC_PEERS adds other hosts)";
    }
  } else if (r == "SUBNET" || r == "SYSTEM_DEFAULT") {
    plan.range = DiscoveryRange::kSubnet;
    if (secured)
      plan.warning =
          "ROS_AUTOMATIC_DISCOVERY_RANGE=" + r +
          " under security: with multicast discovery, Fast DDS 2.9.1 can leave two participants that start together "
          "unauthenticated for good (eProsima/Fast-DDS PR #3362, fixed in 2.9.2); unset it for unicast discovery";
  } else if (r == "LOCALHOST") {
    plan.range = DiscoveryRange::kLocalhost;
    plan.reason = "ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST";
  } else if (r == "OFF") {
    plan.range = DiscoveryRange::kOff;
    plan.reason = "ROS_AUTOMATIC_DISCOVERY_RANGE=OFF";
  } else {
    throw ConfigError("environment ROS_AUTOMATIC_DISCOVERY_RANGE='" + r +
                      "': expected SUBNET, LOCALHOST, OFF or SYSTEM_DEFAULT");
  }
  const std::string peers = static_peers ? static_peers : "";
  std::size_t at = 0;
  while (at <= peers.size()) {
    const std::size_t end = std::min(peers.find(';', at), peers.size());
    const std::string p = trim(peers.substr(at, end - at));
    at = end + 1;
    if (p.empty()) continue;
    in_addr addr{};
    if (inet_pton(AF_INET, p.c_str(), &addr) != 1)
      throw ConfigError("environment ROS_STATIC_PEERS='" + peers + "': '" + p +
                        "' is not an IPv4 address (peers are IPv4 addresses separated by ';')");
    plan.static_peers.push_back(p);
  }
  return plan;
}

DiscoveryPlan discovery_plan_from_env(bool secured) {
  return discovery_plan(std::getenv("ROS_AUTOMATIC_DISCOVERY_RANGE"), std::getenv("ROS_STATIC_PEERS"),
                        std::getenv("ROS_LOCALHOST_ONLY"), secured);
}

}  // namespace unav
