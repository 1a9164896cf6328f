// `unav_eval` as a user runs it: trajectories straight from a rosbag2 (Odometry, PoseStamped, a
// /tf frame pair), the plot and the saved results, with hand-computed errors.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include <yaml-cpp/yaml.h>
#include <nlohmann/json.hpp>

#include "unav_bag/bag.hpp"
#include "unav_introspection/cdr_codec.hpp"
#include "unav_introspection/type_registry.hpp"

namespace fs = std::filesystem;

namespace {

std::string run(const std::string& args, int* rc) {
  std::string out;
  FILE* p = popen((std::string(UNAV_EVAL_EXE) + " " + args + " 2>&1").c_str(), "r");
  char buf[512];
  while (fgets(buf, sizeof(buf), p)) out += buf;
  *rc = WEXITSTATUS(pclose(p));
  return out;
}

YAML::Node header(double t, const std::string& frame) {
  YAML::Node h;
  h["stamp"]["sec"] = static_cast<int32_t>(t);
  h["stamp"]["nanosec"] = static_cast<uint32_t>(std::lround((t - static_cast<int32_t>(t)) * 1e9));
  h["frame_id"] = frame;
  return h;
}

// A bag with ground truth (Odometry), an estimate (PoseStamped, 0.1 m east of the truth) and the
// truth again on /tf (world_ned -> base_link_frd), 50 poses at 10 Hz along a curve.
std::string make_bag(const std::string& storage) {
  unav::introspection::TypeRegistry reg;
  reg.add_root(ROS2_MSGS_IDL);
  std::string dir = (fs::temp_directory_path() / ("unav_eval_bag_" + storage + std::to_string(::getpid()))).string();
  fs::remove_all(dir);
  unav::bag::BagWriter::Options opt;
  opt.storage_id = storage;
  unav::bag::BagWriter w(dir, opt);
  w.add_topic({"/gt", "nav_msgs/msg/Odometry", "cdr", "", ""});
  w.add_topic({"/est", "geometry_msgs/msg/PoseStamped", "cdr", "", ""});
  w.add_topic({"/tf", "tf2_msgs/msg/TFMessage", "cdr", "", ""});
  for (int i = 0; i < 50; ++i) {
    const double t = 100.0 + 0.1 * i;
    const double x = 0.2 * i, y = std::sin(0.2 * i);
    YAML::Node odom;
    odom["header"] = header(t, "world_ned");
    odom["pose"]["pose"]["position"]["x"] = x;
    odom["pose"]["pose"]["position"]["y"] = y;
    odom["pose"]["pose"]["orientation"]["w"] = 1.0;
    YAML::Node est;
    est["header"] = header(t, "world_ned");
    est["pose"]["position"]["x"] = x;
    est["pose"]["position"]["y"] = y + 0.1;
    est["pose"]["orientation"]["w"] = 1.0;
    YAML::Node tf, tr;
    tr["header"] = header(t, "world_ned");
    tr["child_frame_id"] = "base_link_frd";
    tr["transform"]["translation"]["x"] = x;
    tr["transform"]["translation"]["y"] = y;
    tr["transform"]["rotation"]["w"] = 1.0;
    tf["transforms"].push_back(tr);
    const auto a = unav::introspection::encode(reg.load("nav_msgs/msg/Odometry"), odom);
    const auto b = unav::introspection::encode(reg.load("geometry_msgs/msg/PoseStamped"), est);
    const auto c = unav::introspection::encode(reg.load("tf2_msgs/msg/TFMessage"), tf);
    // Arrival order differs from stamp order for the estimate (it comes late): the reader sorts.
    const auto ns = static_cast<int64_t>(t * 1e9);
    w.write(0, ns, a.data(), a.size());
    w.write(2, ns, c.data(), c.size());
    w.write(1, ns + 300000000, b.data(), b.size());
  }
  w.close();
  return dir;
}

}  // namespace

