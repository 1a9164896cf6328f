// The talker and listener executables over DDS, and their start-up errors.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fstream>
#include <sstream>

#include "std_msgs/msg/string.hpp"
#include "unav_runtime/runtime.hpp"
#include "unav_runtime/testing.hpp"

using namespace std::chrono_literals;

namespace {

struct Child {
  pid_t pid = -1;
  std::string err_path;
};

Child spawn(const std::vector<std::string>& argv) {
  Child c;
  c.err_path = ::testing::TempDir() + "child_" + std::to_string(getpid()) + "_" + std::to_string(rand()) + ".err";
  // Chosen (and locked) by this process before the fork: the children inherit the lock with the
  // descriptor, so the domain stays reserved as long as any of them runs.
  const std::string domain_id = std::to_string(unav::testing::unique_domain_id());
  c.pid = fork();
  if (c.pid == 0) {
    setenv("ROS_DOMAIN_ID", domain_id.c_str(), 1);
    FILE* f = freopen(c.err_path.c_str(), "w", stderr);
    (void)f;
    std::vector<char*> args;
    args.reserve(argv.size() + 1);
    for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    execv(args[0], args.data());
    _exit(127);
  }
  return c;
}

int wait_exit(const Child& c, std::chrono::seconds timeout) {
  const auto end = std::chrono::steady_clock::now() + timeout;
  int status = 0;
  while (std::chrono::steady_clock::now() < end) {
    if (waitpid(c.pid, &status, WNOHANG) == c.pid)
      return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    std::this_thread::sleep_for(20ms);
  }
  kill(c.pid, SIGKILL);
  waitpid(c.pid, &status, 0);
  return -1;
}

std::string read_file(const std::string& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

}  // namespace

TEST(ExampleNodes, TalkerPublishesOverDdsAndStopsOnSigint) {
  Child talker =
      spawn({TALKER_EXE, "--ros-args", "--params-file", TALKER_PARAMS, "-p", "rate:=20.0", "-r", "__ns:=/rov"});
  unav::Context ctx(unav::testing::test_context_options());
  unav::Node probe("probe", {&ctx});
  std::vector<std::string> got;
  auto sub = probe.create_subscription<std_msgs::msg::String>(
      "/rov/chatter", unav::QoS::reliable(), [&](const std_msgs::msg::String& m) { got.push_back(m.data()); });
  // The talker publishes continuously: whatever is sent before both sides matched is simply not
  // counted, so the test needs no matching wait.
  ASSERT_TRUE(ctx.spin_until([&] { return got.size() >= 5; }, 20s)) << read_file(talker.err_path);
  // The params file sets the message text; -p overrides its rate.
  EXPECT_EQ(got[0].rfind("Hello from UNav-Sim: ", 0), 0u) << got[0];
  kill(talker.pid, SIGINT);
  EXPECT_EQ(wait_exit(talker, 10s), 0) << "talker must exit cleanly on SIGINT";
}

TEST(ExampleNodes, ListenerReceivesFromTalkerProcess) {
  Child talker = spawn({TALKER_EXE, "--ros-args", "-p", "rate:=20.0"});
  Child listener = spawn({LISTENER_EXE, "--ros-args", "-p", "exit_after:=3"});
  EXPECT_EQ(wait_exit(listener, 20s), 0) << read_file(listener.err_path);
  EXPECT_NE(read_file(listener.err_path).find("I heard: 'Hello World: "), std::string::npos);
  kill(talker.pid, SIGTERM);
  EXPECT_EQ(wait_exit(talker, 10s), 0);
}

TEST(ExampleNodes, BadParametersGiveOneLineErrorAndExit2) {
  struct Case {
    std::vector<std::string> args;
    std::string must_mention;
  };
  const std::string typo = ::testing::TempDir() + "typo.yaml";
  std::ofstream(typo) << "talker:\n  ros__parameters:\n    rat: 5.0\n";
  const std::vector<Case> cases = {
      {{TALKER_EXE, "--ros-args", "-p", "rate:=fast"}, "rate = fast: must be a number"},
      {{TALKER_EXE, "--ros-args", "-p", "rate:=-1"}, "rate = -1: must be in [0.001, 1000]"},
      {{TALKER_EXE, "--ros-args", "--params-file", "/no/such/file.yaml"}, "/no/such/file.yaml"},
      {{TALKER_EXE, "--ros-args", "--params-file", typo}, "'rat'"},
      {{TALKER_EXE, "--ros-args", "--bogus"}, "--bogus"},
      {{TALKER_EXE, "--ros-args", "-r", "__node:=bad/name"}, "bad/name"},
  };
  for (const auto& c : cases) {
    Child child = spawn(c.args);
    EXPECT_EQ(wait_exit(child, 20s), 2) << c.must_mention;
    const std::string err = read_file(child.err_path);
    EXPECT_NE(err.find(c.must_mention), std::string::npos) << err;
    EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << "one line expected: " << err;
  }
}
