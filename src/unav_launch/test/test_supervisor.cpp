#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>

#include "fake_prefix.hpp"
#include "unav_launch/launch_description.hpp"
#include "unav_launch/supervisor.hpp"

namespace unav::launch::test {
namespace {

using Clock = std::chrono::steady_clock;

// Loops until stopped; `trap` chooses how it reacts to signals. Writes its pid to DIR/<name>.pid
// once the trap is set (tests signal it as soon as the pid file appears: with the trap after it,
// a loaded machine let SIGINT arrive first and kill a child meant to ignore it).
std::string looping(const std::string& name, const std::string& trap) {
  return trap + "\necho $$ > \"$DIR/" + name + ".pid.tmp\"; mv \"$DIR/" + name + ".pid.tmp\" \"$DIR/" + name +
         ".pid\"\nwhile true; do sleep 0.02; done";
}

class SupervisorTest : public FakePrefix {
 protected:
  NodeDescription node(const std::string& exec, const std::string& body) {
    NodeDescription node;
    node.package = "fakepkg";
    node.executable = exec;
    node.executable_path = script(exec, body);
    return node;
  }

  int run_nodes(const std::vector<NodeDescription>& nodes, double grace_s = 1.0) {
    LaunchDescription description;
    description.nodes = nodes;
    SupervisorOptions options;
    options.sigint_grace_s = grace_s;
    options.sigterm_grace_s = grace_s;
    options.out = &output_;
    const auto start = Clock::now();
    const int code = run(description, options);
    elapsed_s_ = std::chrono::duration<double>(Clock::now() - start).count();
    return code;
  }

