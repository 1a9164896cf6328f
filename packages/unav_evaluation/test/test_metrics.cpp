#include <gtest/gtest.h>
#include "unav_common/thrown.hpp"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>

#include "unav_common/temp_dir.hpp"
#include "unav_evaluation/metrics.hpp"

using namespace unav::evaluation;

namespace {

// A 3D figure-eight with changing attitude, 10 Hz for 20 s.
Trajectory ground_truth() {
  Trajectory t;
  for (int i = 0; i < 200; ++i) {
    const double s = 0.1 * i;
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.translation() = Eigen::Vector3d(5 * std::sin(0.3 * s), 3 * std::sin(0.6 * s), 10 + 0.5 * std::cos(0.2 * s));
    T.linear() = (Eigen::AngleAxisd(0.3 * s, Eigen::Vector3d::UnitZ()) *
                  Eigen::AngleAxisd(0.1 * std::sin(s), Eigen::Vector3d::UnitX()))
                     .toRotationMatrix();
    t.push_back(100.0 + s, T);
  }
  return t;
}

Eigen::Isometry3d transform(const Sim3& S, const Eigen::Isometry3d& P) {
  Eigen::Isometry3d out = P;
  out.translation() = S.R * (S.s * P.translation()) + S.t;
  out.linear() = S.R * P.linear();
  return out;
}

std::string write_temp(const std::string& name, const std::string& text) {
  std::string p = ::testing::TempDir() + name;
  std::ofstream(p) << text;
  return p;
}

}  // namespace

TEST(Umeyama, RecoversKnownSim3Exactly) {
  Sim3 truth;
  truth.R = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  truth.t = Eigen::Vector3d(4, -2, 9);
  truth.s = 2.5;
  std::mt19937 rng(1);
  std::normal_distribution<double> n(0, 3);
  Eigen::Matrix3Xd src(3, 50), dst(3, 50);
  for (int i = 0; i < 50; ++i) {
    src.col(i) = Eigen::Vector3d(n(rng), n(rng), n(rng));
    dst.col(i) = truth.s * truth.R * src.col(i) + truth.t;
  }
  const Sim3 est = umeyama(src, dst, true);
  // Noise-free correspondences: the closed form is exact up to round-off (~1e-12).
  EXPECT_NEAR((est.R - truth.R).norm(), 0.0, 1e-10);
  EXPECT_NEAR((est.t - truth.t).norm(), 0.0, 1e-9);
  EXPECT_NEAR(est.s, truth.s, 1e-10);
  const Sim3 rigid = umeyama(src, dst, false);
  EXPECT_DOUBLE_EQ(rigid.s, 1.0);
  EXPECT_NEAR((rigid.R - truth.R).norm(), 0.0, 1e-10);  // scale does not change the best rotation
}

