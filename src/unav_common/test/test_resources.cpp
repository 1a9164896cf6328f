// Package index (ament_index-like) and resource lookup, on a throwaway folder tree.
#include "unav_common/resources.hpp"

#include <sys/stat.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>

#include "unav_common/errors.hpp"
#include "unav_common/temp_dir.hpp"

namespace uc = unav::common;
using Strings = std::vector<std::string>;

namespace {

class Resources : public ::testing::Test {
 protected:
  void SetUp() override {
    std::filesystem::create_directories(prefix_ + "/share/fakepkg");
    std::filesystem::create_directories(prefix_ + "/lib/fakepkg");
    for (const char* v : {"AMENT_PREFIX_PATH", "CMAKE_PREFIX_PATH", "COLCON_PREFIX_PATH", "UNAV_RESOURCE_PATH"}) {
      if (const char* old = std::getenv(v)) saved_.emplace_back(v, old);
      ::unsetenv(v);
    }
    ::setenv("AMENT_PREFIX_PATH", prefix_.c_str(), 1);
  }
  void TearDown() override {
    for (const char* v : {"AMENT_PREFIX_PATH", "CMAKE_PREFIX_PATH", "COLCON_PREFIX_PATH", "UNAV_RESOURCE_PATH"})
      ::unsetenv(v);
    for (const auto& [k, v] : saved_) ::setenv(k.c_str(), v.c_str(), 1);
  }
  void Write(const std::string& path, const std::string& text = "") const {
    tmp_.write(std::filesystem::path(path).lexically_relative(root_).string(), text);
  }
  static std::string ErrorOf(const std::string& path) {
    try {
      uc::find_resource(path);
    } catch (const unav::ConfigError& e) {
      return e.what();
    }
    ADD_FAILURE() << "no ConfigError for " << path;
    return "";
  }

