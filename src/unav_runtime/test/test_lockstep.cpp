// The lockstep barrier protocol: one ack rule, tested without DDS.
#include <gtest/gtest.h>

#include "unav_runtime/lockstep.hpp"

using unav::lockstep::Barrier;
using unav::lockstep::Participant;

namespace {
constexpr int64_t kMs = 1000000;  // ns
}

TEST(LockstepBarrier, OpensOnlyWhenEveryListedParticipantAckedTheInstant) {
  Barrier b({"renderer", "recorder"}, kMs / 2);  // tolerance: half of a 1 kHz physics step
  const int64_t T = 100 * kMs;
  EXPECT_FALSE(b.open(T));
  EXPECT_EQ(b.missing(T), (std::vector<std::string>{"renderer", "recorder"}));
  EXPECT_TRUE(b.on_ack("renderer", T));
  EXPECT_EQ(b.missing(T), std::vector<std::string>{"recorder"});
  EXPECT_FALSE(b.on_ack("stranger", 10 * T));  // not listed: never opens a barrier for anyone
  EXPECT_FALSE(b.open(T));
  EXPECT_TRUE(b.on_ack("recorder", T - kMs / 4));  // rounding below the barrier is within tolerance
  EXPECT_TRUE(b.open(T));
  EXPECT_FALSE(b.open(T + kMs));  // the next barrier needs new acks
  // Acks never go backwards: a late, older ack does not close an open barrier.
  b.on_ack("renderer", T - 50 * kMs);
  EXPECT_TRUE(b.open(T));
  EXPECT_EQ(b.last_ack("renderer"), T);  // what the hold warning shows beside a missing name
  EXPECT_EQ(b.last_ack("nobody"), INT64_MIN);
  EXPECT_TRUE(b.meets(T - kMs / 4, T));
  EXPECT_FALSE(b.meets(T - kMs, T));
}

TEST(LockstepBarrier, DroppedParticipantIsNoLongerWaitedFor) {
  unav::lockstep::Barrier b({"renderer", "recorder"}, 500000);
  b.on_ack("renderer", 100000000);
  EXPECT_FALSE(b.open(100000000));
  EXPECT_EQ(b.missing(100000000), std::vector<std::string>{"recorder"});
  EXPECT_FALSE(b.drop("sonar"));  // not listed
  EXPECT_TRUE(b.drop("recorder"));
  EXPECT_TRUE(b.open(100000000));
  EXPECT_FALSE(b.open(150000000));  // the renderer still counts
  EXPECT_EQ(b.participants(), std::vector<std::string>{"renderer"});
  EXPECT_FALSE(b.on_ack("recorder", 150000000));  // its acks are kept but no longer listed
}

TEST(LockstepBarrier, NoParticipantsMeansAlwaysOpen) {
  Barrier b({}, 0);
  EXPECT_TRUE(b.open(123));
}

TEST(LockstepParticipant, StateAnswererAcksTheStampItAnswered) {
  Participant p;  // renderer, recorder
  EXPECT_EQ(p.ack_for(50 * kMs), 50 * kMs);
  EXPECT_EQ(p.ack_for(100 * kMs), 100 * kMs);
  // The server re-published a held barrier (our ack was lost): ack it again, never lower.
  EXPECT_EQ(p.ack_for(100 * kMs), 100 * kMs);
  EXPECT_EQ(p.ack_for(60 * kMs), 100 * kMs);
  EXPECT_EQ(p.acks(), 4u);
}

TEST(LockstepParticipant, FrameConsumerAcksUpToJustBeforeItsNextFrame) {
  // A 10 Hz estimator owes nothing between frames: after the frame at 1.0 s it acks 1.099 s, so
  // the 20 Hz physics barriers at 1.05 s pass without it and the one at 1.1 s waits for it.
  Participant p(100 * kMs - kMs);
  Barrier b({"orb_slam"}, kMs / 2);
  b.on_ack("orb_slam", p.ack_for(1000 * kMs));
  EXPECT_TRUE(b.open(1050 * kMs));
  EXPECT_FALSE(b.open(1100 * kMs));
  b.on_ack("orb_slam", p.ack_for(1100 * kMs));
  EXPECT_TRUE(b.open(1100 * kMs));
}
