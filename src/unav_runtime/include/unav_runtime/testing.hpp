// Test support for DDS tests (header-only; tests include it, the runtime library does not).
//
// The usual shape of a node test: the node under test in one Context, a probe node in another,
// both in this process on a DDS domain of the test process' own, spun alternately from the test
// thread:
//
//   unav::Context node_ctx(argc, argv, unav::testing::test_context_options());
//   MyNode node({&node_ctx});
//   unav::Context test_ctx(unav::testing::test_context_options());
//   unav::Node probe("probe", {&test_ctx});
//   auto in = probe.create_publisher<...>("/rov/in", unav::QoS::reliable());
//   auto out = probe.create_subscription<...>("/rov/out", unav::QoS::reliable(), ...);
//   const std::vector<unav::testing::Link> links = {unav::testing::make_link(*in, node),
//                                                     unav::testing::make_link(node, *out)};
//   ASSERT_TRUE(unav::testing::wait_for_match({&node_ctx, &test_ctx}, links)) << unav::testing::describe(links);
//   in->publish(...);
//
// Why both sides: discovery is not symmetric. A writer counts a matched reader when it has seen
// the reader's announcement, the reader counts the writer when it has seen the writer's; the two
// happen at different moments, further apart on a loaded machine. A sample written before the
// writer knows the reader is never sent to it (volatile durability): it is lost although the
// reader already counts the writer. (Written when only the writer knows the reader, it is
// repaired by the reliable protocol, ~0.15 s later, with Fast DDS 2.9.) Only when both counts are
// non-zero does every reliable sample reach its reader, at once.
#pragma once

#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/file.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <initializer_list>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>

#include "nav_msgs/msg/odometry.hpp"
#include "unav_runtime/context.hpp"
#include "unav_runtime/conversions.hpp"
#include "unav_runtime/node.hpp"
#include "unav_runtime/publisher.hpp"

