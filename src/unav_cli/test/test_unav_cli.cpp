// The unav CLI against live DDS traffic from this test process (domain of its own).
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <future>

#include "unav_msgs/msg/thruster_command.hpp"
#include "unav_runtime/runtime.hpp"
#include "unav_runtime/testing.hpp"

using namespace std::chrono_literals;

namespace {

struct Result {
  int code = -1;
  std::string out;
  std::string err;
};

// Runs `unav ARGS` with this test's domain; stdout and stderr captured separately.
Result run_unav(const std::string& args, const std::string& spin_time = "1.5") {
  const std::string err_file = ::testing::TempDir() + "unav_err_" + std::to_string(getpid());
  const std::string cmd = "ROS_DOMAIN_ID=" + std::to_string(unav::testing::unique_domain_id()) +
                          " UNAV_SPIN_TIME=" + spin_time + " timeout -s INT 30 " + UNAV_EXE + " " + args + " 2>" + err_file;
  Result r;
  FILE* p = popen(cmd.c_str(), "r");
  std::array<char, 4096> buf;
  size_t n;
  while ((n = fread(buf.data(), 1, buf.size(), p)) > 0) r.out.append(buf.data(), n);
  const int status = pclose(p);
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  std::ifstream in(err_file);
  r.err.assign(std::istreambuf_iterator<char>(in), {});
  return r;
}

// Runs `unav` in the background while spinning `ctx`, so this process keeps answering DDS.
Result run_unav_while_spinning(unav::Context& ctx, const std::string& args, const std::string& spin_time = "1.5") {
  auto fut = std::async(std::launch::async, [&] { return run_unav(args, spin_time); });
  while (fut.wait_for(10ms) != std::future_status::ready) ctx.spin_some(5ms);
  return fut.get();
}

class CliTest : public ::testing::Test {
 protected:
  CliTest() {
    ctx_ = std::make_unique<unav::Context>(unav::testing::test_context_options());
    node_ = std::make_unique<unav::Node>("talker", unav::NodeOptions{ctx_.get()}, "cli_test");
    pub_ = node_->create_publisher<unav_msgs::msg::ThrusterCommand>("cmd", unav::QoS::reliable());
    timer_ = node_->create_wall_timer(50ms, [this] {
      unav_msgs::msg::ThrusterCommand c;
      c.header().frame_id("base_link_frd");
      c.u({0.5, -1.0});
      pub_->publish(c);
    });
  }
  ~CliTest() override {
    timer_.reset();
    pub_.reset();
    node_.reset();
    ctx_.reset();
  }
  std::unique_ptr<unav::Context> ctx_;
  std::unique_ptr<unav::Node> node_;
  std::shared_ptr<unav::Publisher<unav_msgs::msg::ThrusterCommand>> pub_;
  std::shared_ptr<unav::Timer> timer_;
};

}  // namespace

TEST_F(CliTest, TopicListShowsRos2TypeNames) {
  const Result r = run_unav_while_spinning(*ctx_, "topic list -t");
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("/cli_test/cmd [unav_msgs/msg/ThrusterCommand]"), std::string::npos) << r.out;
}

TEST_F(CliTest, EchoOncePrintsYamlLikeRos2) {
  const Result r = run_unav_while_spinning(*ctx_, "topic echo /cli_test/cmd --once");
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("  frame_id: base_link_frd\nu:\n- 0.5\n- -1.0\n---\n"), std::string::npos) << r.out;
}

TEST_F(CliTest, PubOnceIsReceived) {
  std::vector<double> got;
  auto sub = node_->create_subscription<unav_msgs::msg::ThrusterCommand>(
      "/cli_test/in", unav::QoS::reliable(), [&](const unav_msgs::msg::ThrusterCommand& m) { got = m.u(); });
  // `topic pub --once` waits (up to the spin time) until its writer matched this reader, then
  // waits for the reliable acknowledgement: a generous spin time only bounds the wait for
  // discovery on a loaded machine; it costs nothing when discovery is quick.
  const Result r = run_unav_while_spinning(
      *ctx_, "topic pub /cli_test/in unav_msgs/msg/ThrusterCommand '{u: [0.25, 1]}' --once", "15");
  EXPECT_EQ(r.code, 0) << r.err;
  ctx_->spin_until([&] { return !got.empty(); }, 5s);
  EXPECT_EQ(got, (std::vector<double>{0.25, 1.0}));
}

