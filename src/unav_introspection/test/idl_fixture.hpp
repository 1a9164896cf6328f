// Writes small IDL trees into a per-test temporary folder.
#pragma once

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>

namespace unav::introspection::test {

class IdlFixture : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    base_ = std::filesystem::temp_directory_path() /
            ("unav_introspection_" + std::to_string(::getpid()) + "_" + info->test_suite_name() + "_" + info->name());
    std::filesystem::remove_all(base_);
    std::filesystem::create_directories(base_);
  }

  void TearDown() override { std::filesystem::remove_all(base_); }

  /// Writes `text` to `<base>/<root>/<relative>` and returns the root folder.
  std::string write(const std::string& root, const std::string& relative, const std::string& text) {
    const std::filesystem::path path = base_ / root / relative;
    std::filesystem::create_directories(path.parent_path());
    std::ofstream(path) << text;
    return (base_ / root).string();
  }

  std::string path(const std::string& root, const std::string& relative) const {
    return (base_ / root / relative).string();
  }

  /// builtin_interfaces/Time and std_msgs/Header in the style of our IDL files.
  std::string write_std_types(const std::string& root = "idl") {
    write(root, "builtin_interfaces/msg/Time.idl", R"IDL(
module builtin_interfaces { module msg { module dds_ {
  struct Time_ {
    int32 sec;        // [s]
    uint32 nanosec;   // [ns]
  };
}; }; };
)IDL");
    return write(root, "std_msgs/msg/Header.idl", R"IDL(#include "builtin_interfaces/msg/Time.idl"
/* Standard metadata
   for time-stamped data. */
module std_msgs { module msg { module dds_ {
  struct Header_ {
    builtin_interfaces::msg::dds_::Time_ stamp;  // time of the data
    string frame_id;
  };
}; }; };
)IDL");
  }

  std::filesystem::path base_;
};

}  // namespace unav::introspection::test