TEST(EvalTool, ApeFromBagTopicsAndTfPairWithPlotAndResults) {
  for (const char* storage : {"mcap", "sqlite3"}) {
    const std::string bag = make_bag(storage);
    const std::string plot = bag + "_ape.png", results = bag + "_ape.json";
    int rc = 0;
    // Unaligned: every error is the 0.1 m offset.
    std::string out =
        run("ape --format bag " + bag + " /gt /est -a none --plot " + plot + " --save_results " + results, &rc);
    ASSERT_EQ(rc, 0) << out;
    EXPECT_NE(out.find("      rmse\t0.100000"), std::string::npos) << out;
    EXPECT_NE(out.find("(50 pose pairs of 50 reference and 50 estimated poses)"), std::string::npos) << out;
    EXPECT_TRUE(fs::file_size(plot) > 1000);
    const auto j = nlohmann::json::parse(std::ifstream(results));
    EXPECT_NEAR(j["stats"]["rmse"].get<double>(), 0.1, 1e-9);
    ASSERT_EQ(j["errors"].size(), 50u);
    EXPECT_NEAR(j["errors"][7].get<double>(), 0.1, 1e-9);
    EXPECT_NEAR(j["timestamps"][0].get<double>(), 100.0, 1e-9);
    // SE(3)-aligned: the constant offset is removed entirely.
    out = run("ape --format bag " + bag + " /gt /est -a se3", &rc);
    ASSERT_EQ(rc, 0) << out;
    EXPECT_NE(out.find("      rmse\t0.000000"), std::string::npos) << out;
    // The truth from /tf against the truth from the odometry: zero.
    out = run("ape --format bag " + bag + " /tf:world_ned.base_link_frd /gt -a none", &rc);
    ASSERT_EQ(rc, 0) << out;
    EXPECT_NE(out.find("       max\t0.000000"), std::string::npos) << out;
    // RPE over 1 frame: the offset cancels.
    out = run("rpe --format bag " + bag + " /gt /est -a none", &rc);
    ASSERT_EQ(rc, 0) << out;
    EXPECT_NE(out.find("      rmse\t0.000000"), std::string::npos) << out;
    // Errors name what is missing.
    out = run("ape --format bag " + bag + " /gt /nope", &rc);
    EXPECT_EQ(rc, 2);
    EXPECT_NE(out.find("no topic '/nope' (topics: /gt [nav_msgs/msg/Odometry]"), std::string::npos) << out;
    out = run("ape --format bag " + bag + " /tf:world_ned.camera /gt", &rc);
    EXPECT_EQ(rc, 2);
    EXPECT_NE(out.find("frame pairs in the bag: world_ned.base_link_frd"), std::string::npos) << out;
    fs::remove_all(bag);
  }
}

TEST(EvalTool, KittiAndTrajInfo) {
  const std::string dir = ::testing::TempDir();
  std::ofstream(dir + "ref.kitti") << "1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 1 0 1 0 0 0 0 1 0\n1 0 0 2 0 1 0 0 0 0 1 0\n";
  std::ofstream(dir + "est.kitti") << "1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 1 0 1 0 0.3 0 0 1 0\n1 0 0 2 0 1 0 0 0 0 1 0\n";
  int rc = 0;
  // By index, no alignment: errors 0, 0.3, 0 -> rmse = 0.3 / sqrt(3).
  std::string out = run("ape --format kitti " + dir + "ref.kitti " + dir + "est.kitti -a none", &rc);
  ASSERT_EQ(rc, 0) << out;
  EXPECT_NE(out.find("      rmse\t0.173205"), std::string::npos) << out;
  EXPECT_NE(out.find("paired by index"), std::string::npos) << out;
  std::ofstream(dir + "short.kitti") << "1 0 0 0 0 1 0 0 0 0 1 0\n";
  out = run("ape --format kitti " + dir + "ref.kitti " + dir + "short.kitti", &rc);
  EXPECT_EQ(rc, 2);
  EXPECT_NE(out.find("same number of poses"), std::string::npos) << out;
  out = run("traj --format kitti " + dir + "ref.kitti", &rc);
  ASSERT_EQ(rc, 0) << out;
  EXPECT_NE(out.find("\tnr. of poses\t3"), std::string::npos) << out;
  EXPECT_NE(out.find("\tpath length (m)\t2.000000"), std::string::npos) << out;
}
