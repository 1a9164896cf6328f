#include "unav_common/crash_report.hpp"

#include <execinfo.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <atomic>
#include <csignal>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <iterator>

namespace unav::common {
namespace {

constexpr int kSignals[] = {SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT};
constexpr const char* kNames[] = {"SIGSEGV", "SIGBUS", "SIGFPE", "SIGILL", "SIGABRT"};

char g_program[64] = "unav";
struct sigaction g_previous[std::size(kSignals)];
std::atomic<bool> g_reporting{false};

void Put(const char* s) {
  const std::size_t n = std::strlen(s);
  std::size_t done = 0;
  while (done < n) {
    const ssize_t w = ::write(STDERR_FILENO, s + done, n - done);
    if (w <= 0) return;
    done += static_cast<std::size_t>(w);
  }
}

// Unsigned integer as decimal or hexadecimal text into buf (no allocation).
const char* Number(std::uintptr_t v, int base, char (&buf)[32]) {
  char* p = buf + sizeof(buf) - 1;
  *p = '\0';
  do {
    *--p = "0123456789abcdef"[v % static_cast<unsigned>(base)];
    v /= static_cast<unsigned>(base);
  } while (v != 0 && p > buf);
  return p;
}

void Report(int sig, siginfo_t* info, void* /*context*/) {
  std::size_t which = 0;
  while (which < std::size(kSignals) && kSignals[which] != sig) ++which;
  // A second fault while reporting (or in another thread at the same time): report once.
  if (!g_reporting.exchange(true)) {
    char buf[32];
    Put("\n");
    Put(g_program);
    Put(": fatal signal ");
    Put(which < std::size(kNames) ? kNames[which] : Number(static_cast<std::uintptr_t>(sig), 10, buf));
    if (sig != SIGABRT && info != nullptr) {
      Put(" at address 0x");
      Put(Number(reinterpret_cast<std::uintptr_t>(info->si_addr), 16, buf));
    }
    Put(" in thread ");
    Put(Number(static_cast<std::uintptr_t>(::syscall(SYS_gettid)), 10, buf));
    Put(" (pid ");
    Put(Number(static_cast<std::uintptr_t>(::getpid()), 10, buf));
    Put("); native stack of that thread:\n");
    void* frames[64];
    const int n = ::backtrace(frames, static_cast<int>(std::size(frames)));
    ::backtrace_symbols_fd(frames, n, STDERR_FILENO);
    Put("(end of native stack)\n");
  }
  // Hand on to what was there before. A fault raised by the hardware happens again when this
  // returns (now to the previous handler); one sent by kill/raise/abort is sent again.
  if (which < std::size(kSignals)) ::sigaction(sig, &g_previous[which], nullptr);
  if (info == nullptr || info->si_code <= 0 || sig == SIGABRT) ::raise(sig);
}

}  // namespace

void InstallCrashReport(const char* program) {
  std::strncpy(g_program, program != nullptr ? program : "unav", sizeof(g_program) - 1);
  g_program[sizeof(g_program) - 1] = '\0';
  static std::atomic<bool> installed{false};
  if (installed.exchange(true)) return;
  void* warm[1];
  ::backtrace(warm, 1);  // loads libgcc's unwinder now, not inside the handler
  for (std::size_t i = 0; i < std::size(kSignals); ++i) {
    struct sigaction action {};
    action.sa_sigaction = Report;
    action.sa_flags = SA_SIGINFO | SA_ONSTACK;
    sigemptyset(&action.sa_mask);
    ::sigaction(kSignals[i], &action, &g_previous[i]);
  }
}

}  // namespace unav::common
