// A lockstep participant's acks on /lockstep/ack, by the one ack rule of lockstep.hpp. A node
// that includes this links unav_msgs (header-only here, so the runtime itself does not).
//
//   acker_ = std::make_unique<unav::lockstep::Acker>(*this, "renderer");          // answers states
//   acker_ = std::make_unique<unav::lockstep::Acker>(*this, "orb_slam", 0.099);   // frame consumer
//   ...publish every output owed for the input...
//   acker_->ack(input.header());
#pragma once

#include <cmath>
#include <memory>
#include <string>
#include <utility>

#include "unav_common/config.hpp"
#include "unav_msgs/msg/lockstep_ack.hpp"
#include "unav_runtime/conversions.hpp"
#include "unav_runtime/lockstep.hpp"
#include "unav_runtime/node.hpp"

namespace unav::lockstep {

/// QoS of /lockstep/ack, both sides: reliable, transient local, keep last 100. A participant
/// acks an input once; an ack written before the physics server's reader matched its writer (16
/// processes starting at once on 2 cores) was lost with a volatile writer, and the lockstep held
/// at t = 0 for ever. Transient local hands it to the late reader.
inline QoS ack_qos() { return {QoS::Reliability::kReliable, QoS::Durability::kTransientLocal, 100}; }

/// A participant's `lockstep` and `lockstep_name` parameters. A node's params struct embeds it,
/// `unav::lockstep::ParticipantParams lockstep{"renderer"};`, and calls `lockstep.Serialize(a)`:
/// the keys stay at the node's level. What the node acks and when is said in its header.
struct ParticipantParams {
  bool enabled = false;
  std::string name;
  explicit ParticipantParams(std::string default_name) : name(std::move(default_name)) {}
  template <class Archive>
  void Serialize(Archive* a) {
    a->Visit(unav::common::Field("lockstep", &enabled).Doc("a lockstep participant: ack on /lockstep/ack"));
    a->Visit(unav::common::Field("lockstep_name", &name).Doc("participant name in acks"));
  }
};

class Acker {
 public:
  /// `name`: the participant name the physics server lists; `lead_s`: see Participant (0 for a
  /// participant that answers every state, frame period - margin for a frame consumer).
  Acker(unav::Node& node, std::string name, double lead_s = 0.0)
      : name_(std::move(name)),
        participant_(std::llround(lead_s * 1e9)),
        pub_(node.create_publisher<unav_msgs::msg::LockstepAck>("/lockstep/ack", ack_qos())) {}

  /// Call once every output owed for the input with this header has been published.
  void ack(const std_msgs::msg::Header& input) { ack(nanoseconds(input)); }
  /// The same for an input instant in nanoseconds (a participant that computes what it owes).
  void ack(int64_t input_ns) {
    unav_msgs::msg::LockstepAck a;
    a.header().stamp() = to_msg(Time{participant_.ack_for(input_ns)});
    a.participant(name_);
    pub_->publish(a);
  }
  const std::string& name() const { return name_; }
  const Participant& participant() const { return participant_; }
  /// The ack publisher (tests wait for it to match).
  const std::shared_ptr<unav::Publisher<unav_msgs::msg::LockstepAck>>& publisher() const { return pub_; }

 private:
  std::string name_;
  Participant participant_;
  std::shared_ptr<unav::Publisher<unav_msgs::msg::LockstepAck>> pub_;
};

}  // namespace unav::lockstep
