#include "unav_launch/supervisor.hpp"

#include <fcntl.h>
#include <poll.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <iomanip>
#include <sstream>
#include <string>
#include <vector>

extern char** environ;

namespace unav::launch {
namespace {

using Clock = std::chrono::steady_clock;

constexpr std::size_t kMaxPartialLine = std::size_t{64} * 1024;
constexpr int kMaxPollTimeoutMs = 500;
const int kHandledSignals[] = {SIGINT, SIGTERM, SIGCHLD, SIGPIPE};

int g_signal_pipe[2] = {-1, -1};

void on_signal(int signo) {
  const int saved_errno = errno;
  const auto byte = static_cast<unsigned char>(signo);
  [[maybe_unused]] const ssize_t n = ::write(g_signal_pipe[1], &byte, 1);
  errno = saved_errno;
}

// Self-pipe signal handling for the duration of run().
class SignalGuard {
 public:
  SignalGuard() {
    if (g_signal_pipe[0] != -1) {
      throw LaunchError("unav::launch::run() is already running in this process");
    }
    if (::pipe2(g_signal_pipe, O_CLOEXEC | O_NONBLOCK) != 0) {
      throw LaunchError(std::string("cannot create the signal pipe: ") + std::strerror(errno));
    }
    for (std::size_t i = 0; i < std::size(kHandledSignals); ++i) {
      struct sigaction action {};
      action.sa_handler = kHandledSignals[i] == SIGPIPE ? SIG_IGN : on_signal;
      sigemptyset(&action.sa_mask);
      action.sa_flags = SA_RESTART | (kHandledSignals[i] == SIGCHLD ? SA_NOCLDSTOP : 0);
      ::sigaction(kHandledSignals[i], &action, &previous_[i]);
    }
  }
  ~SignalGuard() {
    for (std::size_t i = 0; i < std::size(kHandledSignals); ++i) {
      ::sigaction(kHandledSignals[i], &previous_[i], nullptr);
    }
    ::close(g_signal_pipe[0]);
    ::close(g_signal_pipe[1]);
    g_signal_pipe[0] = g_signal_pipe[1] = -1;
  }
  SignalGuard(const SignalGuard&) = delete;
  SignalGuard& operator=(const SignalGuard&) = delete;

 private:
  struct sigaction previous_[std::size(kHandledSignals)]{};
};

std::string join(const std::vector<std::string>& items) {
  std::string out;
  for (const auto& item : items) {
    out += (out.empty() ? "" : " ") + item;
  }
  return out;
}

struct Process {
  const NodeDescription* node = nullptr;
  std::string label;  // "<exec>-<n>"
  std::vector<std::string> argv;
  std::vector<std::string> envp;
  pid_t pid = -1;
  int out_fd = -1;
  std::string partial;
  bool respawn_pending = false;
  Clock::time_point respawn_at;
  // Resource use over every run of the process (respawns summed): from wait4() at each exit.
  Clock::time_point started;
  double alive_s = 0, user_s = 0, system_s = 0;
  long max_rss_kb = 0;
  int runs = 0;
};

double seconds_of(const timeval& t) { return static_cast<double>(t.tv_sec) + 1e-6 * static_cast<double>(t.tv_usec); }

class Supervisor {
 public:
  Supervisor(const LaunchDescription& description, const SupervisorOptions& options)
      : options_(options), out_(*options.out) {
    for (std::size_t i = 0; i < description.nodes.size(); ++i) {
      Process process;
      process.node = &description.nodes[i];
      process.label = process.node->executable + "-" + std::to_string(i + 1);
      process.argv = node_argv(*process.node);
      for (char** entry = environ; *entry != nullptr; ++entry) {
        const std::string text = *entry;
        const std::string name = text.substr(0, text.find('='));
        const auto& env = process.node->env;
        if (std::none_of(env.begin(), env.end(), [&](const auto& e) { return e.first == name; })) {
          process.envp.push_back(text);
        }
      }
      for (const auto& [name, value] : process.node->env) {
        process.envp.push_back(name + "=" + value);
      }
      processes_.push_back(std::move(process));
    }
  }

