#include <gtest/gtest.h>

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <opencv2/imgcodecs.hpp>

#include <nlohmann/json.hpp>

#include "unav_datagen/dataset_writer.hpp"
#include "unav_datagen/manifest.hpp"

using namespace unav::datagen;

TEST(DatasetWriter, DepthEncodingFollowsTum) {
  EXPECT_EQ(encode_depth(1.0f), 5000);
  EXPECT_EQ(encode_depth(0.0002f), 1);  // 0.2 mm resolution
  EXPECT_EQ(encode_depth(13.0f), 65000);
  EXPECT_EQ(encode_depth(14.0f), 0);  // beyond 13.1 m: not storable, marked missing
  EXPECT_EQ(encode_depth(std::numeric_limits<float>::infinity()), 0);
  EXPECT_EQ(encode_depth(std::nanf("")), 0);
  EXPECT_EQ(encode_depth(-1.0f), 0);
}

TEST(DatasetWriter, WritesTumLayoutThatReadsBack) {
  const std::string root = ::testing::TempDir() + "dataset_test";
  std::filesystem::remove_all(root);
  {
    DatasetWriter w(root);
    w.write_camera({4, 2, 100, 100, 2, 1, {0.1, 0, 0, 0, 0}});
    const std::uint8_t rgb[4 * 2 * 3] = {255, 0, 0, 0, 255, 0, 0,  0,  255, 1,  2,  3,
                                         4,   5, 6, 7, 8,   9, 10, 11, 12,  13, 14, 15};
    const float depth[8] = {1.0f, 2.5f, 0.0f, 3.0f, 1.0f, 1.0f, 1.0f, 13.0f};
    const std::uint8_t seg[8] = {0, 1, 2, 3, 4, 1, 1, 1};
    Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
    X.translation() = Eigen::Vector3d(1, 2, 10);
    w.write_rgb(12.5, 4, 2, rgb);
    w.write_depth(12.5, 4, 2, depth);
    w.write_segmentation(12.5, 4, 2, seg);
    w.write_pose(12.5, X, X);
    w.write_imu(12.501, Eigen::Vector3d(0, 0, 0.1), Eigen::Vector3d(0, 0, -9.81));
    EXPECT_EQ(w.frames(), 1u);
  }
  const cv::Mat rgb = cv::imread(root + "/rgb/12.500000.png", cv::IMREAD_COLOR);
  ASSERT_FALSE(rgb.empty());
  EXPECT_EQ(rgb.at<cv::Vec3b>(0, 0), cv::Vec3b(0, 0, 255));  // red pixel, stored BGR
  const cv::Mat d = cv::imread(root + "/depth/12.500000.png", cv::IMREAD_UNCHANGED);
  ASSERT_EQ(d.type(), CV_16UC1);
  EXPECT_EQ(d.at<std::uint16_t>(0, 1), 12500);  // 2.5 m * 5000
  EXPECT_EQ(d.at<std::uint16_t>(0, 2), 0);
  const cv::Mat s = cv::imread(root + "/segmentation/12.500000.png", cv::IMREAD_UNCHANGED);
  EXPECT_EQ(s.at<std::uint8_t>(0, 3), 3);
  std::ifstream gt(root + "/groundtruth.txt");
  std::string header, line;
  std::getline(gt, header);
  std::getline(gt, line);
  EXPECT_EQ(line, "12.500000000 1.000000000 2.000000000 10.000000000 0.000000000 0.000000000 0.000000000 1.000000000");
  std::ifstream rgb_txt(root + "/rgb.txt");
  std::getline(rgb_txt, header);
  std::getline(rgb_txt, line);
  EXPECT_EQ(line, "12.500000000 rgb/12.500000.png");
}

TEST(DatasetWriter, UnwritableRootIsAnError) {
  try {
    DatasetWriter w("/proc/unav_cannot_write_here");
    FAIL();
  } catch (const DatasetError& e) {
    EXPECT_NE(std::string(e.what()).find("/proc/unav_cannot_write_here"), std::string::npos);
  }
}

// ---------------------------------------------------------------- EuRoC and KITTI layouts

