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
#include <cstdio>
#include <map>
#include <string>
#include <utility>
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

/// Where a lockstep server's wall time goes, for the report at the end of a run: the time held at
/// barriers, each hold charged to the input that ended it (the participant whose ack came last,
/// or the thruster command), and the rest (stepping, publishing). The first barrier (t = 0, the
/// participants starting up) is counted apart. Times are wall seconds from any steady clock.
class HoldProfile {
 public:
  /// A barrier was reached and could not be passed at once.
  void held(double wall_s) {
    if (hold_start_ < 0.0) hold_start_ = wall_s;
  }
  /// A barrier was passed at `wall_s`; `by`: the input that opened it (the last ack or command).
  void passed(const std::string& by, double wall_s) {
    const double hold = hold_start_ < 0.0 ? 0.0 : wall_s - hold_start_;
    hold_start_ = -1.0;
    if (run_start_ < 0.0) {  // the first barrier: start-up
      startup_s_ = hold;
      run_start_ = wall_s;
      return;
    }
    ++barriers_;
    if (hold <= 0.0) return;
    Charge& c = charges_[by];
    c.held_s += hold;
    ++c.holds;
  }
  /// The report after `sim_s` simulated seconds, at `wall_s`, e.g. "20.000 s simulated in 6.70 s
  /// of wall time (2.99x real time) after 1.10 s of start-up; 399 barriers, 5.90 s held (88 %):
  /// for underwater_renderer 4.80 s (301), orb_slam 1.10 s (77); between barriers 0.80 s".
  std::string report(double sim_s, double wall_s) const {
    const double wall = run_start_ < 0.0 ? 0.0 : wall_s - run_start_;
    double held = 0.0;
    std::vector<std::pair<std::string, Charge>> rows(charges_.begin(), charges_.end());
    std::sort(rows.begin(), rows.end(), [](const auto& a, const auto& b) { return a.second.held_s > b.second.held_s; });
    std::string by;
    for (const auto& [who, c] : rows) {
      held += c.held_s;
      by += (by.empty() ? ": for " : ", ") + who + " " + fixed(c.held_s, 2) + " s (" + std::to_string(c.holds) + ")";
    }
    return fixed(sim_s, 3) + " s simulated in " + fixed(wall, 2) + " s of wall time (" +
           (wall > 0.0 ? fixed(sim_s / wall, 2) : std::string("-")) + "x real time) after " + fixed(startup_s_, 2) +
           " s of start-up; " + std::to_string(barriers_) + " barriers, " + fixed(held, 2) + " s held (" +
           (wall > 0.0 ? fixed(100.0 * held / wall, 0) : std::string("-")) + " %)" + by + "; between barriers " +
           fixed(std::max(0.0, wall - held), 2) + " s";
  }
  /// When the hold now under way began (wall s); < 0 when not holding.
  double holding_since() const { return hold_start_; }
  /// Hold time charged to `who` so far [s].
  double held_for(const std::string& who) const {
    const auto it = charges_.find(who);
    return it == charges_.end() ? 0.0 : it->second.held_s;
  }
  double startup_s() const { return startup_s_; }
  std::uint64_t barriers() const { return barriers_; }

 private:
  struct Charge {
    double held_s = 0.0;
    std::uint64_t holds = 0;
  };
  static std::string fixed(double v, int digits) {
    char buf[64];
    std::snprintf(buf, sizeof(buf), "%.*f", digits, v);
    return buf;
  }
  std::map<std::string, Charge> charges_;
  double hold_start_ = -1.0, run_start_ = -1.0, startup_s_ = 0.0;
  std::uint64_t barriers_ = 0;
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