namespace unav::testing {

/// Domains handed out by unique_domain_id(): [kFirstTestDomain, kFirstTestDomain + kTestDomainCount).
/// Chosen apart from every other domain in this repository (0: ROS default; 42, 43: demo and
/// vocabulary scripts; 50-229: the shell system tests) and low enough that Fast DDS' ports
/// (7400 + 250 * domain + ...) stay below Linux' ephemeral port range (32768 and up), where an
/// unrelated outgoing socket could hold a port a participant needs.
inline constexpr int kFirstTestDomain = 1;
inline constexpr int kTestDomainCount = 41;  // 1..41

/// A DDS domain id that no other process on this machine that uses this function holds: the
/// first free one of kTestDomainCount domains, each guarded by an exclusive, non-blocking
/// flock() on /tmp/unav_test_domain_<N>.lock, tried from an offset given by the pid (to spread)
/// onwards. The lock is held (the descriptor stays open) for the life of the process and is
/// inherited by forked children, so a child still using the domain keeps it reserved; the
/// kernel releases it when the last holder exits, crashed or not. The same id is returned on
/// every call. The environment variable UNAV_TEST_DOMAIN, if set, overrides the choice (no lock).
inline int unique_domain_id() {
  static const int id = [] {
    if (const char* env = std::getenv("UNAV_TEST_DOMAIN"); env && *env) {
      char* end = nullptr;
      const long v = std::strtol(env, &end, 10);
      if (*end != '\0' || v < 0 || v > 232)
        throw std::runtime_error(std::string("UNAV_TEST_DOMAIN='") + env + "': expected an integer in [0, 232]");
      return static_cast<int>(v);
    }
    const int start = static_cast<int>(::getpid() % kTestDomainCount);
    for (int i = 0; i < kTestDomainCount; ++i) {
      const int domain = kFirstTestDomain + (start + i) % kTestDomainCount;
      const std::string path = "/tmp/unav_test_domain_" + std::to_string(domain) + ".lock";
      int fd = ::open(path.c_str(), O_RDWR | O_CREAT, 0666);
      if (fd < 0) fd = ::open(path.c_str(), O_RDONLY);  // created by another user: flock works read-only
      if (fd < 0) continue;
      if (::flock(fd, LOCK_EX | LOCK_NB) == 0) return domain;  // fd deliberately kept open: holds the lock
      ::close(fd);
    }
    const int fallback = kFirstTestDomain + start;
    std::fprintf(stderr, "unav::testing: all %d test domains are locked; sharing domain %d\n", kTestDomainCount,
                 fallback);
    return fallback;
  }();
  return id;
}

/// Options for every Context of a test: the process' own domain, no signal handling (gtest and
/// ctest own the signals).
inline ContextOptions test_context_options() {
  ContextOptions o;
  o.domain_id = unique_domain_id();
  o.handle_signals = false;
  return o;
}

/// Spins every context in turn (up to 1 ms each) until `done` holds or `timeout` passes; returns
/// done(). With a node and a probe in one thread, both must be spun for either to progress.
inline bool spin_until(std::initializer_list<Context*> contexts, const std::function<bool()>& done,
                       std::chrono::milliseconds timeout = std::chrono::seconds(20)) {
  const auto end = std::chrono::steady_clock::now() + timeout;
  while (!done()) {
    if (std::chrono::steady_clock::now() >= end) return done();
    for (Context* c : contexts) c->spin_some(std::chrono::milliseconds(1));
  }
  return true;
}

/// Spins every context in turn for `duration` (lets callbacks run, e.g. to show nothing happens).
inline void spin_for(std::initializer_list<Context*> contexts, std::chrono::milliseconds duration) {
  spin_until(
      contexts, [] { return false; }, duration);
}

/// A writer and a reader on the same topic that a test needs connected.
struct Link {
  const PublisherBase* pub = nullptr;
  const SubscriptionBase* sub = nullptr;
};

/// The node's publisher on the DDS topic `dds_topic` (topic_name(), e.g. "rt/rov/ground_truth/odom").
/// Throws std::logic_error if the node has none (a test naming the wrong topic).
inline const PublisherBase& publisher_of(const Node& node, const std::string& dds_topic) {
  for (const PublisherBase* p : node.publishers())
    if (p->topic_name() == dds_topic) return *p;
  throw std::logic_error("node '" + node.name() + "' has no publisher on '" + dds_topic + "'");
}

/// The node's subscription on the DDS topic `dds_topic`; throws std::logic_error if none.
inline const SubscriptionBase& subscription_of(const Node& node, const std::string& dds_topic) {
  for (const SubscriptionBase* s : node.subscriptions())
    if (s->topic_name() == dds_topic) return *s;
  throw std::logic_error("node '" + node.name() + "' has no subscription on '" + dds_topic + "'");
}

/// Odometry stamped t [s] (whole nanoseconds) at p_W (world_ned), level unless told: a test's
/// stand-in for the physics server's ground truth.
inline nav_msgs::msg::Odometry odometry_at(double t, const Eigen::Vector3d& p_W,
                                           const Eigen::Quaterniond& q = Eigen::Quaterniond::Identity()) {
  nav_msgs::msg::Odometry o;
  o.header(make_header(t, "world_ned"));
  o.child_frame_id("base_link_frd");
  o.pose().pose(to_msg(p_W, q));
  return o;
}

inline Link make_link(const PublisherBase& pub, const SubscriptionBase& sub) { return {&pub, &sub}; }
/// `pub` (the probe's) to the node's subscription on the same topic.
inline Link make_link(const PublisherBase& pub, const Node& reader) {
  return {&pub, &subscription_of(reader, pub.topic_name())};
}
/// The node's publisher on the topic of `sub` (the probe's) to `sub`.
inline Link make_link(const Node& writer, const SubscriptionBase& sub) {
  return {&publisher_of(writer, sub.topic_name()), &sub};
}

/// Both sides matched: the writer has a matched subscription and the reader a matched publisher.
inline bool matched(const Link& l) { return l.pub->subscription_count() > 0 && l.sub->publisher_count() > 0; }

inline bool all_matched(const std::vector<Link>& links) {
  for (const Link& l : links)
    if (!matched(l)) return false;
  return true;
}

/// Spins `contexts` until every link is matched on both sides (see the top of this file).
inline bool wait_for_match(std::initializer_list<Context*> contexts, const std::vector<Link>& links,
                           std::chrono::milliseconds timeout = std::chrono::seconds(20)) {
  return spin_until(
      contexts, [&] { return all_matched(links); }, timeout);
}

/// Everything `l.pub` wrote was acknowledged by the readers it matched, and `l.sub` holds no sample
/// its owner has not taken yet (its callback ran).
inline bool delivered(const Link& l) {
  return l.pub->writer()->wait_for_acknowledgments(eprosima::fastrtps::Duration_t(0, 0)) == ReturnCode_t::RETCODE_OK &&
         l.sub->reader()->get_unread_count() == 0;
}

/// Spins `contexts` until every link delivered() what was written so far: instead of a fixed wait
/// before checking what a node received (or before destroying it), which a loaded machine outlasts.
inline bool wait_for_delivery(std::initializer_list<Context*> contexts, const std::vector<Link>& links,
                              std::chrono::milliseconds timeout = std::chrono::seconds(20)) {
  return spin_until(
      contexts,
      [&] {
        for (const Link& l : links)
          if (!delivered(l)) return false;
        return true;
      },
      timeout);
}

/// One line per link with both counts, for the failure message of wait_for_match.
inline std::string describe(const std::vector<Link>& links) {
  std::string s;
  for (const Link& l : links)
    s += l.pub->topic_name() + ": writer sees " + std::to_string(l.pub->subscription_count()) +
         " reader(s), reader sees " + std::to_string(l.sub->publisher_count()) + " writer(s)\n";
  return s;
}

/// The node test pattern: the node under test on a participant of its own, started with `args`
/// as on its command line (`{"--ros-args", "-p", "x:=1"}`), and a probe node on another, both in
/// the test's domain (or `options`') and spun together from the test's thread:
///   NodeUnderTest<StationKeeperNode> t("station_keeper", {"--ros-args", "-r", "__ns:=/rov2"});
///   auto pub = t.probe.create_publisher<...>(...);
///   ASSERT_TRUE(t.match({make_link(*pub, *t.node)}));
///   ASSERT_TRUE(t.spin_until([&] { return got; }));
///   t.node.reset();  // a node's shutdown (e.g. what it writes on exit), while the probe lives on
template <class NodeT>
class NodeUnderTest {
 public:
  NodeUnderTest(const std::string& executable, std::vector<std::string> args,
                const ContextOptions& options = test_context_options())
      : args_(with_executable(executable, std::move(args))),
        argv_(pointers(args_)),
        node_ctx(static_cast<int>(argv_.size()), argv_.data(), options),
        node(std::make_unique<NodeT>(NodeOptions{&node_ctx})),
        test_ctx(options),
        probe("probe", {&test_ctx}) {}

