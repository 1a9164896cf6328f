// Single-threaded executor: DDS listener threads only enqueue ready entities; callbacks and timers
// run on the thread that spins, so node code needs no locks.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <vector>

namespace unav {

/// Something the executor runs when a listener marks it ready (a subscription).
class Waitable {
 public:
  virtual ~Waitable() = default;
  /// Takes the available samples and runs the callbacks. Returns true if more may be pending.
  virtual bool execute() = 0;
  std::atomic<bool> queued{false};
};

class Clock;

/// A periodic callback. Wall timers use the steady clock; ROS timers follow the node clock
/// (simulated time while use_sim_time is active).
class Timer {
 public:
  Timer(std::chrono::nanoseconds period, std::function<void()> callback, bool ros_time)
      : period_(period), callback_(std::move(callback)), ros_time_(ros_time) {}
  void cancel() { cancelled_ = true; }
  bool is_cancelled() const { return cancelled_; }
  std::chrono::nanoseconds period() const { return period_; }

 private:
  friend class Executor;
  std::chrono::nanoseconds period_;
  std::function<void()> callback_;
  bool ros_time_;
  std::atomic<bool> cancelled_{false};
  std::chrono::steady_clock::time_point next_steady_{};
  int64_t next_ros_ns_ = -1;
};

class Executor {
 public:
  explicit Executor(Clock& clock) : clock_(clock) {}
  /// Called from any thread: marks `w` ready and wakes the spinning thread.
  void notify(const std::shared_ptr<Waitable>& w);
  void add_timer(const std::shared_ptr<Timer>& t);
  /// Runs until shutdown() is called (or a signal arrives through the Context).
  void spin();
  /// Runs callbacks until `done()` is true or `timeout` passes; returns done().
  bool spin_until(const std::function<bool()>& done, std::chrono::nanoseconds timeout);
  /// Runs what is ready or due within `max_wait`, then returns.
  void spin_some(std::chrono::nanoseconds max_wait = std::chrono::nanoseconds(0));
  void shutdown();
  bool is_shutdown() const { return shutdown_; }
  /// Wakes the spinning thread (e.g. after simulated time advanced).
  void wake();

 private:
  // Waits up to `deadline` for work, runs at most one batch; false if nothing ran.
  bool run_once(std::chrono::steady_clock::time_point deadline);
  bool run_due_timers();

  Clock& clock_;
  std::mutex mutex_;
  std::condition_variable cv_;
  std::deque<std::weak_ptr<Waitable>> ready_;
  std::vector<std::weak_ptr<Timer>> timers_;
  std::atomic<bool> shutdown_{false};
  bool woken_ = false;
};

}  // namespace unav