  // Waits (up to 3 s) for DIR/<name>.pid and returns the pid in it.
  pid_t wait_pid(const std::string& name) {
    for (int i = 0; i < 300; ++i) {
      std::ifstream file(root_ + "/" + name + ".pid");
      pid_t pid = 0;
      if (file >> pid) {
        return pid;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    return -1;
  }

  // SIGINT to this process (the supervisor) once every named node has written its pid.
  std::thread interrupt_when_started(const std::vector<std::string>& names) {
    return std::thread([this, names] {
      for (const auto& name : names) {
        wait_pid(name);
      }
      ::kill(::getpid(), SIGINT);
    });
  }

  static bool alive(pid_t pid) { return pid > 0 && ::kill(pid, 0) == 0; }

  bool contains(const std::string& text) const { return output_.str().find(text) != std::string::npos; }

  std::ostringstream output_;
  double elapsed_s_ = 0.0;
};

TEST_F(SupervisorTest, PrintsWholeLinesWithPrefixAndReturnsZero) {
  const int code = run_nodes({
      node("alpha", "echo hello from alpha\nprintf 'abc'; sleep 0.1; printf 'def\\n'\nprintf 'no newline'"),
      node("beta", "echo oops from beta >&2\necho \"FOO=$FOO\""),
  });
  EXPECT_EQ(code, 0);
  EXPECT_TRUE(contains("[alpha-1] hello from alpha\n")) << output_.str();
  EXPECT_TRUE(contains("[alpha-1] abcdef\n")) << output_.str();
  EXPECT_TRUE(contains("[alpha-1] no newline\n")) << output_.str();
  EXPECT_TRUE(contains("[beta-2] oops from beta\n")) << output_.str();
  EXPECT_TRUE(contains("[INFO] [alpha-1]: process started with pid [")) << output_.str();
  EXPECT_TRUE(contains("[INFO] [beta-2]: process has finished cleanly [pid ")) << output_.str();
}

TEST_F(SupervisorTest, PassesEnvironmentAndArgv) {
  NodeDescription talker = node("talker", "echo \"FOO=$FOO argv=$*\"");
  talker.env = {{"FOO", "bar"}};
  talker.args = {"--x"};
  talker.name = "t";
  EXPECT_EQ(run_nodes({talker}), 0);
  EXPECT_TRUE(contains("[talker-1] FOO=bar argv=--x --ros-args -r __node:=t\n")) << output_.str();
}

TEST_F(SupervisorTest, FailedNodeMakesResultOneAndIsLogged) {
  const NodeDescription failing = node("failing", "exit 2");
  EXPECT_EQ(run_nodes({failing, node("fine", "exit 0")}), 1);
  EXPECT_TRUE(contains("[ERROR] [failing-1]: process has died [pid ")) << output_.str();
  EXPECT_TRUE(contains(", exit code 2, cmd '" + failing.executable_path + "']")) << output_.str();
}

TEST_F(SupervisorTest, RequiredExitStopsSiblingsQuickly) {
  NodeDescription required = node("boss", "sleep 0.2; exit 3");
  required.required = true;
  const NodeDescription sibling = node("worker", looping("worker", "trap 'echo worker stopping; exit 0' INT"));
  EXPECT_EQ(run_nodes({required, sibling}, 3.0), 3);
  EXPECT_LT(elapsed_s_, 1.5);  // SIGINT is honoured well before the 3 s grace period
  EXPECT_TRUE(contains("required process [boss-1] has exited, shutting down")) << output_.str();
  EXPECT_TRUE(contains("[worker-2] worker stopping")) << output_.str();
  EXPECT_FALSE(alive(wait_pid("worker")));
}

TEST_F(SupervisorTest, RespawnRestartsNodeUntilRequiredNodeEnds) {
  NodeDescription flaky = node("flaky", "echo start >> \"$DIR/starts\"; exit 4");
  flaky.respawn = true;
  flaky.respawn_delay_s = 0.05;
  // Ends once flaky has started three times: the required watcher exits 0, so the launch does.
  NodeDescription watcher =
      node("watcher", "while [ \"$(cat \"$DIR/starts\" 2>/dev/null | wc -l)\" -lt 3 ]; do sleep 0.02; done");
  watcher.required = true;
  EXPECT_EQ(run_nodes({flaky, watcher}), 0);
  std::ifstream starts(root_ + "/starts");
  int count = 0;
  for (std::string line; std::getline(starts, line);) ++count;
  EXPECT_GE(count, 3);
  EXPECT_LT(elapsed_s_, 3.0);
}

TEST_F(SupervisorTest, SigintStopsChildrenThatTrapIt) {
  std::thread interrupter = interrupt_when_started({"a", "b"});
  const int code = run_nodes(
      {node("a", looping("a", "trap 'echo a got SIGINT; exit 0' INT")), node("b", looping("b", "trap 'exit 5' INT"))},
      3.0);
  interrupter.join();
  EXPECT_EQ(code, 128 + SIGINT);
  EXPECT_LT(elapsed_s_, 2.0);
  EXPECT_TRUE(contains("[INFO] [launch]: caught SIGINT, shutting down")) << output_.str();
  EXPECT_TRUE(contains("[a-1] a got SIGINT")) << output_.str();
  EXPECT_FALSE(contains("SIGTERM")) << output_.str();
  EXPECT_FALSE(alive(wait_pid("a")));
  EXPECT_FALSE(alive(wait_pid("b")));
}

TEST_F(SupervisorTest, ChildIgnoringSignalsIsKilledAfterGracePeriods) {
  std::thread interrupter = interrupt_when_started({"stubborn"});
  const int code = run_nodes({node("stubborn", looping("stubborn", "trap '' INT TERM"))}, 0.2);
  interrupter.join();
  EXPECT_EQ(code, 128 + SIGINT);
  EXPECT_GE(elapsed_s_, 0.4);  // both grace periods were waited for
  EXPECT_LT(elapsed_s_, 2.0);
  EXPECT_TRUE(contains("escalating to SIGTERM")) << output_.str();
  EXPECT_TRUE(contains("escalating to SIGKILL")) << output_.str();
  EXPECT_TRUE(contains("exit code -9")) << output_.str();
  EXPECT_FALSE(alive(wait_pid("stubborn")));
}

TEST_F(SupervisorTest, NodesDieWithAKilledLauncher) {
  // Orphans are re-parented to this test process, so it can see them die (and reap them).
  ASSERT_EQ(::prctl(PR_SET_CHILD_SUBREAPER, 1), 0);
  const NodeDescription orphan = node("orphan", looping("orphan", ""));
  const pid_t launcher = ::fork();
  ASSERT_GE(launcher, 0);
  if (launcher == 0) {
    std::ostringstream sink;
    LaunchDescription description;
    description.nodes = {orphan};
    SupervisorOptions options;
    options.out = &sink;
    ::_exit(run(description, options));
  }
  const pid_t node_pid = wait_pid("orphan");
  ASSERT_GT(node_pid, 0);
  ::kill(launcher, SIGKILL);
  ASSERT_EQ(::waitpid(launcher, nullptr, 0), launcher);
  bool reaped = false;
  for (int i = 0; i < 200 && !reaped; ++i) {  // PR_SET_PDEATHSIG delivers SIGTERM at once
    reaped = ::waitpid(node_pid, nullptr, WNOHANG) == node_pid;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  EXPECT_TRUE(reaped);
  while (::waitpid(-1, nullptr, WNOHANG) > 0) {
  }
}

// The resource table at the end: each process's CPU (user + system) against its time alive.
// A shell counting to 300000 spends ~0.3-1 s of CPU whatever the load (fixed work; 0.05 s is far
// below it); a sleeping one spends a few ms (0.05 s is far above that).
TEST_F(SupervisorTest, ReportsEachProcesssCpuAgainstItsTimeAlive) {
  EXPECT_EQ(
      run_nodes({node("burner", "i=0; while [ $i -lt 300000 ]; do i=$((i+1)); done"), node("sleeper", "sleep 0.3")}),
      0);
  const std::string out = output_.str();
  ASSERT_TRUE(contains("[INFO] [launch]: resource use: ")) << out;
  auto cpu_of = [&](const std::string& label) {
    const std::size_t row = out.find("\n  " + label + " ");  // labels are padded to one width
    const std::size_t at = row == std::string::npos ? row : out.find(" cpu ", row);
    EXPECT_NE(at, std::string::npos) << out;
    return at == std::string::npos ? -1.0 : std::stod(out.substr(at + 5));
  };
  EXPECT_GT(cpu_of("burner-1"), 0.05) << out;
  EXPECT_GE(cpu_of("sleeper-2"), 0.0) << out;
  EXPECT_LT(cpu_of("sleeper-2"), 0.05) << out;
  EXPECT_TRUE(contains("% busy, max RSS")) << out;
}

TEST_F(SupervisorTest, EmptyDescriptionReturnsZero) { EXPECT_EQ(run_nodes({}), 0); }

}  // namespace
}  // namespace unav::launch::test