TEST_F(CliTest, NodeListShowsNodes) {
  const Result r = run_unav_while_spinning(*ctx_, "node list", "3");  // latched graph data: discovery + a heartbeat
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("/cli_test/talker\n"), std::string::npos) << "out: " << r.out << " err: " << r.err;
}

TEST(CliErrors, BadInputGivesOneLineAndExit2) {
  const std::string launch = ::testing::TempDir() + "bad_exec.launch.yaml";
  std::ofstream(launch) << "launch:\n  - node: {pkg: unav_cli_no_such_pkg, exec: nothing}\n";
  struct Case {
    std::string args;
    std::string must_mention;
  };
  const std::vector<Case> cases = {
      {"topic pub /x foo_msgs/msg/Nope '{}' --once", "foo_msgs/msg/Nope"},
      {"topic pub /x unav_msgs/msg/ThrusterCommand '{u: [1, 2' --once", "malformed YAML"},
      {"topic pub /x unav_msgs/msg/ThrusterCommand '{v: 1}' --once", "v"},
      {"launch /no/such/file.launch.yaml", "/no/such/file.launch.yaml"},
      {"launch " + launch, "unav_cli_no_such_pkg"},
  };
  for (const auto& c : cases) {
    const Result r = run_unav(c.args);
    EXPECT_EQ(r.code, 2) << c.args << "\n" << r.err;
    EXPECT_NE(r.err.find(c.must_mention), std::string::npos) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  }
}

TEST(CliEval, ApeAndRpeOnTumFiles) {
  // Reference: a circle of radius 2 m at 10 Hz; estimate: the same path scaled by 0.5 and
  // shifted (a monocular result), so Sim(3)-aligned APE is ~0 and unaligned APE is not.
  const std::string ref = ::testing::TempDir() + "ref.tum", est = ::testing::TempDir() + "est.tum";
  std::ofstream r(ref), e(est);
  r.precision(12);
  e.precision(12);
  for (int i = 0; i < 100; ++i) {
    const double a = 0.06 * i, x = 2 * std::cos(a), y = 2 * std::sin(a);
    r << 10 + 0.1 * i << " " << x << " " << y << " 0 0 0 0 1\n";
    e << 10 + 0.1 * i + 0.002 << " " << 0.5 * x + 3 << " " << 0.5 * y << " 1 0 0 0 1\n";
  }
  r.close();
  e.close();
  const Result aligned = run_unav("eval ape " + ref + " " + est);
  EXPECT_EQ(aligned.code, 0) << aligned.err;
  EXPECT_NE(aligned.out.find("(with Sim(3) Umeyama alignment)"), std::string::npos) << aligned.out;
  EXPECT_NE(aligned.out.find("      rmse\t0.000000"), std::string::npos) << aligned.out;
  const Result raw = run_unav("eval ape " + ref + " " + est + " --align none");
  EXPECT_EQ(raw.code, 0) << raw.err;
  EXPECT_EQ(raw.out.find("      rmse\t0.000000"), std::string::npos) << raw.out;
  const Result rpe = run_unav("eval rpe " + ref + " " + est + " --delta 1 --delta_unit m");
  EXPECT_EQ(rpe.code, 0) << rpe.err;
  EXPECT_NE(rpe.out.find("RPE w.r.t. translation part (m) for delta = 1 (m)"), std::string::npos) << rpe.out;
  const std::string bad = ::testing::TempDir() + "bad.tum";
  std::ofstream(bad) << "1 0 0 0 0 0 0 1\n2 0 0 0\n";
  const Result err = run_unav("eval ape " + ref + " " + bad);
  EXPECT_EQ(err.code, 2);
  EXPECT_NE(err.err.find("bad.tum:2: expected 8 columns"), std::string::npos) << err.err;
}
