// A throwaway install prefix holding package `fakepkg` with /bin/sh "executables".
#pragma once

#include <sys/stat.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>

namespace unav::launch::test {

class FakePrefix : public ::testing::Test {
 protected:
  void SetUp() override {
    char pattern[] = "/tmp/unav_launch_test.XXXXXX";
    ASSERT_NE(::mkdtemp(pattern), nullptr);
    root_ = pattern;
    prefix_ = root_ + "/install";
    std::filesystem::create_directories(prefix_ + "/share/fakepkg");
    std::filesystem::create_directories(prefix_ + "/lib/fakepkg");
    write(prefix_ + "/share/fakepkg/package.xml", "<package format=\"3\"><name>fakepkg</name></package>\n");
    ::setenv("AMENT_PREFIX_PATH", prefix_.c_str(), 1);
    ::unsetenv("CMAKE_PREFIX_PATH");
    ::unsetenv("COLCON_PREFIX_PATH");
  }

  void TearDown() override { std::filesystem::remove_all(root_); }

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

  std::string root_;
  std::string prefix_;
};

}  // namespace unav::launch::test
