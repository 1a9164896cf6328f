// A throwaway install prefix holding package `fakepkg` with /bin/sh "executables".
#pragma once

#include <sys/stat.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>

#include "unav_common/temp_dir.hpp"

namespace unav::launch::test {

class FakePrefix : public ::testing::Test {
 protected:
  void SetUp() override {
    std::filesystem::create_directories(prefix_ + "/lib/fakepkg");
    write(prefix_ + "/share/fakepkg/package.xml", "<package format=\"3\"><name>fakepkg</name></package>\n");
    ::setenv("AMENT_PREFIX_PATH", prefix_.c_str(), 1);
    ::unsetenv("CMAKE_PREFIX_PATH");
    ::unsetenv("COLCON_PREFIX_PATH");
  }

  static void write(const std::string& path, const std::string& text) {
    std::filesystem::create_directories(std::filesystem::path(path).parent_path());
    std::ofstream(path) << text;
  }

  // lib/fakepkg/<name>: a /bin/sh script with `body`; DIR is the test's temp folder.
  std::string script(const std::string& name, const std::string& body) {
    const std::string path = prefix_ + "/lib/fakepkg/" + name;
    write(path, "#!/bin/sh\nDIR='" + root_ + "'\n" + body + "\n");
    ::chmod(path.c_str(), 0755);
    return path;
  }

  // <root>/<name>.launch.yaml with `text`.
  std::string launch_file(const std::string& name, const std::string& text) {
    const std::string path = root_ + "/" + name + ".launch.yaml";
    write(path, text);
    return path;
  }

  unav::common::TempDir tmp_{"unav_launch_test"};
  const std::string root_ = tmp_.path();
  const std::string prefix_ = root_ + "/install";
};

}  // namespace unav::launch::test