  int run() {
    const int stagger_ms = start_stagger_ms();
    if (stagger_ms > 0 && processes_.size() > 1)
      log("INFO", "launch", "starting nodes " + std::to_string(stagger_ms) + " ms apart");
    for (auto& process : processes_) {
      if (stage_ == 0) {
        spawn(process);
        if (stagger_ms > 0) ::usleep(static_cast<useconds_t>(stagger_ms) * 1000);
      }
    }
    while (true) {
      reap();
      const auto now = Clock::now();
      if (stage_ > 0 && stage_ < 3 && now >= next_escalation_) {
        escalate();
      }
      for (auto& process : processes_) {
        if (stage_ == 0 && process.respawn_pending && now >= process.respawn_at) {
          process.respawn_pending = false;
          spawn(process);
        }
      }
      if (std::none_of(processes_.begin(), processes_.end(),
                       [](const Process& p) { return p.pid > 0 || p.respawn_pending; })) {
        break;
      }
      wait_for_events();
    }
    report_resources();
    if (result_ >= 0) {
      return result_;
    }
    return any_failed_ ? 1 : 0;
  }

 private:
  void log(const char* level, const std::string& who, const std::string& message) {
    out_ << '[' << level << "] [" << who << "]: " << message << '\n' << std::flush;
  }

  // With DDS Security on, Fast DDS 2.9 (Debian 12) leaves a pair of participants unauthenticated
  // for good, now and then, when many start their handshakes at the same instant: measured on
  // the 2-core machine, 8 secured nodes started together hung the lockstep in ~15 % of launches
  // (one node pair never matched), none in 24 launches started 300 ms apart. So secured launches
  // start their nodes 300 ms apart; UNAV_LAUNCH_STAGGER_MS sets it (0 = all at once).
  static int start_stagger_ms() {
    if (const char* env = std::getenv("UNAV_LAUNCH_STAGGER_MS"); env && *env) {
      char* end = nullptr;
      const long ms = std::strtol(env, &end, 10);
      if (*end == '\0' && ms >= 0 && ms <= 10000) return static_cast<int>(ms);
    }
    const char* secure = std::getenv("ROS_SECURITY_ENABLE");
    return secure && std::string(secure) == "true" ? 300 : 0;
  }

  void spawn(Process& process) {
    int fds[2];
    if (::pipe2(fds, O_CLOEXEC) != 0) {
      log("ERROR", process.label, std::string("cannot create a pipe: ") + std::strerror(errno));
      on_exit(process, 127 << 8);
      return;
    }
    // Everything the child touches is prepared before fork: only async-signal-safe calls after.
    std::vector<char*> argv, envp;
    for (auto& arg : process.argv) argv.push_back(arg.data());
    for (auto& var : process.envp) envp.push_back(var.data());
    argv.push_back(nullptr);
    envp.push_back(nullptr);
    const pid_t parent = ::getpid();
    const pid_t pid = ::fork();
    if (pid == 0) {
      ::setpgid(0, 0);
      ::prctl(PR_SET_PDEATHSIG, SIGTERM);
      if (::getppid() != parent) {
        ::_exit(1);
      }
      for (int signo : kHandledSignals) {
        struct sigaction action {};
        action.sa_handler = SIG_DFL;
        ::sigaction(signo, &action, nullptr);
      }
      sigset_t none;
      sigemptyset(&none);
      ::sigprocmask(SIG_SETMASK, &none, nullptr);
      const int null_fd = ::open("/dev/null", O_RDONLY);
      if (null_fd >= 0) ::dup2(null_fd, STDIN_FILENO);
      ::dup2(fds[1], STDOUT_FILENO);
      ::dup2(fds[1], STDERR_FILENO);
      ::execve(argv[0], argv.data(), envp.data());
      const char message[] = "unav launch: exec failed\n";
      [[maybe_unused]] const ssize_t n = ::write(STDERR_FILENO, message, sizeof(message) - 1);
      ::_exit(127);
    }
    ::close(fds[1]);
    if (pid < 0) {
      ::close(fds[0]);
      log("ERROR", process.label, std::string("cannot fork: ") + std::strerror(errno));
      on_exit(process, 127 << 8);
      return;
    }
    ::setpgid(pid, pid);  // also here, so signals reach the group whoever runs first
    ::fcntl(fds[0], F_SETFL, ::fcntl(fds[0], F_GETFL) | O_NONBLOCK);
    process.pid = pid;
    process.out_fd = fds[0];
    process.started = Clock::now();
    ++process.runs;
    log("INFO", process.label, "process started with pid [" + std::to_string(pid) + "]");
  }