  /// Both sides of every link matched (see wait_for_match); the failure says which are not.
  ::testing::AssertionResult match(const std::vector<Link>& links) {
    if (wait_for_match({&node_ctx, &test_ctx}, links)) return ::testing::AssertionSuccess();
    return ::testing::AssertionFailure() << describe(links);
  }
  bool spin_until(const std::function<bool()>& done, std::chrono::milliseconds timeout = std::chrono::seconds(20)) {
    return testing::spin_until({&node_ctx, &test_ctx}, done, timeout);
  }
  void spin_for(std::chrono::milliseconds duration) { testing::spin_for({&node_ctx, &test_ctx}, duration); }

 private:
  static std::vector<std::string> with_executable(const std::string& exe, std::vector<std::string> args) {
    args.insert(args.begin(), exe);
    return args;
  }
  static std::vector<const char*> pointers(const std::vector<std::string>& args) {
    std::vector<const char*> p;
    p.reserve(args.size());
    for (const auto& a : args) p.push_back(a.c_str());
    return p;
  }
  std::vector<std::string> args_;
  std::vector<const char*> argv_;

 public:
  Context node_ctx;
  std::unique_ptr<NodeT> node;
  Context test_ctx;
  Node probe;
};

/// What a subscriber that joins after the node under test started receives on a latched topic
/// (transient local: /tf_static, /robot_description): the first message, from a probe in a
/// context of its own, spinning both; nullopt after `timeout`.
template <typename Msg>
std::optional<Msg> late_latched(Context& node_ctx, const std::string& topic,
                                std::chrono::milliseconds timeout = std::chrono::seconds(30)) {
  ContextOptions o = test_context_options();
  o.domain_id = node_ctx.domain_id();  // the node's domain, whatever it was given
  Context test_ctx(o);
  Node probe("late_probe", {&test_ctx});
  std::optional<Msg> got;
  auto sub = probe.create_subscription<Msg>(topic, QoS::static_latched(), [&](const Msg& m) {
    if (!got) got = m;
  });
  spin_until(
      {&node_ctx, &test_ctx}, [&] { return got.has_value(); }, timeout);
  return got;
}

}  // namespace unav::testing
