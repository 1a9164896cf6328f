// A node that is SIGKILLed and started again (a launch respawn, a crashed tool run a second time)
// must be heard by, and hear, the processes that were talking to the one that died. The peer is
// this test binary run again as another process (the DISABLED_ test below, selected by filter);
// it gets the survivor's domain through UNAV_TEST_DOMAIN. Fast DDS 2.9's shared-memory transport
// fails this (context.cpp): the fault-injection system test saw the respawned renderer never
// rejoin lockstep in 3 of 7 runs with it.
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "std_msgs/msg/string.hpp"
#include "unav_runtime/runtime.hpp"
#include "unav_runtime/testing.hpp"

extern char** environ;  // NOLINT(readability-redundant-declaration): POSIX, for posix_spawn

using namespace std::chrono_literals;
using namespace unav;
using unav::testing::test_context_options;

namespace {

// Runs this binary's peer test as another process with the survivor's domain and `id`.
pid_t spawn_peer(int domain, int id) {
  std::vector<std::string> env_strings;
  for (char** e = environ; *e; ++e) {
    const std::string kv = *e;
    if (kv.rfind("UNAV_TEST_DOMAIN=", 0) != 0 && kv.rfind("UNAV_PEER_ID=", 0) != 0) env_strings.push_back(kv);
  }
  env_strings.push_back("UNAV_TEST_DOMAIN=" + std::to_string(domain));
  env_strings.push_back("UNAV_PEER_ID=" + std::to_string(id));
  std::vector<char*> envp;
  envp.reserve(env_strings.size() + 1);
  for (auto& s : env_strings) envp.push_back(s.data());
  envp.push_back(nullptr);
  std::string exe = "/proc/self/exe", filter = "--gtest_filter=PeerRestart.DISABLED_Peer",
              disabled = "--gtest_also_run_disabled_tests";
  std::vector<char*> argv{exe.data(), filter.data(), disabled.data(), nullptr};
  pid_t pid = -1;
  if (posix_spawn(&pid, exe.c_str(), nullptr, nullptr, argv.data(), envp.data()) != 0) return -1;
  return pid;
}

}  // namespace

// The peer: hears /restart/to_peer and says so on /restart/from_peer ("peer N", then
// "peer N heard"), 50 times a second, until it is killed (or 120 s pass).
TEST(PeerRestart, DISABLED_Peer) {
  const char* id = std::getenv("UNAV_PEER_ID");
  if (!id) GTEST_SKIP() << "run by PeerRestart.ANewPeerIsHeardAndHearsAfterOneWasKilled";
  Context ctx(test_context_options());
  Node node("peer", {&ctx}, "restart");
  auto pub = node.create_publisher<std_msgs::msg::String>("from_peer", QoS::reliable());
  bool heard = false;
  auto sub = node.create_subscription<std_msgs::msg::String>("to_peer", QoS::reliable(),
                                                             [&](const std_msgs::msg::String&) { heard = true; });
  std_msgs::msg::String msg;
  const auto end = std::chrono::steady_clock::now() + 120s;
  while (std::chrono::steady_clock::now() < end) {
    ctx.spin_some(20ms);
    msg.data(std::string("peer ") + id + (heard ? " heard" : ""));
    pub->publish(msg);
  }
}

// The survivor writes to the peer 100 times a second throughout (also while a killed peer is
// gone, as the physics server writes odometry to a dead renderer). Each of four peers in turn,
// started 0.5 s after the previous one was SIGKILLed (the launch's respawn delay), must hear it
// and be heard. The 30 s limit is discovery on a loaded 2-core machine (seconds), not a timing.
TEST(PeerRestart, ANewPeerIsHeardAndHearsAfterOneWasKilled) {
  Context ctx(test_context_options());
  Node node("survivor", {&ctx}, "restart");
  auto pub = node.create_publisher<std_msgs::msg::String>("to_peer", QoS::reliable());
  std::set<std::string> said;
  auto sub = node.create_subscription<std_msgs::msg::String>(
      "from_peer", QoS::reliable(), [&](const std_msgs::msg::String& m) { said.insert(m.data()); });
  std_msgs::msg::String msg;
  msg.data("survivor");
  const int domain = unav::testing::unique_domain_id();
  for (int id = 1; id <= 4; ++id) {
    const pid_t peer = spawn_peer(domain, id);
    ASSERT_GT(peer, 0) << "could not start peer " << id;
    const std::string heard = "peer " + std::to_string(id) + " heard";
    const auto end = std::chrono::steady_clock::now() + 30s;
    while (!said.count(heard) && std::chrono::steady_clock::now() < end) {
      ctx.spin_some(10ms);
      pub->publish(msg);
    }
    const bool spoke = said.count("peer " + std::to_string(id)) || said.count(heard);
    ::kill(peer, SIGKILL);
    ::waitpid(peer, nullptr, 0);
    ASSERT_TRUE(said.count(heard)) << "peer " << id
                                   << (spoke ? " was heard but never heard the survivor"
                                             : " and the survivor never heard each other")
                                   << " within 30 s (peers 1.." << id - 1 << " were SIGKILLed before it)";
    const auto resume = std::chrono::steady_clock::now() + 500ms;
    while (std::chrono::steady_clock::now() < resume) {
      ctx.spin_some(10ms);
      pub->publish(msg);
    }
  }
}