  void reap() {
    for (auto& process : processes_) {
      if (process.pid <= 0) {
        continue;
      }
      siginfo_t info{};
      if (::waitid(P_PID, process.pid, &info, WEXITED | WNOHANG | WNOWAIT) != 0 || info.si_pid != process.pid) {
        continue;
      }
      // The main process is a zombie and still holds its group: end what is left of it.
      ::kill(-process.pid, SIGKILL);
      int status = 0;
      rusage usage{};
      while (::wait4(process.pid, &status, 0, &usage) < 0 && errno == EINTR) {
      }
      process.alive_s += std::chrono::duration<double>(Clock::now() - process.started).count();
      process.user_s += seconds_of(usage.ru_utime);
      process.system_s += seconds_of(usage.ru_stime);
      process.max_rss_kb = std::max(process.max_rss_kb, usage.ru_maxrss);
      on_exit(process, status);
    }
  }

  void on_exit(Process& process, int status) {
    read_output(process, true);
    const int code = WIFSIGNALED(status) ? -WTERMSIG(status) : WEXITSTATUS(status);
    const pid_t pid = process.pid;
    process.pid = -1;
    if (code == 0) {
      log("INFO", process.label, "process has finished cleanly [pid " + std::to_string(pid) + "]");
    } else {
      log("ERROR", process.label,
          "process has died [pid " + std::to_string(pid) + ", exit code " + std::to_string(code) + ", cmd '" +
              join(process.argv) + "']");
    }
    if (stage_ > 0) {
      return;
    }
    any_failed_ = any_failed_ || code != 0;
    if (process.node->required) {
      result_ = code >= 0 ? code : 1;  // a clean exit of a required node ends the launch cleanly
      begin_shutdown("required process [" + process.label + "] has exited");
    } else if (process.node->respawn) {
      process.respawn_pending = true;
      process.respawn_at = Clock::now() + seconds(process.node->respawn_delay_s);
    }
  }

  // Where the wall time went, per process: CPU (user + system, all its threads and the children it
  // waited for) against the time it was alive. A lockstep participant's idle share is the time
  // it waited for the others (or for the clock); the run's CPU sum against its wall time says
  // whether the machine's cores were the limit.
  void report_resources() {
    if (std::none_of(processes_.begin(), processes_.end(), [](const Process& p) { return p.runs > 0; })) return;
    const double wall = std::chrono::duration<double>(Clock::now() - launch_start_).count();
    double total_cpu = 0;
    std::size_t width = 0;
    for (const auto& p : processes_) width = std::max(width, p.label.size());
    std::ostringstream table;
    table << std::fixed << std::setprecision(2);
    for (const auto& p : processes_) {
      if (p.runs == 0) continue;
      const double cpu = p.user_s + p.system_s;
      total_cpu += cpu;
      table << "\n  " << std::left << std::setw(static_cast<int>(width)) << p.label << std::right << "  cpu "
            << std::setw(7) << cpu << " s (user " << p.user_s << ", sys " << p.system_s << ") over " << p.alive_s
            << " s alive: " << std::setprecision(0) << std::setw(3) << (p.alive_s > 0 ? 100.0 * cpu / p.alive_s : 0.0)
            << " % busy, max RSS " << std::setw(4) << p.max_rss_kb / 1024 << " MiB" << std::setprecision(2);
      if (p.runs > 1) table << ", " << p.runs << " runs";
    }
    std::ostringstream head;
    head << std::fixed << std::setprecision(2) << "resource use: " << total_cpu << " s of CPU in " << wall
         << " s of wall time (" << std::setprecision(2) << (wall > 0 ? total_cpu / wall : 0.0)
         << " cores busy on average)";
    log("INFO", "launch", head.str() + table.str());
  }

  static Clock::duration seconds(double s) {
    return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(s));
  }

  void begin_shutdown(const std::string& reason) {
    log("INFO", "launch", reason + ", shutting down");
    stage_ = 1;
    for (auto& process : processes_) {
      process.respawn_pending = false;
    }
    signal_all(SIGINT);
    next_escalation_ = Clock::now() + seconds(options_.sigint_grace_s);
  }

  void escalate() {
    const bool to_kill = stage_ == 2;
    const double waited = to_kill ? options_.sigterm_grace_s : options_.sigint_grace_s;
    for (const auto& process : processes_) {
      if (process.pid > 0) {
        std::ostringstream message;
        message << "process [" << process.label << "] failed to terminate " << waited << " s after "
                << (to_kill ? "SIGTERM" : "SIGINT") << ", escalating to " << (to_kill ? "SIGKILL" : "SIGTERM");
        log(to_kill ? "ERROR" : "WARNING", process.label, message.str());
      }
    }
    ++stage_;
    signal_all(to_kill ? SIGKILL : SIGTERM);
    next_escalation_ = Clock::now() + seconds(options_.sigterm_grace_s);
  }

