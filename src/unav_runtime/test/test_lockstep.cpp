// The lockstep barrier protocol: one ack rule, tested without DDS.
#include <gtest/gtest.h>

#include "unav_runtime/lockstep.hpp"

using unav::lockstep::Barrier;
using unav::lockstep::HoldProfile;
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

TEST(LockstepHoldProfile, ChargesEachHoldToTheInputThatEndedIt) {
  HoldProfile p;
  p.held(10.0);  // t = 0: the participants start up for 1.5 s
  p.passed("renderer", 11.5);
  p.passed("renderer", 11.6);  // passed at once: a barrier, no hold
  p.held(11.7);
  p.held(11.8);                // still the same hold
  p.passed("renderer", 11.9);  // 0.2 s for the renderer
  p.held(12.0);
  p.passed("orb_slam", 12.05);  // 0.05 s for the SLAM
  p.held(12.1);
  p.passed("renderer", 12.4);  // 0.3 s more for the renderer
  EXPECT_DOUBLE_EQ(p.startup_s(), 1.5);
  EXPECT_EQ(p.barriers(), 4u);
  EXPECT_NEAR(p.held_for("renderer"), 0.5, 1e-12);
  EXPECT_NEAR(p.held_for("orb_slam"), 0.05, 1e-12);
  EXPECT_EQ(p.held_for("recorder"), 0.0);
  // 0.2 s simulated in the 1.0 s after start-up, 0.55 s of it held.
  EXPECT_EQ(p.report(0.2, 12.5),
            "0.200 s simulated in 1.00 s of wall time (0.20x real time) after 1.50 s of start-up; 4 barriers, "
            "0.55 s held (55 %): for renderer 0.50 s (2), orb_slam 0.05 s (1); between barriers 0.45 s");
}

TEST(LockstepHoldProfile, ReportsARunThatNeverStarted) {
  const HoldProfile p;
  EXPECT_EQ(p.report(0.0, 5.0),
            "0.000 s simulated in 0.00 s of wall time (-x real time) after 0.00 s of start-up; 0 barriers, 0.00 s "
            "held (- %); between barriers 0.00 s");
}
