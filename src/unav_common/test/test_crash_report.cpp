// The crash report: a process that faults prints its native stack and still dies of the same
// signal (the handler before it runs after it: here gtest's death-test child gets the default
// action, so the exit is "killed by SIGSEGV" as without the report).
#include <gtest/gtest.h>

#include <csignal>
#include <cstdlib>

#include "unav_common/crash_report.hpp"

namespace {

// Not inlined, so it is a frame of its own in the stack the report prints.
[[gnu::noinline]] void Fault() {
  volatile int* volatile p = nullptr;
  *p = 42;
}

}  // namespace

TEST(CrashReportDeathTest, AFaultPrintsTheStackAndStillKillsWithTheSameSignal) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  EXPECT_EXIT(
      {
        unav::common::InstallCrashReport("crash_test");
        Fault();
      },
      testing::KilledBySignal(SIGSEGV),
      "crash_test: fatal signal SIGSEGV at address 0x0 in thread [0-9]+ \\(pid [0-9]+\\); native stack of that "
      "thread:\n(.*\n)+\\(end of native stack\\)");
}

TEST(CrashReportDeathTest, AbortIsReportedAndStillAborts) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  EXPECT_EXIT(
      {
        unav::common::InstallCrashReport("abort_test");
        std::abort();
      },
      testing::KilledBySignal(SIGABRT), "abort_test: fatal signal SIGABRT in thread [0-9]+");
}

TEST(CrashReportDeathTest, ARenamedProgramIsReportedOnce) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  EXPECT_EXIT(
      {
        unav::common::InstallCrashReport("first");
        unav::common::InstallCrashReport("second");
        std::raise(SIGBUS);
      },
      testing::KilledBySignal(SIGBUS), "second: fatal signal SIGBUS");
}
