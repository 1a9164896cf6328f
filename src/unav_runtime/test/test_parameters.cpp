#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>

#include "unav_runtime/errors.hpp"
#include "unav_runtime/parameters.hpp"

using namespace unav;

namespace {

std::string write_temp(const std::string& name, const std::string& text) {
  const std::string path = ::testing::TempDir() + name;
  std::ofstream(path) << text;
  return path;
}

RosArgs args_with(const std::vector<std::string>& files, const std::vector<ParamOverride>& params = {}) {
  RosArgs a;
  a.params_files = files;
  a.params = params;
  return a;
}

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
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
  EXPECT_EQ(parameter_as<double>(o.find("rate")->value, {}, "x"), 2.0);  // node entry after /**
  EXPECT_EQ(parameter_as<std::string>(o.find("topic")->value, {}, "x"), "chat");
  EXPECT_EQ(parameter_as<int64_t>(o.find("gains.kp")->value, {}, "x"), 3);  // nested maps flatten
  EXPECT_EQ(parameter_as<std::string>(o.find("frame")->value, {}, "x"), "odom");  // -p wins
  EXPECT_NE(o.find("frame")->source.find("command line"), std::string::npos);
  o.mark_used("rate");
  EXPECT_EQ(o.unused().size(), 4u);  // frame, gains.kd, gains.kp, topic
}

TEST(Parameters, TypedConversionAndRules) {
  ParameterDescriptor range{"rate [Hz]", 0.1, 100.0, false};
  EXPECT_EQ(parameter_as<double>(YAML::Load("5"), range, "c"), 5.0);  // integers are valid doubles
  EXPECT_EQ(parameter_as<std::vector<double>>(YAML::Load("[1, 2.5]"), {}, "c"), (std::vector<double>{1.0, 2.5}));
  EXPECT_TRUE(parameter_as<bool>(YAML::Load("true"), {}, "c"));
  EXPECT_EQ(parameter_as<std::string>(YAML::Load(""), {}, "c"), "");  // `-p name:=`
  const std::string wrong_type = error_of([&] { parameter_as<double>(YAML::Load("fast"), range, "file 'a.yaml': 'rate'"); });
  EXPECT_NE(wrong_type.find("expected double, got 'fast'"), std::string::npos) << wrong_type;
  EXPECT_NE(wrong_type.find("a.yaml"), std::string::npos);
  EXPECT_NE(error_of([&] { parameter_as<double>(YAML::Load("1000"), range, "c"); }).find("out of range"),
            std::string::npos);
  EXPECT_NE(error_of([&] { parameter_as<double>(YAML::Load(".nan"), {}, "c"); }).find("finite"), std::string::npos);
  EXPECT_NE(error_of([&] { parameter_as<int64_t>(YAML::Load("1.5"), {}, "c"); }).find("expected integer"),
            std::string::npos);
  EXPECT_NE(error_of([&] { parameter_as<bool>(YAML::Load("3"), {}, "c"); }).find("expected bool"), std::string::npos);
  EXPECT_NE(error_of([&] { parameter_as<std::string>(YAML::Load("[1]"), {}, "c"); }).find("expected string"),
            std::string::npos);
  EXPECT_NE(error_of([&] { parameter_as<std::vector<double>>(YAML::Load("[1, x]"), {}, "c"); }).find("c[1]"),
            std::string::npos);
}

TEST(Parameters, BadFilesNameTheFile) {
  const std::string missing = error_of([] { ParameterOverrides(args_with({"/nonexistent/p.yaml"}), "/", "n"); });
  EXPECT_NE(missing.find("/nonexistent/p.yaml"), std::string::npos) << missing;
  const auto bad = write_temp("bad.yaml", "talker:\n  ros__parameters:\n    rate: [1, 2\n");
  const std::string malformed = error_of([&] { ParameterOverrides(args_with({bad}), "/", "talker"); });
  EXPECT_NE(malformed.find("bad.yaml"), std::string::npos) << malformed;
  EXPECT_NE(malformed.find("line"), std::string::npos) << malformed;
  const auto layout = write_temp("layout.yaml", "talker:\n  rate: 1\n");
  const std::string wrong_layout = error_of([&] { ParameterOverrides(args_with({layout}), "/", "talker"); });
  EXPECT_NE(wrong_layout.find("ros__parameters"), std::string::npos) << wrong_layout;
}
