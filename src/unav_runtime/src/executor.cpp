#include "unav_runtime/executor.hpp"

#include <algorithm>
#include <chrono>

#include "unav_runtime/clock.hpp"

namespace unav {

Time Clock::now() const {
  if (sim_active_) return Time{sim_ns_.load()};
  return Time{std::chrono::duration_cast<std::chrono::nanoseconds>(
                  std::chrono::system_clock::now().time_since_epoch())
                  .count()};
}

void Executor::notify(const std::shared_ptr<Waitable>& w) {
  if (w->queued.exchange(true)) return;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    ready_.push_back(w);
  }
  cv_.notify_one();
}

void Executor::add_timer(const std::shared_ptr<Timer>& t) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    t->next_steady_ = std::chrono::steady_clock::now() + t->period_;
    timers_.push_back(t);
  }
  cv_.notify_one();
}

void Executor::shutdown() {
  shutdown_ = true;
  cv_.notify_all();
}

void Executor::wake() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    woken_ = true;
  }
  cv_.notify_one();
}

bool Executor::run_due_timers() {
  std::vector<std::shared_ptr<Timer>> due;
  const auto now = std::chrono::steady_clock::now();
  const bool sim = clock_.sim_time_active();
  const int64_t ros_now = sim ? clock_.now().ns : 0;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    timers_.erase(std::remove_if(timers_.begin(), timers_.end(),
                                 [](const std::weak_ptr<Timer>& w) {
                                   auto t = w.lock();
                                   return !t || t->is_cancelled();
                                 }),
                  timers_.end());
    for (auto& w : timers_) {
      auto t = w.lock();
      if (t->ros_time_ && sim) {
        if (t->next_ros_ns_ < 0) t->next_ros_ns_ = ros_now + t->period_.count();
        if (ros_now >= t->next_ros_ns_) {
          // Simulated time may jump by several periods: fire once, catch up the schedule.
          while (t->next_ros_ns_ <= ros_now) t->next_ros_ns_ += t->period_.count();
          due.push_back(t);
        }
      } else if (now >= t->next_steady_) {
        t->next_steady_ += t->period_;
        if (t->next_steady_ < now) t->next_steady_ = now + t->period_;  // overrun: no burst
        due.push_back(t);
      }
    }
  }
  for (auto& t : due)
    if (!t->is_cancelled() && !shutdown_) t->callback_();
  return !due.empty();
}

bool Executor::run_once(std::chrono::steady_clock::time_point deadline) {
  std::shared_ptr<Waitable> work;
  {
    std::unique_lock<std::mutex> lock(mutex_);
    auto wake_at = deadline;
    const bool sim = clock_.sim_time_active();
    for (auto& w : timers_)
      if (auto t = w.lock(); t && !(t->ros_time_ && sim)) wake_at = std::min(wake_at, t->next_steady_);
    cv_.wait_until(lock, wake_at, [&] { return shutdown_ || woken_ || !ready_.empty(); });
    woken_ = false;
    while (!ready_.empty() && !work) {
      work = ready_.front().lock();
      ready_.pop_front();
    }
  }
  bool ran = false;
  if (work && !shutdown_) {
    work->queued = false;
    if (work->execute()) notify(work);  // more samples pending: requeue behind the others
    ran = true;
  }
  if (!shutdown_) ran = run_due_timers() || ran;
  return ran;
}

void Executor::spin() {
  while (!shutdown_) run_once(std::chrono::steady_clock::now() + std::chrono::seconds(1));
}

bool Executor::spin_until(const std::function<bool()>& done, std::chrono::nanoseconds timeout) {
  const auto end = std::chrono::steady_clock::now() + timeout;
  while (!done() && !shutdown_ && std::chrono::steady_clock::now() < end)
    run_once(std::min(end, std::chrono::steady_clock::now() + std::chrono::milliseconds(10)));
  return done();
}

void Executor::spin_some(std::chrono::nanoseconds max_wait) {
  const auto end = std::chrono::steady_clock::now() + max_wait;
  while (!shutdown_ && run_once(end)) {
  }
}

}  // namespace unav