TEST(Ape, ZeroAfterAligningARigidlyTransformedCopy) {
  const Trajectory gt = ground_truth();
  Sim3 S;
  S.R = Eigen::AngleAxisd(-1.2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  S.t = Eigen::Vector3d(30, 1, -4);
  S.s = 0.37;  // monocular SLAM: arbitrary scale
  Trajectory est = gt;
  for (auto& P : est.poses) P = transform(S, P);
  Trajectory se3 = est;
  align(se3, gt, Alignment::kSE3);
  EXPECT_GT(statistics(ape(gt, se3, PoseRelation::kTranslation)).rmse, 1.0);  // scale not corrected
  align(est, gt, Alignment::kSim3);
  EXPECT_LT(statistics(ape(gt, est, PoseRelation::kTranslation)).max, 1e-9);
  EXPECT_LT(statistics(ape(gt, est, PoseRelation::kRotationAngleRad)).max, 1e-7);
}

TEST(Rpe, ConstantDriftEqualsTheDrift) {
  // The estimate over-shoots every 1-frame step by the same body-frame offset d: the relative
  // motion error of each pair is exactly d, while APE grows.
  const Trajectory gt = ground_truth();
  const Eigen::Vector3d d(0.02, -0.01, 0.005);
  Trajectory est;
  est.push_back(gt.stamps[0], gt.poses[0]);
  for (size_t i = 1; i < gt.size(); ++i) {
    Eigen::Isometry3d step = gt.poses[i - 1].inverse() * gt.poses[i];
    Eigen::Isometry3d drift = Eigen::Isometry3d::Identity();
    drift.translation() = d;
    est.push_back(gt.stamps[i], est.poses.back() * step * drift);
  }
  const Statistics r = statistics(rpe(gt, est, PoseRelation::kTranslation));
  EXPECT_NEAR(r.mean, d.norm(), 1e-12);
  EXPECT_NEAR(r.std, 0.0, 1e-12);
  EXPECT_EQ(r.count, gt.size() - 1);
  EXPECT_NEAR(statistics(rpe(gt, est, PoseRelation::kRotationAngleRad)).max, 0.0, 1e-7);
  EXPECT_GT(statistics(ape(gt, est, PoseRelation::kTranslation)).max, 10 * d.norm());
}

TEST(Rpe, PairsFollowEvo) {
  const Trajectory gt = ground_truth();
  const auto frames = rpe_pairs(gt, {10.0, DeltaUnit::kFrames, false, 0.1});
  ASSERT_EQ(frames.size(), 19u);  // ids 0, 10, ..., 190 -> 19 consecutive pairs
  EXPECT_EQ(frames[1], (std::pair<size_t, size_t>{10, 20}));
  const auto all = rpe_pairs(gt, {10.0, DeltaUnit::kFrames, true, 0.1});
  EXPECT_EQ(all.size(), 190u);
  // Straight line at 0.1 m per pose: 1 m of path is every 10 poses, the first segment end is
  // the first pose whose accumulated path reaches 1 m (index 10).
  Trajectory line;
  for (int i = 0; i < 101; ++i) {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.translation().x() = 0.1 * i + 1e-9 * i;
    line.push_back(i, T);
  }
  const auto meters = rpe_pairs(line, {1.0, DeltaUnit::kMeters, false, 0.1});
  ASSERT_FALSE(meters.empty());
  EXPECT_EQ(meters.front(), (std::pair<size_t, size_t>{10, 20}));
  EXPECT_THROW(rpe_pairs(line, {1000.0, DeltaUnit::kMeters, false, 0.1}), TrajectoryError);
}

TEST(Statistics, MatchNumpy) {
  // numpy: rmse=sqrt(mean(e^2)), std with ddof=0, median of an even count averages the middle.
  const Statistics s = statistics({1.0, 2.0, 3.0, 4.0});
  EXPECT_DOUBLE_EQ(s.mean, 2.5);
  EXPECT_DOUBLE_EQ(s.median, 2.5);
  EXPECT_DOUBLE_EQ(s.rmse, std::sqrt(7.5));
  EXPECT_DOUBLE_EQ(s.std, std::sqrt(1.25));
  EXPECT_DOUBLE_EQ(s.sse, 30.0);
  EXPECT_DOUBLE_EQ(s.min, 1.0);
  EXPECT_DOUBLE_EQ(s.max, 4.0);
}

TEST(Tum, RoundTripAndAssociation) {
  const Trajectory gt = ground_truth();
  const std::string path = ::testing::TempDir() + "gt.tum";
  write_tum(path, gt);
  const Trajectory back = read_tum(path);
  ASSERT_EQ(back.size(), gt.size());
  EXPECT_NEAR((back.poses[57].matrix() - gt.poses[57].matrix()).norm(), 0.0, 1e-8);
  // An estimate at 5 Hz, stamps 3 ms late: associates to every other pose within 10 ms.
  Trajectory est;
  for (size_t i = 0; i < gt.size(); i += 2) est.push_back(gt.stamps[i] + 0.003, gt.poses[i]);
  const auto [ref_a, est_a] = associate(gt, est, 0.01);
  EXPECT_EQ(ref_a.size(), est.size());
  EXPECT_DOUBLE_EQ(ref_a.stamps[3], gt.stamps[6]);
  EXPECT_THROW(associate(gt, est, 0.001), TrajectoryError);  // nothing within 1 ms
}

TEST(Tum, BadFilesGiveLineNumberedErrors) {
  EXPECT_NE(unav::common::thrown_message<TrajectoryError>([&] {
              read_tum(write_temp("cols.tum", "# x\n1 0 0 0 0 0 0 1\n2 0 0 0 0 0 1\n"));
            }).find("cols.tum:3: expected 8 columns"),
            std::string::npos);
  EXPECT_NE(unav::common::thrown_message<TrajectoryError>([&] {
              read_tum(write_temp("time.tum", "2 0 0 0 0 0 0 1\n1 0 0 0 0 0 0 1\n"));
            }).find("time.tum:2"),
            std::string::npos);
  EXPECT_NE(unav::common::thrown_message<TrajectoryError>([&] {
              read_tum(write_temp("nan.tum", "1 nan 0 0 0 0 0 1\n"));
            }).find("nan.tum:1"),
            std::string::npos);
  EXPECT_NE(unav::common::thrown_message<TrajectoryError>([&] {
              read_tum(write_temp("quat.tum", "1 0 0 0 0 0 0 2\n"));
            }).find("quaternion"),
            std::string::npos);
  Trajectory a, b;
  a.push_back(0, Eigen::Isometry3d::Identity());
  b.push_back(50, Eigen::Isometry3d::Identity());
  EXPECT_NE(unav::common::thrown_message<TrajectoryError>([&] { associate(a, b); }).find("do not overlap"),
            std::string::npos);
}

TEST(Tum, RepeatedStampsAreKeptAndAssociatedAsEvoDoes) {
  // The TUM RGB-D benchmark's ground truth repeats stamps; evo keeps every line, and its
  // association (numpy argmin) takes the first of equally near stamps.
  const Trajectory gt = read_tum(write_temp("rep.tum",
                                            "1.0 0 0 0 0 0 0 1\n"
                                            "1.0 5 0 0 0 0 0 1\n"  // same stamp, another pose
                                            "1.1 1 0 0 0 0 0 1\n"
                                            "1.2 2 0 0 0 0 0 1\n"));
  ASSERT_EQ(gt.size(), 4u);
  Trajectory est;
  est.push_back(1.0, Eigen::Isometry3d::Identity());
  est.push_back(1.15, Eigen::Isometry3d::Identity());  // midway: the earlier stamp wins
  est.push_back(1.2, Eigen::Isometry3d::Identity());
  const auto [ref_a, est_a] = associate(gt, est, 0.06);
  ASSERT_EQ(ref_a.size(), 3u);
  EXPECT_DOUBLE_EQ(ref_a.poses[0].translation().x(), 0.0);  // the first of the two 1.0 lines
  EXPECT_DOUBLE_EQ(ref_a.poses[1].translation().x(), 1.0);  // 1.1, not 1.2
  EXPECT_DOUBLE_EQ(ref_a.poses[2].translation().x(), 2.0);
  // A stamp that goes back is an error naming the timestamp column and its value (not qw's).
  const std::string e = unav::common::thrown_message<TrajectoryError>(
      [&] { read_tum(write_temp("back.tum", "2.5 0 0 0 0 0 0 1\n1.25 0 0 0 0 0 0 1\n")); });
  EXPECT_NE(e.find("back.tum:2: column 1 (timestamp): 1.25 is before the previous stamp 2.5"), std::string::npos) << e;
  const std::string c =
      unav::common::thrown_message<TrajectoryError>([&] { read_tum(write_temp("col.tum", "1 0 0 x 0 0 0 1\n")); });
  EXPECT_NE(c.find("col.tum:1: column 4 (tz): 'x' is not a number"), std::string::npos) << c;
}

TEST(Kitti, ReadsPosesPairsByIndexAndChecksRotations) {
  // Pose 1: rotation 90 deg about z, translation (1, 2, 3).
  const Trajectory k = read_kitti(write_temp("p.kitti",
                                             "1 0 0 0 0 1 0 0 0 0 1 0\n"
                                             "0 -1 0 1 1 0 0 2 0 0 1 3\n"));
  ASSERT_EQ(k.size(), 2u);
  EXPECT_DOUBLE_EQ(k.stamps[1], 1.0);  // the index
  EXPECT_NEAR((k.poses[1].translation() - Eigen::Vector3d(1, 2, 3)).norm(), 0.0, 1e-12);
  EXPECT_NEAR((k.poses[1].linear() * Eigen::Vector3d::UnitX() - Eigen::Vector3d::UnitY()).norm(), 0.0, 1e-12);
  const std::string path = ::testing::TempDir() + "rt.kitti";
  write_kitti(path, k);
  const Trajectory back = read_kitti(path);
  EXPECT_NEAR((back.poses[1].matrix() - k.poses[1].matrix()).norm(), 0.0, 1e-8);
  // Hand-computed APE: the estimate is the reference shifted by 0.3 m in x at pose 1 only.
  Trajectory est = k;
  est.poses[1].translation().x() += 0.3;
  const auto [r, e] = pair_by_index(k, est);
  const auto err = ape(r, e, PoseRelation::kTranslation);
  EXPECT_DOUBLE_EQ(err[0], 0.0);
  EXPECT_NEAR(err[1], 0.3, 1e-12);
  Trajectory shorter = k;
  shorter.stamps.pop_back();
  shorter.poses.pop_back();
  EXPECT_NE(
      unav::common::thrown_message<TrajectoryError>([&] { pair_by_index(k, shorter); }).find("same number of poses"),
      std::string::npos);
  EXPECT_NE(unav::common::thrown_message<TrajectoryError>([&] {
              read_kitti(write_temp("r.kitti", "2 0 0 0 0 1 0 0 0 0 1 0\n"));
            }).find("not a rotation"),
            std::string::npos);
  EXPECT_NE(unav::common::thrown_message<TrajectoryError>([&] {
              read_kitti(write_temp("n.kitti", "1 0 0 0 0 1 0 0 0 0 1\n"));
            }).find("expected 12 columns"),
            std::string::npos);
}

TEST(Euroc, ReadsNanosecondsAndWxyzQuaternionsIgnoringExtraColumns) {
  const Trajectory t = read_trajectory(
      write_temp("gt.csv",
                 "#timestamp, p_RS_R_x [m], p_RS_R_y [m], p_RS_R_z [m], q_RS_w [], q_RS_x [], q_RS_y [], q_RS_z [], "
                 "v_RS_R_x [m s^-1]\n"
                 "1403636579758555392,4.688319,-1.786938,0.783338,0.534108,-0.153029,-0.827383,-0.082152,0.1\n"
                 "1403636579763555584,4.688177,-1.786770,0.787350,0.534640,-0.152990,-0.826976,-0.082863,0.1\n"),
      trajectory_format_from_string("euroc"));
  ASSERT_EQ(t.size(), 2u);
  EXPECT_NEAR(t.stamps[0], 1403636579.758555392, 1e-6);
  EXPECT_NEAR(t.stamps[1] - t.stamps[0], 0.005, 1e-6);
  const Eigen::Quaterniond q(t.poses[0].linear());
  EXPECT_NEAR(std::abs(q.w()), 0.534108 / Eigen::Vector4d(0.534108, -0.153029, -0.827383, -0.082152).norm(), 1e-6);
  EXPECT_NEAR(t.poses[0].translation().x(), 4.688319, 1e-12);
  EXPECT_NE(unav::common::thrown_message<TrajectoryError>([&] {
              read_euroc_csv(write_temp("e.csv", "1,2,3\n"));
            }).find("at least 8 columns"),
            std::string::npos);
  EXPECT_THROW(trajectory_format_from_string("bag2"), TrajectoryError);
}

TEST(Timing, AssociationOfTwentyThousandPosesIsFast) {
  // Not a timing assertion: the pairing must be O(n log n); 20k x 20k pairs must all match.
  Trajectory a, b;
  for (int i = 0; i < 20000; ++i) {
    a.push_back(0.01 * i, Eigen::Isometry3d::Identity());
    b.push_back(0.01 * i + 0.001, Eigen::Isometry3d::Identity());
  }
  const auto [ra, rb] = associate(a, b, 0.005);
  EXPECT_EQ(ra.size(), 20000u);
}

// A spooled trajectory gives back exactly what went in (bit for bit: the evaluation's numbers do
// not depend on whether poses were spooled), holds nothing in memory but its count and last stamp,
// and its file is the record until removed.
// A SLAM's bounded path: each path holds only its latest poses, corrected. Every stamp keeps the
// pose the latest path gave it; odometry fills in before the first path's start and after the
// last path's end.
TEST(PathHistory, EveryStampKeepsItsLatestCorrectionAndOdometryFillsTheEnds) {
  auto pose = [](double x) {
    Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
    X.translation().x() = x;
    return X;
  };
  Trajectory odom;  // stamps 0.0 .. 0.9, x = 1 * stamp
  for (int k = 0; k < 10; ++k) odom.push_back(0.1 * k, pose(0.1 * k));
  unav::evaluation::PathHistory h;
  EXPECT_EQ(h.over(odom).size(), 10u);  // no path: the odometry
  Trajectory p1, p2;  // the first path: 0.2 .. 0.5 at x = 2 stamp; the next (bounded): 0.4 .. 0.7 at 3 stamp
  for (int k = 2; k <= 5; ++k) p1.push_back(0.1 * k, pose(0.2 * k));
  for (int k = 4; k <= 7; ++k) p2.push_back(0.1 * k, pose(0.3 * k));
  h.update(p1);
  h.update(p2);
  const Trajectory t = h.over(odom);
  ASSERT_EQ(t.size(), 10u);
  const double want[] = {0.0, 0.1, 0.4, 0.6, 1.2, 1.5, 1.8, 2.1, 0.8, 0.9};
  for (int k = 0; k < 10; ++k) {
    EXPECT_NEAR(t.stamps[static_cast<size_t>(k)], 0.1 * k, 1e-12);
    EXPECT_NEAR(t.poses[static_cast<size_t>(k)].translation().x(), want[k], 1e-12) << "stamp " << 0.1 * k;
  }
}

TEST(TrajectorySpool, GivesBackTheSamePosesBitForBit) {
  unav::common::TempDir dir("spool");
  TrajectorySpool spool(dir.path() + "/gt.bin");
  EXPECT_TRUE(spool.empty());
  EXPECT_TRUE(spool.load().empty());
  EXPECT_FALSE(std::filesystem::exists(spool.path()));  // created at the first pose
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Trajectory in;
  for (int i = 0; i < 5000; ++i) {
    Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
    X.linear() = Eigen::Quaterniond(u(rng), u(rng), u(rng), u(rng)).normalized().toRotationMatrix();
    X.translation() = Eigen::Vector3d(100 * u(rng), 100 * u(rng), 10 * u(rng));
    in.push_back(0.01 * i + 1e-7 * u(rng), X);
    spool.push_back(in.stamps.back(), X);
  }
  EXPECT_EQ(spool.size(), 5000u);
  EXPECT_EQ(spool.last_stamp(), in.stamps.back());
  const Trajectory out = spool.load();
  EXPECT_EQ(std::filesystem::file_size(spool.path()), std::uintmax_t{5000} * 13 * sizeof(double));  // flushed by load()
  ASSERT_EQ(out.size(), in.size());
  for (size_t i = 0; i < in.size(); ++i) {
    ASSERT_EQ(out.stamps[i], in.stamps[i]) << i;
    ASSERT_TRUE(out.poses[i].matrix() == in.poses[i].matrix()) << i;  // exact, not approximately
  }
  spool.push_back(99.0, Eigen::Isometry3d::Identity());  // appending goes on after a load
  EXPECT_EQ(spool.load().size(), 5001u);
  spool.remove();
  EXPECT_TRUE(spool.empty());
  EXPECT_FALSE(std::filesystem::exists(spool.path()));
  TrajectorySpool nowhere("/nonexistent_dir_for_unav/gt.bin");
  try {
    nowhere.push_back(0.0, Eigen::Isometry3d::Identity());
    ADD_FAILURE() << "wrote into a missing folder";
  } catch (const TrajectoryError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent_dir_for_unav/gt.bin: cannot create"), std::string::npos)
        << e.what();
  }
}
