#include <gtest/gtest.h>

#include "interface_checks.hpp"

#include "unav_msgs/msg/ThrusterCommandPubSubTypes.h"
#include "unav_msgs/msg/ThrusterStatePubSubTypes.h"

using interface_checks::deserialize;
using interface_checks::serialize;

TEST(UnavMsgs, EveryTypeHasRos2NameAndRoundTrips) { interface_checks::check_all_types_round_trip(); }

TEST(UnavMsgs, ThrusterCommandBytes) {
  unav_msgs::msg::dds_::ThrusterCommand_PubSubType type;
  unav_msgs::msg::dds_::ThrusterCommand_ cmd;
  cmd.header().frame_id("");
  cmd.u({0.5, -1.0});
  // 4 encapsulation + Time (8) + empty string (4 + NUL = 5) + pad to 4 (3) + count (4)
  // + pad to 8 relative to the body start (body offset 20 -> 24: 4) + 2 doubles.
  const auto bytes = serialize(type, &cmd);
  ASSERT_EQ(bytes.size(), 4u + 8u + 5u + 3u + 4u + 4u + 16u);
  double first = 0.0;
  std::memcpy(&first, bytes.data() + 4 + 24, sizeof(double));
  EXPECT_EQ(first, 0.5);
  unav_msgs::msg::dds_::ThrusterCommand_ back;
  deserialize(type, bytes, &back);
  EXPECT_EQ(back.u(), cmd.u());
}

TEST(UnavMsgs, ThrusterStateRoundTrip) {
  unav_msgs::msg::dds_::ThrusterState_PubSubType type;
  unav_msgs::msg::dds_::ThrusterState_ s;
  s.commanded({1.0, 0.0, -0.5});
  s.filtered({0.63, 0.0, -0.3});
  s.thrust({40.0, 0.0, -20.0});
  unav_msgs::msg::dds_::ThrusterState_ back;
  deserialize(type, serialize(type, &s), &back);
  EXPECT_EQ(back.thrust(), s.thrust());
  EXPECT_EQ(back.filtered(), s.filtered());
}