namespace {

std::vector<std::string> lines_of(const std::string& path) {
  std::ifstream f(path);
  std::vector<std::string> out;
  for (std::string l; std::getline(f, l);) out.push_back(l);
  return out;
}

std::vector<double> numbers_of(const std::string& line, char sep) {
  std::vector<double> v;
  std::stringstream ss(line);
  for (std::string tok; std::getline(ss, tok, sep);)
    if (!tok.empty()) v.push_back(std::stod(tok));
  return v;
}

Eigen::Isometry3d pose(double yaw, const Eigen::Vector3d& p) {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear() = (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitX()))
                   .toRotationMatrix();
  X.translation() = p;
  return X;
}

// A 3-frame flight at 10 Hz with 200 Hz IMU; the camera looks down from 0.16 m ahead.
struct Flight {
  static constexpr int kW = 4, kH = 2;
  std::uint8_t rgb[kW * kH * 3] = {255, 0,  0,  0, 255, 0, 0, 0, 255, 255, 255, 255,
                                   10,  20, 30, 0, 0,   0, 1, 2, 3,   9,   9,   9};
  float depth[kW * kH] = {1.0f, 2.5f, 0.0f, 70.0f, 1.0f, 1.0f, 1.0f, 13.0f};
  std::uint8_t seg[kW * kH] = {0, 1, 2, 3, 4, 1, 1, 1};
  Eigen::Isometry3d X_BC = pose(0.0, Eigen::Vector3d(0.16, 0.0, 0.1));
  CameraIntrinsics k{kW, kH, 100.0, 101.0, 1.5, 0.5, {0, 0, 0, 0, 0}};
  Eigen::Isometry3d X_WB(int i) const { return pose(0.3 * i, Eigen::Vector3d(1.0 + i, -2.0 + 0.5 * i, 8.0)); }
  double t(int i) const { return 1.0 + 0.1 * i; }
  void record(SequenceWriter* w, const std::vector<int>& frames_with_pose = {0, 1, 2}) const {
    w->write_camera(k);
    w->set_camera_mount(X_BC);
    for (int j = 0; j <= 40; ++j)
      w->write_imu(1.0 + 0.005 * j, Eigen::Vector3d(0, 0, 0.1), Eigen::Vector3d(0, 0, -9.81));
    for (int i = 0; i < 3; ++i) {
      // Depth and labels arrive on their own topics: frame 1's before its colour image.
      if (i == 1) w->write_depth(t(i), kW, kH, depth);
      w->write_rgb(t(i), kW, kH, rgb);
      if (i != 1) w->write_depth(t(i), kW, kH, depth);
      w->write_segmentation(t(i), kW, kH, seg);
      if (std::find(frames_with_pose.begin(), frames_with_pose.end(), i) != frames_with_pose.end())
        w->write_pose(t(i), X_WB(i) * X_BC, X_WB(i));
    }
    w->close();
  }
};

}  // namespace

