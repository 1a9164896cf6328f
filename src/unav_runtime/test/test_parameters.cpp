#include <gtest/gtest.h>
#include "unav_common/thrown.hpp"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>

#include "unav_runtime/errors.hpp"
#include "unav_runtime/parameters.hpp"

using namespace unav;

namespace {

std::string write_temp(const std::string& name, const std::string& text) {
  std::string path = ::testing::TempDir() + name;
  std::ofstream(path) << text;
  return path;
}

RosArgs args_with(const std::vector<std::string>& files, const std::vector<ParamOverride>& params = {}) {
  RosArgs a;
  a.params_files = files;
  a.params = params;
  return a;
}

}  // namespace

TEST(Parameters, FileMatchingAndPrecedence) {
  const auto f = write_temp("p1.yaml",
                            "/**:\n  ros__parameters:\n    rate: 1.0\n    frame: base\n"
                            "talker:\n  ros__parameters:\n    rate: 2.0\n    gains: {kp: 3, kd: 0.5}\n"
                            "/rov/talker:\n  ros__parameters:\n    topic: chat\n"
                            "listener:\n  ros__parameters:\n    rate: 9.0\n");
  ParameterOverrides o(args_with({f}, {{"", "frame", "odom"}}), "/rov", "talker");
  ASSERT_NE(o.find("rate"), nullptr);
  EXPECT_EQ(o.find("rate")->value.as<double>(), 2.0);  // node entry after /**
  EXPECT_EQ(o.find("topic")->value.as<std::string>(), "chat");
  EXPECT_EQ(o.find("gains.kp")->value.as<int>(), 3);            // nested maps flatten
  EXPECT_EQ(o.find("frame")->value.as<std::string>(), "odom");  // -p wins
  EXPECT_NE(o.find("frame")->source.find("command line"), std::string::npos);
  o.mark_used("rate");
  EXPECT_EQ(o.unused().size(), 4u);  // frame, gains.kd, gains.kp, topic
}

TEST(Parameters, BadFilesNameTheFile) {
  const std::string missing = unav::common::thrown_message<ConfigError>(
      [] { ParameterOverrides(args_with({"/nonexistent/p.yaml"}), "/", "n"); });
  EXPECT_NE(missing.find("/nonexistent/p.yaml"), std::string::npos) << missing;
  const auto bad = write_temp("bad.yaml", "talker:\n  ros__parameters:\n    rate: [1, 2\n");
  const std::string malformed =
      unav::common::thrown_message<ConfigError>([&] { ParameterOverrides(args_with({bad}), "/", "talker"); });
  EXPECT_NE(malformed.find("bad.yaml"), std::string::npos) << malformed;
  EXPECT_NE(malformed.find("line"), std::string::npos) << malformed;
  const auto layout = write_temp("layout.yaml", "talker:\n  rate: 1\n");
  const std::string wrong_layout =
      unav::common::thrown_message<ConfigError>([&] { ParameterOverrides(args_with({layout}), "/", "talker"); });
  EXPECT_NE(wrong_layout.find("ros__parameters"), std::string::npos) << wrong_layout;
}

// Found by fuzz_params: a key that is a list or a map (YAML's `? [a, b]: v`) escaped as
// YAML::TypedBadConversion; now a ParameterError naming the file, the place and the line.
TEST(Parameters, NonScalarKeysNameTheFileAndLine) {
  const auto top = write_temp("complex_top.yaml", "? [a, b]\n: {ros__parameters: {rate: 1}}\n");
  const std::string e1 =
      unav::common::thrown_message<ConfigError>([&] { ParameterOverrides(args_with({top}), "/", "talker"); });
  EXPECT_NE(e1.find("complex_top.yaml"), std::string::npos) << e1;
  EXPECT_NE(e1.find("at the top level at line 1 is a list"), std::string::npos) << e1;
  const auto inner =
      write_temp("complex_inner.yaml", "talker:\n  ros__parameters:\n    gains:\n      ? {x: 1}\n      : 2\n");
  const std::string e2 =
      unav::common::thrown_message<ConfigError>([&] { ParameterOverrides(args_with({inner}), "/", "talker"); });
  EXPECT_NE(e2.find("complex_inner.yaml"), std::string::npos) << e2;
  EXPECT_NE(e2.find("under 'gains' at line 4 is a map"), std::string::npos) << e2;
}
