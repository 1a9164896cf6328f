#include <gtest/gtest.h>

#include "unav_runtime/errors.hpp"
#include "unav_runtime/names.hpp"
#include "unav_runtime/ros_args.hpp"

using namespace unav;

TEST(Names, ResolveLikeRos2) {
  EXPECT_EQ(resolve_topic_name("imu", "/rov", "physics"), "/rov/imu");
  EXPECT_EQ(resolve_topic_name("/clock", "/rov", "physics"), "/clock");
  EXPECT_EQ(resolve_topic_name("~/state", "/rov", "physics"), "/rov/physics/state");
  EXPECT_EQ(resolve_topic_name("imu", "/", "physics"), "/imu");
  EXPECT_EQ(resolve_topic_name("~/x", "", "n"), "/n/x");
  EXPECT_EQ(normalize_namespace("rov/"), "/rov");
}

TEST(Names, RejectInvalid) {
  EXPECT_THROW(resolve_topic_name("a//b", "/", "n"), NameError);
  EXPECT_THROW(resolve_topic_name("a/b/", "/", "n"), NameError);
  EXPECT_THROW(resolve_topic_name("a b", "/", "n"), NameError);
  EXPECT_THROW(resolve_topic_name("1abc", "/", "n"), NameError);
  EXPECT_THROW(resolve_topic_name("a~b", "/", "n"), NameError);
  EXPECT_THROW(validate_node_name("my/node"), NameError);
  EXPECT_THROW(validate_node_name(""), NameError);
}

TEST(Names, DdsPrefixesAndTypeNames) {
  EXPECT_EQ(to_dds_topic("/rov/imu"), "rt/rov/imu");
  EXPECT_EQ(from_dds_topic("rt/rov/imu"), "/rov/imu");
  EXPECT_EQ(from_dds_topic("ros_discovery_info"), "ros_discovery_info");
  EXPECT_EQ(ros_type_from_dds("sensor_msgs::msg::dds_::Image_"), "sensor_msgs/msg/Image");
  EXPECT_EQ(dds_type_from_ros("sensor_msgs/msg/Image"), "sensor_msgs::msg::dds_::Image_");
  EXPECT_EQ(dds_type_from_ros("sensor_msgs/Image"), "sensor_msgs::msg::dds_::Image_");
}

TEST(Names, RemapsApplyToResolvedNames) {
  std::vector<RemapRule> rules = {{"", "chatter", "/rov/chat"}, {"other", "imu", "/x"}};
  EXPECT_EQ(apply_remaps("/ns/chatter", rules, "/ns", "talker"), "/rov/chat");
  EXPECT_EQ(apply_remaps("/ns/imu", rules, "/ns", "talker"), "/ns/imu");  // rule for another node
  EXPECT_EQ(apply_remaps("/ns/imu", rules, "/ns", "other"), "/x");
}

TEST(RosArgs, ParsesRos2Syntax) {
  const RosArgs a = parse_ros_args(std::vector<std::string>{
      "exe", "pos", "--ros-args", "-p", "rate:=2.5", "-r", "__node:=t", "-r", "__ns:=/rov", "--params-file", "f.yaml",
      "-r", "talker:chatter:=/c", "--log-level", "debug", "-e", "/rov/t", "--", "tail"});
  EXPECT_EQ(a.non_ros_args, (std::vector<std::string>{"exe", "pos", "tail"}));
  ASSERT_EQ(a.params.size(), 1u);
  EXPECT_EQ(a.params[0].name, "rate");
  EXPECT_EQ(a.params[0].value, "2.5");
  EXPECT_EQ(a.node_name, "t");
  EXPECT_EQ(a.node_namespace, "/rov");
  EXPECT_EQ(a.params_files, std::vector<std::string>{"f.yaml"});
  ASSERT_EQ(a.remaps.size(), 1u);
  EXPECT_EQ(a.remaps[0].node, "talker");
  EXPECT_EQ(a.remaps[0].from, "chatter");
  EXPECT_EQ(a.log_level, "debug");
  EXPECT_EQ(a.enclave, "/rov/t");
  EXPECT_EQ(parse_ros_args(std::vector<std::string>{"exe", "--ros-args", "--enclave", "/x"}).enclave, "/x");
}

TEST(RosArgs, BadArgumentsNameTheArgument) {
  try {
    parse_ros_args(std::vector<std::string>{"exe", "--ros-args", "--bogus"});
    FAIL();
  } catch (const ArgumentError& e) {
    EXPECT_NE(std::string(e.what()).find("--bogus"), std::string::npos);
  }
  EXPECT_THROW(parse_ros_args(std::vector<std::string>{"exe", "--ros-args", "-p", "rate=2"}), ArgumentError);
  EXPECT_THROW(parse_ros_args(std::vector<std::string>{"exe", "--ros-args", "--params-file"}), ArgumentError);
}
