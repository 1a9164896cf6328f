// The offline inputs' readers: IMU logs (ours and EuRoC's), DVL logs, the camera's mount from a
// dataset manifest; bad lines named by file:line.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include "unav_common/temp_dir.hpp"
#include "unav_common/thrown.hpp"
#include "unav_localization/image_sequence.hpp"

namespace ul = unav::localization;

namespace {

// The test's files, in one folder removed at exit.
std::string write(const std::string& name, const std::string& text) {
  static const unav::common::TempDir dir("unav_aiding_logs");
  return dir.write(name, text);
}

}  // namespace

TEST(AidingLogs, ImuSamplesOfOurLogAndOfEuroc) {
  const auto ours = ul::ReadImuSamples(write("imu.txt",
                                             "# timestamp wx wy wz ax ay az\n"
                                             "0.05 0.1 0.2 0.3 -0.1 0.0 -9.81\n\n"
                                             "0.10 0.0 0.0 0.5 0.2 0.1 -9.80\n"));
  ASSERT_EQ(ours.size(), 2u);
  EXPECT_DOUBLE_EQ(ours[0].stamp, 0.05);
  EXPECT_TRUE(ours[0].gyro.isApprox(Eigen::Vector3d(0.1, 0.2, 0.3)));
  EXPECT_TRUE(ours[1].accel.isApprox(Eigen::Vector3d(0.2, 0.1, -9.80)));
  // EuRoC: nanoseconds, commas, a header line.
  const auto euroc = ul::ReadImuSamples(
      write("euroc_imu.csv",
            "#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],a_RS_S_x [m s^-2],"
            "a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]\n"
            "1403636579758555392,-0.0991,0.1424,0.0258,8.1476,-0.3760,-2.4251\n"
            "1403636579763555584,-0.0991,0.1445,0.0293,8.0332,-0.4086,-2.4414\n"));
  ASSERT_EQ(euroc.size(), 2u);
  EXPECT_NEAR(euroc[1].stamp - euroc[0].stamp, 0.005, 1e-6);  // 200 Hz
  EXPECT_NEAR(euroc[0].accel.x(), 8.1476, 1e-12);
  // Bad lines: named by file and line.
  const std::string e1 =
      unav::common::thrown_message<ul::InputError>([] { ul::ReadImuSamples(write("bad_imu.txt", "0.1 0 0 0 0 0\n")); });
  EXPECT_NE(e1.find("bad_imu.txt:1"), std::string::npos) << e1;
  const std::string e2 = unav::common::thrown_message<ul::InputError>(
      [] { ul::ReadImuSamples(write("back_imu.txt", "0.2 0 0 0 0 0 -9.8\n0.1 0 0 0 0 0 -9.8\n")); });
  EXPECT_NE(e2.find("back_imu.txt:2"), std::string::npos) << e2;
  EXPECT_NE(e2.find("increase"), std::string::npos) << e2;
  const std::string e3 = unav::common::thrown_message<ul::InputError>(
      [] { ul::ReadImuSamples(write("nan_imu.txt", "0.1 0 nan 0 0 0 -9.8\n")); });
  EXPECT_NE(e3.find("nan_imu.txt:1"), std::string::npos) << e3;
  EXPECT_NE(unav::common::thrown_message<ul::InputError>([] {
              ul::ReadImuSamples(::testing::TempDir() + "no_such_imu.txt");
            }).find("cannot be read"),
            std::string::npos);
}

TEST(AidingLogs, EurocImagesAreStampedInSecondsLikeItsImu) {
  // mav0/cam0/data/<ns>.png: seconds, on the clock of ReadImuSamples' EuRoC stamps.
  const std::string dir = ::testing::TempDir() + "euroc_cam0";
  std::filesystem::create_directories(dir);
  for (const char* n : {"1403636579763555584", "1403636579813555456"}) std::ofstream(dir + "/" + n + ".png") << "x";
  const auto seq = ul::ListImages(dir);
  ASSERT_EQ(seq.size(), 2u);
  EXPECT_NEAR(seq[0].stamp, 1403636579.763555584, 1e-6);
  EXPECT_NEAR(seq[1].stamp - seq[0].stamp, 0.05, 1e-6);  // 20 Hz
}

