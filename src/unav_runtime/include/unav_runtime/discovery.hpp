// How a participant finds its peers: ROS 2's switches (Iron and later), read from the environment.
//   ROS_AUTOMATIC_DISCOVERY_RANGE = SUBNET | LOCALHOST | OFF | SYSTEM_DEFAULT
//   ROS_STATIC_PEERS             = IPv4 addresses separated by ';' (always contacted, any range)
//   ROS_LOCALHOST_ONLY=1         = the older switch (Humble): LOCALHOST
// SUBNET is multicast discovery (Fast DDS' default). LOCALHOST is unicast discovery: announcements
// go to the discovery ports of the first `localhost_participants` participants on 127.0.0.1 (and
// to the static peers), nothing is sent or heard by multicast. OFF: the static peers only.
//
// Secured participants default to LOCALHOST: Fast DDS 2.9.1 (Debian 12) authenticates two new
// participants at once with shared, unlocked temporaries in its SecurityManager
// (match_builtin_endpoints), and discovery arrives on two receive threads with multicast (the
// multicast and unicast sockets), so a pair started together can be left half-matched, never to
// authenticate (eProsima/Fast-DDS PR #3362, fixed in 2.9.2 and 2.10.0). With unicast discovery one
// thread receives every announcement and the race cannot happen. An explicit
// ROS_AUTOMATIC_DISCOVERY_RANGE=SUBNET keeps multicast under security (with a warning).
#pragma once

#include <string>
#include <vector>

namespace unav {

enum class DiscoveryRange { kSubnet, kLocalhost, kOff };

struct DiscoveryPlan {
  DiscoveryRange range = DiscoveryRange::kSubnet;
  /// IPv4 addresses contacted whatever the range.
  std::vector<std::string> static_peers;
  /// Why the range is what it is (said in the log when it is not the plain default).
  std::string reason;
  /// A warning to log (e.g. multicast discovery under security on Fast DDS 2.9).
  std::string warning;
  /// Unicast discovery contacts the ports of this many participants per address (Fast DDS'
  /// maxInitialPeersRange): a launch's nodes, its tools and a margin.
  unsigned localhost_participants = 32;
};

/// The plan from ROS_AUTOMATIC_DISCOVERY_RANGE, ROS_STATIC_PEERS and ROS_LOCALHOST_ONLY (the
/// values as given; nullptr = unset), for a secured participant or not. Throws ConfigError naming
/// the variable, its value and what is allowed.
DiscoveryPlan discovery_plan(const char* range, const char* static_peers, const char* localhost_only, bool secured);
/// The same from the process environment.
DiscoveryPlan discovery_plan_from_env(bool secured);
const char* to_string(DiscoveryRange range);

}  // namespace unav