  uc::TempDir tmp_{"unav_common_resources"};
  const std::string root_ = tmp_.path(), prefix_ = root_ + "/install";
  std::vector<std::pair<std::string, std::string>> saved_;
};

TEST_F(Resources, PackageIndexSearchesAllPrefixVariables) {
  // Isolated colcon layout: ROOT/pkg/{share,lib}/pkg; merged: ROOT/{share,lib}/pkg.
  Write(root_ + "/iso/isopkg/share/isopkg/package.xml");
  Write(root_ + "/iso/isopkg/lib/isopkg/run");
  ::chmod((root_ + "/iso/isopkg/lib/isopkg/run").c_str(), 0755);
  Write(root_ + "/merged/share/mergedpkg/package.xml");
  Write(root_ + "/merged/lib/mergedpkg/plain");  // not executable
  Write(root_ + "/cm/share/cmpkg/package.xml");
  ::setenv("COLCON_PREFIX_PATH", (root_ + "/iso:" + root_ + "/merged/").c_str(), 1);
  ::setenv("CMAKE_PREFIX_PATH", (root_ + "/cm::" + prefix_).c_str(), 1);

  EXPECT_EQ(uc::find_package_prefix("fakepkg"), prefix_);
  EXPECT_EQ(uc::find_package_share("isopkg"), root_ + "/iso/isopkg/share/isopkg");
  EXPECT_EQ(uc::find_package_share("cmpkg"), root_ + "/cm/share/cmpkg");
  EXPECT_EQ(uc::find_executable("isopkg", "run"), root_ + "/iso/isopkg/lib/isopkg/run");
  EXPECT_EQ(uc::find_package_prefix("mergedpkg"), root_ + "/merged");
  Strings searched;
  EXPECT_FALSE(uc::find_executable("mergedpkg", "plain", &searched));
  EXPECT_EQ(searched, Strings{root_ + "/merged/lib/mergedpkg"});
  EXPECT_FALSE(uc::find_package_prefix("absent"));
  EXPECT_FALSE(uc::find_package_prefix("a/b"));
  EXPECT_FALSE(uc::find_executable("fakepkg", "../fakepkg/talker"));
  EXPECT_EQ(uc::package_search_prefixes("x"), (Strings{prefix_, root_ + "/cm", root_ + "/iso/x", root_ + "/iso",
                                                       root_ + "/merged/x", root_ + "/merged"}));
}

TEST_F(Resources, FindResourceSearchesResourcePathThenUnavResources) {
  const std::string share = root_ + "/ws_install/unav_resources/share/unav_resources";
  Write(share + "/config/controllers/mpc.yaml", "horizon_steps: 20\n");
  Write(share + "/worlds/pipe_inspection/world.yaml");
  Write(root_ + "/overlay/config/controllers/mpc.yaml", "horizon_steps: 5\n");
  ::setenv("COLCON_PREFIX_PATH", (root_ + "/ws_install").c_str(), 1);

  // Installed data only.
  EXPECT_EQ(uc::resource_roots(), Strings{share});
  EXPECT_EQ(uc::find_resource("config/controllers/mpc.yaml"), share + "/config/controllers/mpc.yaml");
  EXPECT_EQ(uc::find_resource("worlds/pipe_inspection/world.yaml"), share + "/worlds/pipe_inspection/world.yaml");
  EXPECT_EQ(uc::find_resource("config"), share + "/config");  // what the nodes' config_root() was
  EXPECT_EQ(uc::find_resource("./config/../config/controllers/mpc.yaml"), share + "/config/controllers/mpc.yaml");

  // UNAV_RESOURCE_PATH roots come first, in order; files missing there fall through.
  ::setenv("UNAV_RESOURCE_PATH", (root_ + "/nothing_here:" + root_ + "/overlay/").c_str(), 1);
  EXPECT_EQ(uc::resource_roots(), (Strings{root_ + "/nothing_here", root_ + "/overlay", share}));
  EXPECT_EQ(uc::find_resource("config/controllers/mpc.yaml"), root_ + "/overlay/config/controllers/mpc.yaml");
  EXPECT_EQ(uc::find_resource("worlds/pipe_inspection/world.yaml"), share + "/worlds/pipe_inspection/world.yaml");

  // Absolute paths: as they are when they exist.
  const std::string abs = root_ + "/overlay/config/controllers/mpc.yaml";
  EXPECT_EQ(uc::find_resource(abs), abs);
  EXPECT_EQ(uc::try_find_resource(abs + ".missing"), std::nullopt);
  EXPECT_EQ(ErrorOf(abs + ".missing"), "resource = " + abs + ".missing: the file does not exist");

  // Not found: the error names the path and every place looked at.
  EXPECT_EQ(uc::try_find_resource("config/nope.yaml"), std::nullopt);
  EXPECT_EQ(ErrorOf("config/nope.yaml"), "resource = config/nope.yaml: not found; looked in: " + root_ +
                                             "/nothing_here/config/nope.yaml, " + root_ +
                                             "/overlay/config/nope.yaml, " + share + "/config/nope.yaml");
  EXPECT_THROW(uc::find_resource(""), unav::ConfigError);
}

TEST_F(Resources, FindResourceSaysWhenUnavResourcesIsNotInstalled) {
  EXPECT_TRUE(uc::resource_roots().empty());
  const std::string e = ErrorOf("config/controllers/mpc.yaml");
  EXPECT_EQ(e,
            "resource = config/controllers/mpc.yaml: not found; looked in: nothing (unav_resources is not "
            "installed: source install/setup.bash or set UNAV_RESOURCE_PATH)");
  Write(root_ + "/data/config/a.yaml");
  ::setenv("UNAV_RESOURCE_PATH", (root_ + "/data").c_str(), 1);
  EXPECT_EQ(uc::find_resource("config/a.yaml"), root_ + "/data/config/a.yaml");
  EXPECT_NE(ErrorOf("config/b.yaml").find(root_ + "/data/config/b.yaml"), std::string::npos);
}

}  // namespace