TEST(EurocWriter, WritesTheAslLayoutWithNanosecondStampsAndSensorYamls) {
  const std::string root = ::testing::TempDir() + "euroc_test";
  std::filesystem::remove_all(root);
  Flight f;
  auto w = make_sequence_writer("euroc", root);
  f.record(w.get());
  EXPECT_EQ(w->frames(), 3u);
  EXPECT_TRUE(w->warnings().empty());
  const auto cam = lines_of(root + "/mav0/cam0/data.csv");
  ASSERT_EQ(cam.size(), 4u);
  EXPECT_EQ(cam[0], "#timestamp [ns],filename");
  EXPECT_EQ(cam[2], "1100000000,1100000000.png");
  // Grey images: OpenCV's RGB -> grey weights (0.299, 0.587, 0.114): red 255 -> 76.
  const cv::Mat img = cv::imread(root + "/mav0/cam0/data/1100000000.png", cv::IMREAD_UNCHANGED);
  ASSERT_EQ(img.type(), CV_8UC1);
  EXPECT_EQ(img.at<std::uint8_t>(0, 0), 76);
  EXPECT_EQ(img.at<std::uint8_t>(0, 3), 255);
  const auto imu = lines_of(root + "/mav0/imu0/data.csv");
  ASSERT_EQ(imu.size(), 42u);
  const auto imu1 = numbers_of(imu[1], ',');
  ASSERT_EQ(imu1.size(), 7u);
  EXPECT_EQ(imu1[0], 1e9);
  EXPECT_DOUBLE_EQ(imu1[6], -9.81);
  // Ground truth: body pose, quaternion w first.
  const auto gt = lines_of(root + "/mav0/state_groundtruth_estimate0/data.csv");
  ASSERT_EQ(gt.size(), 4u);
  const auto g2 = numbers_of(gt[3], ',');
  ASSERT_EQ(g2.size(), 8u);
  EXPECT_EQ(g2[0], 1.2e9);
  const Eigen::Quaterniond q2(f.X_WB(2).linear());
  EXPECT_NEAR(g2[1], 3.0, 1e-9);
  EXPECT_NEAR(g2[2], -1.0, 1e-9);
  EXPECT_NEAR(std::abs(g2[4] * q2.w() + g2[5] * q2.x() + g2[6] * q2.y() + g2[7] * q2.z()), 1.0, 1e-8);
  // sensor.yaml: the mount, the measured rates, the intrinsics.
  const YAML::Node c = YAML::LoadFile(root + "/mav0/cam0/sensor.yaml");
  const auto T = c["T_BS"]["data"].as<std::vector<double>>();
  ASSERT_EQ(T.size(), 16u);
  for (int r = 0; r < 4; ++r)
    for (int col = 0; col < 4; ++col) EXPECT_NEAR(T[4 * r + col], f.X_BC.matrix()(r, col), 1e-12);
  EXPECT_NEAR(c["rate_hz"].as<double>(), 10.0, 1e-9);
  EXPECT_EQ(c["intrinsics"].as<std::vector<double>>(), (std::vector<double>{100.0, 101.0, 1.5, 0.5}));
  EXPECT_EQ(c["resolution"].as<std::vector<int>>(), (std::vector<int>{4, 2}));
  EXPECT_NEAR(YAML::LoadFile(root + "/mav0/imu0/sensor.yaml")["rate_hz"].as<double>(), 200.0, 1e-9);
}

TEST(KittiWriter, PosesAreCameraPosesInTheFirstCameraFrameOnePerImage) {
  const std::string root = ::testing::TempDir() + "kitti_test";
  std::filesystem::remove_all(root);
  Flight f;
  auto w = make_sequence_writer("kitti", root);
  f.record(w.get());
  EXPECT_TRUE(w->warnings().empty());
  const auto times = lines_of(root + "/sequences/00/times.txt");
  ASSERT_EQ(times.size(), 3u);
  EXPECT_NEAR(std::stod(times[2]), 0.2, 1e-6);
  const auto calib = numbers_of(lines_of(root + "/sequences/00/calib.txt")[0].substr(4), ' ');
  EXPECT_EQ(calib, (std::vector<double>{100.0, 0, 1.5, 0, 0, 101.0, 0.5, 0, 0, 0, 1, 0}));
  ASSERT_EQ(cv::imread(root + "/sequences/00/image_0/000002.png", cv::IMREAD_UNCHANGED).type(), CV_8UC1);
  const auto poses = lines_of(root + "/poses/00.txt");
  ASSERT_EQ(poses.size(), 3u);
  const Eigen::Isometry3d X_C0W = (f.X_WB(0) * f.X_BC).inverse();
  for (int i = 0; i < 3; ++i) {
    const auto v = numbers_of(poses[static_cast<std::size_t>(i)], ' ');
    ASSERT_EQ(v.size(), 12u);
    const Eigen::Matrix4d T = (X_C0W * f.X_WB(i) * f.X_BC).matrix();
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 4; ++c) EXPECT_NEAR(v[static_cast<std::size_t>(4 * r + c)], T(r, c), 1e-8) << i;
  }
  EXPECT_NEAR(numbers_of(poses[0], ' ')[0], 1.0, 1e-12);  // the first camera is the origin
}