TEST(AidingLogs, DvlReadingsKeepTheirLock) {
  const auto d = ul::ReadDvlSamples(write("dvl.csv",
                                          "# t,valid,vx_mps,vy_mps,vz_mps,altitude_m,locked_beams\n"
                                          "0,1,0.25,-0.01,0.002,1.5,4\n"
                                          "0.1,0,nan,nan,nan,nan,2\n"
                                          "0.2,1,0.26,0.0,0.0,1.5,3\n"));
  ASSERT_EQ(d.size(), 3u);
  EXPECT_TRUE(d[0].valid);
  EXPECT_TRUE(d[0].velocity.isApprox(Eigen::Vector3d(0.25, -0.01, 0.002)));
  EXPECT_FALSE(d[1].valid);
  EXPECT_EQ(d[1].velocity, Eigen::Vector3d::Zero());
  EXPECT_TRUE(d[2].valid);
  const std::string e = unav::common::thrown_message<ul::InputError>(
      [] { ul::ReadDvlSamples(write("bad_dvl.csv", "0,1,nan,0,0,1.5\n")); });
  EXPECT_NE(e.find("bad_dvl.csv:1"), std::string::npos) << e;
}

TEST(AidingLogs, CameraMountFromADatasetManifest) {
  // The down camera of the default vehicle: 0.1 m ahead, 0.12 m below the body origin, looking down.
  const auto X = ul::ReadCameraMount(write("manifest.json",
                                           R"({"camera": {"mount_known": true, "mount_xyz_m": [0.1, 0.0, 0.12],
                "mount_quaternion_xyzw": [0.0, 0.0, 0.7071067811865476, 0.7071067811865476]}})"));
  ASSERT_TRUE(X.has_value());
  EXPECT_TRUE(X->translation().isApprox(Eigen::Vector3d(0.1, 0.0, 0.12)));
  EXPECT_TRUE(X->linear().isApprox(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix(), 1e-12));
  EXPECT_FALSE(ul::ReadCameraMount(write("unknown.json", R"({"camera": {"mount_known": false,
      "mount_xyz_m": [0, 0, 0], "mount_quaternion_xyzw": [0, 0, 0, 1]}})"))
                   .has_value());
  EXPECT_FALSE(ul::ReadCameraMount(write("none.json", R"({"format": "tum"})")).has_value());
  const std::string e = unav::common::thrown_message<ul::InputError>([] {
    ul::ReadCameraMount(
        write("bad.json", R"({"camera": {"mount_xyz_m": [0, 0], "mount_quaternion_xyzw": [0, 0, 0, 1]}})"));
  });
  EXPECT_NE(e.find("bad.json"), std::string::npos) << e;
  EXPECT_NE(e.find("camera.mount_xyz_m"), std::string::npos) << e;
}

TEST(AidingLogs, EurocCameraFolderSensorFileAndMount) {
  // mav0/cam0: data.csv lists the images of data/ by ns stamp; sensor.yaml gives the pinhole and
  // T_BS (the camera in the IMU's body frame), row-major.
  const std::string cam0 = ::testing::TempDir() + "euroc_mav0/cam0";
  std::filesystem::create_directories(cam0 + "/data");
  std::ofstream(cam0 + "/data.csv") << "#timestamp [ns],filename\n0,0.png\n50000000,50000000.png\n";
  for (const char* n : {"0.png", "50000000.png"}) std::ofstream(cam0 + "/data/" + n) << "x";
  const auto seq = ul::ListImages(cam0);
  ASSERT_EQ(seq.size(), 2u);
  EXPECT_DOUBLE_EQ(seq[1].stamp, 0.05);
  EXPECT_EQ(std::filesystem::path(seq[1].path).filename(), "50000000.png");
  const std::string sensor = write("sensor.yaml",
                                   "sensor_type: camera\n"
                                   "T_BS:\n  cols: 4\n  rows: 4\n"
                                   "  data: [0, -1, 0, 0.1,\n          1, 0, 0, 0,\n          0, 0, 1, 0.12,\n"
                                   "          0, 0, 0, 1]\n"
                                   "resolution: [752, 480]\nintrinsics: [458.654, 457.296, 367.215, 248.375]\n"
                                   "distortion_coefficients: [-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05]\n");
  const ul::CameraFile c = ul::LoadCameraFile(sensor);
  EXPECT_EQ(c.camera.width, 752);
  EXPECT_DOUBLE_EQ(c.camera.fy, 457.296);
  EXPECT_DOUBLE_EQ(c.camera.cx, 367.215);
  ASSERT_EQ(c.distortion.size(), 4u);
  const auto X = ul::ReadCameraMount(sensor);
  ASSERT_TRUE(X.has_value());
  EXPECT_TRUE(X->translation().isApprox(Eigen::Vector3d(0.1, 0.0, 0.12)));
  EXPECT_TRUE(X->linear().isApprox(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix(), 1e-12));
  const std::string e = unav::common::thrown_message<ul::InputError>([] {
    ul::ReadCameraMount(write("shear.yaml", "T_BS: {data: [2, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]}\n"));
  });
  EXPECT_NE(e.find("shear.yaml"), std::string::npos) << e;
  EXPECT_NE(e.find("rigid"), std::string::npos) << e;
}
