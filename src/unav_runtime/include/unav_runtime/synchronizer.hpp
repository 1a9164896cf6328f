// Pairing two message streams by stamp, with message_filters' policies (STYLE.md item 17): a node
// does not keep its own map of stamps. DDS-free and header-only; stamps are integer nanoseconds
// (unav::nanoseconds(msg.header())); each stream must arrive in stamp order, as one publisher's
// reliable stream does.
//
//   unav::sync::ExactTime<Image, Odometry> sync(10, [&](const Image& i, const Odometry& o) {...});
//   image_sub: sync.add_first(unav::nanoseconds(m.header()), m);
//   odom_sub:  sync.add_second(unav::nanoseconds(m.header()), m);
#pragma once

#include <cstdint>
#include <cstdlib>
#include <deque>
#include <functional>
#include <utility>

namespace unav::sync {

namespace detail {
/// Appends (t, msg) to a stream's queue, dropping (and counting) the oldest beyond `queue_size`.
template <class Q, class T>
void push_bounded(Q* q, int64_t t, const T& msg, std::size_t queue_size, std::uint64_t* dropped) {
  q->emplace_back(t, msg);
  if (q->size() > queue_size) {
    q->pop_front();
    ++*dropped;
  }
}
}  // namespace detail

/// ExactTime: emits (a, b) when both streams have a message with the same stamp. Each stream
/// keeps at most `queue_size` unmatched messages; the oldest is dropped (and counted) beyond
/// that, and a message older than the newest match can never match any more and is dropped.
template <class A, class B>
class ExactTime {
 public:
  using Callback = std::function<void(const A&, const B&)>;
  ExactTime(std::size_t queue_size, Callback callback) : queue_size_(queue_size), callback_(std::move(callback)) {}

  void add_first(int64_t stamp_ns, const A& a) {
    drop_older(&b_, stamp_ns);
    if (!b_.empty() && b_.front().first == stamp_ns) {
      emit(a, b_.front().second);
      b_.pop_front();
      drop_all(&a_);  // our older unmatched messages cannot match any more
      return;
    }
    push(&a_, stamp_ns, a);
  }
  void add_second(int64_t stamp_ns, const B& b) {
    drop_older(&a_, stamp_ns);
    if (!a_.empty() && a_.front().first == stamp_ns) {
      emit(a_.front().second, b);
      a_.pop_front();
      drop_all(&b_);
      return;
    }
    push(&b_, stamp_ns, b);
  }
  /// Messages dropped without a partner (queue overflow or passed by a later match).
  std::uint64_t dropped() const { return dropped_; }
  std::uint64_t matched() const { return matched_; }

 private:
  // The other stream is in order too: its messages older than t will never find a partner.
  template <class Q>
  void drop_older(Q* q, int64_t t) {
    while (!q->empty() && q->front().first < t) {
      q->pop_front();
      ++dropped_;
    }
  }
  template <class Q>
  void drop_all(Q* q) {
    dropped_ += q->size();
    q->clear();
  }
  template <class Q, class T>
  void push(Q* q, int64_t t, const T& msg) {
    detail::push_bounded(q, t, msg, queue_size_, &dropped_);
  }
  void emit(const A& a, const B& b) {
    ++matched_;
    callback_(a, b);
  }

  std::size_t queue_size_;
  Callback callback_;
  std::deque<std::pair<int64_t, A>> a_;
  std::deque<std::pair<int64_t, B>> b_;
  std::uint64_t dropped_ = 0, matched_ = 0;
};

/// ApproximateTime for two streams: the oldest waiting message (the pivot) is paired with the
/// other stream's message nearest in time, decided as soon as the other stream has a message at
/// or after the pivot (in-order streams: nothing later can be nearer). A pair further apart than
/// `max_interval_ns` is not emitted: the pivot is dropped. Everything older than an emitted pair
/// is dropped; queues hold at most `queue_size` messages each.
template <class A, class B>
class ApproximateTime {
 public:
  using Callback = std::function<void(const A&, const B&)>;
  ApproximateTime(std::size_t queue_size, int64_t max_interval_ns, Callback callback)
      : queue_size_(queue_size), max_interval_ns_(max_interval_ns), callback_(std::move(callback)) {}

  void add_first(int64_t stamp_ns, const A& a) {
    push(&a_, stamp_ns, a);
    process();
  }
  void add_second(int64_t stamp_ns, const B& b) {
    push(&b_, stamp_ns, b);
    process();
  }
  std::uint64_t dropped() const { return dropped_; }
  std::uint64_t matched() const { return matched_; }

 private:
  template <class Q, class T>
  void push(Q* q, int64_t t, const T& msg) {
    detail::push_bounded(q, t, msg, queue_size_, &dropped_);
  }
  // Index of the element of `q` nearest to t, or -1 when q has nothing at or after t yet.
  template <class Q>
  static long nearest_decided(const Q& q, int64_t t) {
    long best = -1;
    bool after = false;
    for (std::size_t i = 0; i < q.size(); ++i) {
      if (best < 0 || std::llabs(q[i].first - t) < std::llabs(q[static_cast<std::size_t>(best)].first - t))
        best = static_cast<long>(i);
      if (q[i].first >= t) {
        after = true;
        break;
      }
    }
    return after ? best : -1;
  }
  void process() {
    while (!a_.empty() && !b_.empty()) {
      const bool pivot_is_a = a_.front().first <= b_.front().first;
      const int64_t t = pivot_is_a ? a_.front().first : b_.front().first;
      const long j = pivot_is_a ? nearest_decided(b_, t) : nearest_decided(a_, t);
      if (j < 0) return;  // wait for the other stream
      const int64_t t_other =
          pivot_is_a ? b_[static_cast<std::size_t>(j)].first : a_[static_cast<std::size_t>(j)].first;
      if (std::llabs(t_other - t) > max_interval_ns_) {
        if (pivot_is_a)
          a_.pop_front();
        else
          b_.pop_front();
        ++dropped_;
        continue;
      }
      const std::size_t ja = pivot_is_a ? 0 : static_cast<std::size_t>(j);
      const std::size_t jb = pivot_is_a ? static_cast<std::size_t>(j) : 0;
      ++matched_;
      callback_(a_[ja].second, b_[jb].second);
      dropped_ += ja + jb;  // skipped over on the way to the pair
      a_.erase(a_.begin(), a_.begin() + static_cast<long>(ja) + 1);
      b_.erase(b_.begin(), b_.begin() + static_cast<long>(jb) + 1);
    }
  }

  std::size_t queue_size_;
  int64_t max_interval_ns_;
  Callback callback_;
  std::deque<std::pair<int64_t, A>> a_;
  std::deque<std::pair<int64_t, B>> b_;
  std::uint64_t dropped_ = 0, matched_ = 0;
};

}  // namespace unav::sync