TEST(KittiWriter, AnImageWithoutGroundTruthEndsThePosesAndIsReported) {
  const std::string root = ::testing::TempDir() + "kitti_gap_test";
  std::filesystem::remove_all(root);
  Flight f;
  f.k.distortion = {0.1, 0, 0, 0, 0};
  auto w = make_sequence_writer("kitti", root);
  f.record(w.get(), {0, 2});
  EXPECT_EQ(lines_of(root + "/poses/00.txt").size(), 1u) << "line i must stay image i's";
  const auto warn = w->warnings();
  ASSERT_EQ(warn.size(), 3u);
  EXPECT_NE(warn[0].find("2 of 3 images have no ground-truth pose"), std::string::npos) << warn[0];
  EXPECT_NE(warn[2].find("lens distortion"), std::string::npos) << warn[2];
}

TEST(SequenceWriter, UnknownFormatNamesTheValidOnes) {
  try {
    make_sequence_writer("rosbag", ::testing::TempDir() + "x");
    FAIL() << "no error";
  } catch (const DatasetError& e) {
    EXPECT_NE(std::string(e.what()).find("'rosbag' (valid: tum, euroc, kitti)"), std::string::npos) << e.what();
  }
}

// Depth in millimetres and class ids next to the images, named like them (EuRoC: by stamp;
// KITTI: by image index, also when the depth image arrived before its colour image).
TEST(SequenceWriter, DepthAndLabelsBesideTheImagesInEurocAndKitti) {
  Flight f;
  const std::string e = ::testing::TempDir() + "euroc_depth_test", k = ::testing::TempDir() + "kitti_depth_test";
  std::filesystem::remove_all(e);
  std::filesystem::remove_all(k);
  auto we = make_sequence_writer("euroc", e);
  f.record(we.get());
  auto wk = make_sequence_writer("kitti", k);
  f.record(wk.get());
  for (const std::string& path : {e + "/mav0/depth0/data/1100000000.png", k + "/sequences/00/depth_0/000001.png"}) {
    const cv::Mat d = cv::imread(path, cv::IMREAD_UNCHANGED);
    ASSERT_EQ(d.type(), CV_16UC1) << path;
    EXPECT_EQ(d.at<std::uint16_t>(0, 1), 2500) << path;   // 2.5 m in mm
    EXPECT_EQ(d.at<std::uint16_t>(0, 3), 0) << path;      // 70 m: beyond 65.535 m
    EXPECT_EQ(d.at<std::uint16_t>(1, 3), 13000) << path;  // 13 m: storable in mm (not in TUM units)
  }
  for (const std::string& path : {e + "/mav0/seg0/data/1200000000.png", k + "/sequences/00/seg_0/000002.png"}) {
    const cv::Mat s = cv::imread(path, cv::IMREAD_UNCHANGED);
    ASSERT_EQ(s.type(), CV_8UC1) << path;
    EXPECT_EQ(s.at<std::uint8_t>(0, 3), 3) << path;
  }
  EXPECT_EQ(lines_of(e + "/mav0/depth0/data.csv").size(), 4u);
  const SequenceCounts ck = wk->counts();
  EXPECT_EQ(ck.images, 3u);
  EXPECT_EQ(ck.depth, 3u);
  EXPECT_EQ(ck.segmentation, 3u);
  EXPECT_EQ(ck.poses, 3u);
  EXPECT_EQ(we->counts().imu, 41u);
  EXPECT_TRUE(wk->warnings().empty());
}