  void signal_all(int signo) {
    for (const auto& process : processes_) {
      if (process.pid > 0 && ::kill(-process.pid, signo) != 0) {
        ::kill(process.pid, signo);
      }
    }
  }

  void wait_for_events() {
    std::vector<pollfd> fds{{g_signal_pipe[0], POLLIN, 0}};
    std::vector<Process*> owners{nullptr};
    for (auto& process : processes_) {
      if (process.out_fd >= 0) {
        fds.push_back({process.out_fd, POLLIN, 0});
        owners.push_back(&process);
      }
    }
    auto deadline = Clock::now() + std::chrono::milliseconds(kMaxPollTimeoutMs);
    if (stage_ > 0 && stage_ < 3) {
      deadline = std::min(deadline, next_escalation_);
    }
    for (const auto& process : processes_) {
      if (process.respawn_pending) {
        deadline = std::min(deadline, process.respawn_at);
      }
    }
    const auto timeout = std::chrono::ceil<std::chrono::milliseconds>(deadline - Clock::now());
    if (::poll(fds.data(), fds.size(), std::max<int>(0, static_cast<int>(timeout.count()))) <= 0) {
      return;
    }
    if (fds[0].revents != 0) {
      unsigned char signals[64];
      const ssize_t n = ::read(g_signal_pipe[0], signals, sizeof(signals));
      for (ssize_t i = 0; i < n; ++i) {
        if (signals[i] == SIGINT || signals[i] == SIGTERM) {
          on_stop_signal(signals[i]);
        }
      }
    }
    for (std::size_t i = 1; i < fds.size(); ++i) {
      if (fds[i].revents != 0) {
        read_output(*owners[i], false);
      }
    }
  }

  // Repeats are ignored, like ros2 launch: a signal often arrives twice (`timeout` signals
  // both its child and its process group).
  void on_stop_signal(int signo) {
    const std::string name = signo == SIGINT ? "SIGINT" : "SIGTERM";
    if (stage_ == 0) {
      result_ = 128 + signo;
      begin_shutdown("caught " + name);
    } else {
      log("INFO", "launch", "caught " + name + " again, already shutting down");
    }
  }

  // Reads what the pipe holds; at EOF or when `final` (the process is gone) prints the
  // unterminated rest and closes it.
  void read_output(Process& process, bool final) {
    if (process.out_fd < 0) {
      return;
    }
    char buffer[65536];
    bool eof = false;
    for (int round = 0; final || round < 16; ++round) {
      const ssize_t n = ::read(process.out_fd, buffer, sizeof(buffer));
      if (n > 0) {
        process.partial.append(buffer, static_cast<std::size_t>(n));
        print_lines(process);
      } else if (n < 0 && errno == EINTR) {
        continue;
      } else {
        eof = n == 0 || errno != EAGAIN;
        break;
      }
    }
    if (eof || final) {
      if (!process.partial.empty()) {
        print_line(process, process.partial);
        process.partial.clear();
      }
      ::close(process.out_fd);
      process.out_fd = -1;
    }
    out_.flush();
  }

  void print_lines(Process& process) {
    std::size_t start = 0;
    for (std::size_t end; (end = process.partial.find('\n', start)) != std::string::npos; start = end + 1) {
      print_line(process, process.partial.substr(start, end - start));
    }
    process.partial.erase(0, start);
    if (process.partial.size() > kMaxPartialLine) {
      print_line(process, process.partial);
      process.partial.clear();
    }
  }

  void print_line(const Process& process, std::string line) {
    if (!line.empty() && line.back() == '\r') {
      line.pop_back();
    }
    out_ << '[' << process.label << "] " << line << '\n';
  }

  const SupervisorOptions& options_;
  std::ostream& out_;
  std::vector<Process> processes_;
  int stage_ = 0;  // 0 running, 1 SIGINT sent, 2 SIGTERM sent, 3 SIGKILL sent
  Clock::time_point next_escalation_;
  int result_ = -1;
  bool any_failed_ = false;
  Clock::time_point launch_start_ = Clock::now();
};

}  // namespace

int run(const LaunchDescription& description, const SupervisorOptions& options) {
  SignalGuard guard;
  return Supervisor(description, options).run();
}

}  // namespace unav::launch
