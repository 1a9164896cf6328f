// The lockstep barrier protocol (DESIGN.md section 5) as two small DDS-free state machines, one
// implementation for every node (STYLE.md item 18).
//
// The protocol:
//   * The physics server owns simulated time. Every `lockstep_period` it reaches a barrier at
//     instant T, publishes the state stamped T and does not step past T until every listed
//     participant has acked an instant >= T (and, optionally, a thruster command stamped >= T
//     arrived). While it holds, it re-publishes the barrier's state every second, so a
//     participant that joined late (or whose ack was lost) answers again.
//   * ONE ACK RULE: a participant's ack stamped t means "I have published every output I owe for
//     every instant <= t, and I need no input before t". A participant that answers states
//     (renderer, recorder) acks the stamp of the state it answered; one that works on camera
//     frames (an estimator) acks up to just before its next frame is due (frame stamp + frame
//     period - margin): it owes nothing in between. Acks never go backwards; a repeated input
//     is acked again (the repeat means the server did not see the first ack).
// Stamps are integer nanoseconds (builtin_interfaces/Time), compared with a tolerance of half a
// physics step so that a stamp rounded from a double still meets its barrier.
#pragma once

#include <algorithm>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace unav::lockstep {

/// Server side: who must ack, what they acked, whether a barrier may be passed.
class Barrier {
 public:
  /// `participants`: names listed in the server's lockstep_participants; `tolerance_ns`: an ack
  /// this close below the barrier counts (half a physics step).
  Barrier(std::vector<std::string> participants, int64_t tolerance_ns)
      : participants_(std::move(participants)), tolerance_ns_(tolerance_ns) {}

  /// Records an ack (the latest stamp per participant wins; older acks are ignored). Returns
  /// false when `who` is not a listed participant (the ack is kept but never waited for).
  bool on_ack(const std::string& who, int64_t t_ns) {
    auto it = last_ack_.find(who);
    if (it == last_ack_.end())
      last_ack_.emplace(who, t_ns);
    else
      it->second = std::max(it->second, t_ns);
    return std::find(participants_.begin(), participants_.end(), who) != participants_.end();
  }
  /// Stops waiting for `who` (a participant that hung or died for good: the run goes on without
  /// it). Returns false when `who` is not a listed participant.
  bool drop(const std::string& who) {
    const auto it = std::find(participants_.begin(), participants_.end(), who);
    if (it == participants_.end()) return false;
    participants_.erase(it);
    return true;
  }
  /// Whether `who` has acked anything yet.
  bool has_acked(const std::string& who) const { return last_ack_.count(who) != 0; }
  /// The latest instant `who` acked; INT64_MIN when it has acked nothing.
  int64_t last_ack(const std::string& who) const {
    const auto it = last_ack_.find(who);
    return it == last_ack_.end() ? INT64_MIN : it->second;
  }
  /// True when every participant acked an instant >= barrier (within the tolerance).
  bool open(int64_t barrier_ns) const { return missing(barrier_ns).empty(); }
  /// Participants that have not acked the barrier yet, in list order.
  std::vector<std::string> missing(int64_t barrier_ns) const {
    std::vector<std::string> out;
    for (const auto& p : participants_) {
      const auto it = last_ack_.find(p);
      if (it == last_ack_.end() || it->second < barrier_ns - tolerance_ns_) out.push_back(p);
    }
    return out;
  }
  /// Whether a stamp (e.g. of a thruster command) meets the barrier, with the same tolerance.
  bool meets(int64_t stamp_ns, int64_t barrier_ns) const { return stamp_ns >= barrier_ns - tolerance_ns_; }
  const std::vector<std::string>& participants() const { return participants_; }

 private:
  std::vector<std::string> participants_;
  int64_t tolerance_ns_;
  std::map<std::string, int64_t> last_ack_;
};

/// Participant side: the stamp to ack after the outputs for an input were published.
class Participant {
 public:
  /// `lead_ns` = 0 for a participant that answers every state; frame period - margin for one
  /// that consumes frames (it owes nothing until its next frame).
  explicit Participant(int64_t lead_ns = 0) : lead_ns_(lead_ns) {}

  /// Call after every output owed for the input stamped `input_ns` has been published (or the
  /// input was rejected). Returns the stamp to ack: input + lead, never below an earlier ack.
  int64_t ack_for(int64_t input_ns) {
    last_ = std::max(last_, input_ns + lead_ns_);
    ++acks_;
    return last_;
  }
  int64_t last_acked_ns() const { return last_; }
  std::uint64_t acks() const { return acks_; }
  int64_t lead_ns() const { return lead_ns_; }

 private:
  int64_t lead_ns_;
  int64_t last_ = INT64_MIN;
  std::uint64_t acks_ = 0;
};

}  // namespace unav::lockstep