TEST(Manifest, Sha256KnownAnswers) {
  // FIPS 180-2 test vectors.
  EXPECT_EQ(sha256_bytes("abc"), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  EXPECT_EQ(sha256_bytes(""), "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
  const std::string p = ::testing::TempDir() + "sha_test.bin";
  std::string big(200000, 'a');  // longer than the 64 KiB read buffer
  std::ofstream(p, std::ios::binary) << big;
  EXPECT_EQ(sha256_file(p), sha256_bytes(big));
  EXPECT_THROW(sha256_file(p + ".missing"), DatasetError);
}

TEST(Manifest, ListsEveryFileWithItsChecksumAndIsReproducible) {
  Flight f;
  ManifestInput in;
  in.camera = "down";
  in.intrinsics = f.k;
  in.mount_known = true;
  in.X_BC = f.X_BC;
  in.source["world"] = "worlds/pipe_inspection/world.yaml";
  in.labels = {{0, "water"}, {2, "pipeline"}};
  std::vector<std::string> manifests;
  for (const std::string name : {"manifest_a", "manifest_b"}) {
    const std::string root = ::testing::TempDir() + name;
    std::filesystem::remove_all(root);
    auto w = make_sequence_writer("tum", root);
    f.record(w.get());
    write_manifest(*w, in);
    std::ifstream mf(root + "/manifest.json");
    std::stringstream ss;
    ss << mf.rdbuf();
    manifests.push_back(ss.str());
    const nlohmann::json m = nlohmann::json::parse(manifests.back());
    EXPECT_EQ(m["format"], "tum");
    EXPECT_FALSE(m["software"]["commit"].get<std::string>().empty());
    EXPECT_EQ(m["counts"]["images"], 3);
    EXPECT_EQ(m["counts"]["poses"], 3);
    EXPECT_EQ(m["counts"]["imu"], 41);
    EXPECT_EQ(m["labels"]["2"], "pipeline");
    EXPECT_EQ(m["depth"]["units_per_metre"], 5000.0);
    EXPECT_NEAR(m["camera"]["mount_xyz_m"][0].get<double>(), 0.16, 1e-12);
    // 3 rgb + 3 depth + 3 segmentation PNGs and the 7 text files, sorted, each checksummed.
    const auto& files = m["files"];
    ASSERT_EQ(files.size(), 16u);
    std::vector<std::string> paths;
    for (const auto& e : files) {
      paths.push_back(e["path"]);
      EXPECT_EQ(e["sha256"], sha256_file(root + "/" + e["path"].get<std::string>())) << e["path"];
      EXPECT_EQ(e["bytes"], std::filesystem::file_size(root + "/" + e["path"].get<std::string>()));
    }
    EXPECT_TRUE(std::is_sorted(paths.begin(), paths.end()));
    EXPECT_EQ(std::count(paths.begin(), paths.end(), "rgb/1.100000.png"), 1);
    EXPECT_EQ(std::count(paths.begin(), paths.end(), "manifest.json"), 0);
  }
  EXPECT_EQ(manifests[0], manifests[1]) << "the same recording must give the same manifest, byte for byte";
}

TEST(Manifest, UsesTheDigestsLoggedAsFilesWereWrittenAndRehashesChangedOnes) {
  // Every PNG of every layout is logged with its size and digest as it is written (so a long
  // recording's manifest does not hash tens of thousands of files at shutdown); the manifest
  // takes those, hashes a file whose size changed since, and removes the log.
  Flight f;
  ManifestInput in;
  in.camera = "down";
  in.intrinsics = f.k;
  for (const std::string layout : {"tum", "euroc", "kitti"}) {
    SCOPED_TRACE(layout);
    const std::string root = ::testing::TempDir() + "digest_log_" + layout;
    std::filesystem::remove_all(root);
    auto w = make_sequence_writer(layout, root);
    f.record(w.get());
    std::ifstream log(root + "/.sha256");
    std::string sha, rel;
    std::uintmax_t bytes = 0;
    std::vector<std::string> logged;
    while (log >> sha >> bytes >> rel) {
      EXPECT_EQ(sha, sha256_file(root + "/" + rel)) << rel;
      EXPECT_EQ(bytes, std::filesystem::file_size(root + "/" + rel)) << rel;
      logged.push_back(rel);
    }
    EXPECT_EQ(logged.size(), 9u);  // 3 images, 3 depth, 3 segmentation
    std::ofstream(root + "/" + logged.front(), std::ios::app) << "changed after it was logged";
    write_manifest(*w, in);
    EXPECT_FALSE(std::filesystem::exists(root + "/.sha256"));
    const nlohmann::json m = nlohmann::json::parse(std::ifstream(root + "/manifest.json"));
    int checked = 0;
    for (const auto& e : m["files"]) {
      const std::string path = root + "/" + e["path"].get<std::string>();
      EXPECT_EQ(e["sha256"], sha256_file(path)) << e["path"];
      ++checked;
    }
    EXPECT_GE(checked, 9);
  }
}
