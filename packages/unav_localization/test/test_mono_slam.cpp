// Monocular ORB SLAM: geometry pieces (Sim(3) estimation, pose graph) on analytic cases, then
// the whole system on sequences rendered by our renderer with known motion (slam_flights.hpp,
// rendered by the fixture render_slam_sequences): the down camera over the pipe-inspection
// seabed, a straight run and a closed square loop.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <random>
#include <set>
#include <string>

#include <opencv2/imgproc.hpp>

#include "slam_flights.hpp"
#include "slam_sequences.hpp"
#include "unav_localization/mono_slam.hpp"
#include "unav_localization/orb_extractor.hpp"
#include "unav_localization/sim3.hpp"
#include "unav_localization/slam_optimizer.hpp"

namespace ul = unav::localization;

namespace {

using unav::localization::testing::Rot;
using unav::localization::testing::WeaveFlight;

// Sim(3)-aligned (SE(3) with fix_scale) position RMSE of est against gt (same length, paired by
// index).
double AlignedRmse(const std::vector<Eigen::Vector3d>& gt, const std::vector<Eigen::Vector3d>& est,
                   double* scale = nullptr, bool fix_scale = false) {
  Eigen::Matrix3Xd a(3, static_cast<long>(est.size())), b(3, static_cast<long>(gt.size()));
  for (size_t i = 0; i < est.size(); ++i) {
    a.col(static_cast<long>(i)) = est[i];
    b.col(static_cast<long>(i)) = gt[i];
  }
  ul::Sim3 S;
  if (!ul::EstimateSim3(a, b, fix_scale, &S)) return 1e9;
  if (scale) *scale = S.s;
  double se = 0;
  for (size_t i = 0; i < est.size(); ++i) se += (S * est[i] - gt[i]).squaredNorm();
  return std::sqrt(se / static_cast<double>(est.size()));
}

// A rendered sequence (the fixture's file `name`): images gray, frame k at t = 0.1 k, X_WC the
// camera's true poses. The images these tests were written against: Lambertian, flat, clean. With
// the renderer's materials (relief shaded under the vehicle's moving lamps, highlights, sediment)
// every test here passes on the rendered images as they are (2026-11-27), but the forward camera
// at 1.5 m/s (pitch 35) tracks only 30-60 local-map inliers a frame (mean 46; 65 without
// materials) against the 30 it needs: with 2 % of the pixels moved by one grey level it lost
// track on 7 of 8 seeds, re-initialised (no vocabulary here) and ended 0.1-0.7 m APE. Without
// materials: 0 lost on 10 seeds. A harder image the SLAM does not handle yet (its map is thin
// under fast forward motion), not what these geometry tests are about.
struct RenderedRun {
  std::vector<cv::Mat> gray;
  std::vector<double> stamps;
  std::vector<Eigen::Isometry3d> X_WC;  ///< camera optical frame in world
  Eigen::Matrix3d K;
};

RenderedRun Load(const std::string& name) {
  auto s = unav::localization::testing::load_sequence(name);
  return RenderedRun{std::move(s.images), std::move(s.stamps), std::move(s.X_WC), s.K};
}

// Feeds every frame; returns the first frame tracked (-1: never) and how many frames were lost.
std::pair<int, int> TrackAll(ul::MonoSlam& slam, const RenderedRun& run) {
  int first_tracked = -1, lost = 0;
  for (size_t k = 0; k < run.gray.size(); ++k) {
    const auto s = slam.Track(run.gray[k], run.stamps[k]);
    if (s.state == ul::SlamState::kTracking && first_tracked < 0) first_tracked = static_cast<int>(k);
    if (s.state == ul::SlamState::kLost) ++lost;
  }
  return {first_tracked, lost};
}

ul::PinholeCamera Pinhole(const Eigen::Matrix3d& K, int width = 640, int height = 480) {
  return ul::PinholeCamera::FromK(K, width, height);
}

// APE (Sim(3)-aligned) of a SLAM run against the rendered ground truth, matched by stamp.
double Ape(const ul::MonoSlam& slam, const RenderedRun& run, size_t* n_poses, double* path) {
  std::vector<Eigen::Vector3d> gt, est;
  *path = 0;
  for (size_t k = 1; k < run.X_WC.size(); ++k)
    *path += (run.X_WC[k].translation() - run.X_WC[k - 1].translation()).norm();
  for (const auto& p : slam.Trajectory()) {
    const size_t k = static_cast<size_t>(std::lround(p.stamp / 0.1));
    gt.push_back(run.X_WC[k].translation());
    est.push_back(p.T_wc.translation());
  }
  *n_poses = est.size();
  return est.size() < 3 ? 1e9 : AlignedRmse(gt, est);
}

}  // namespace

TEST(Sim3, UmeyamaRecoversAKnownSimilarity) {
  std::mt19937 rng(3);
  std::normal_distribution<double> n(0.0, 2.0);
  const ul::Sim3 S_true(2.5, Rot(0.3, -0.2, 1.1), Eigen::Vector3d(1, -2, 0.5));
  Eigen::Matrix3Xd from(3, 20), to(3, 20);
  for (int i = 0; i < 20; ++i) {
    from.col(i) = Eigen::Vector3d(n(rng), n(rng), n(rng));
    to.col(i) = S_true * Eigen::Vector3d(from.col(i));
  }
  ul::Sim3 S;
  ASSERT_TRUE(ul::EstimateSim3(from, to, false, &S));
  EXPECT_NEAR(S.s, 2.5, 1e-10);
  EXPECT_LT((S.R - S_true.R).norm(), 1e-10);
  EXPECT_LT((S.t - S_true.t).norm(), 1e-9);
  // Composition and inverse are consistent.
  const Eigen::Vector3d x(0.3, 0.2, -1);
  EXPECT_LT(((S.inverse() * S) * x - x).norm(), 1e-12);
  // Collinear points are refused.
  Eigen::Matrix3Xd line(3, 4);
  line << 0, 1, 2, 3, 0, 1, 2, 3, 0, 1, 2, 3;
  EXPECT_FALSE(ul::EstimateSim3(line, line, false, &S));
}

TEST(OrbExtractor, SpreadsFeaturesOverWeakTexture) {
  // Texture whose contrast fades from 100 % on the left to 30 % on the right (like sand under a
  // lamp's falloff). Plain ORB keeps its strongest corners, crowded on the left; the grid
  // selection over ORB's (3x) candidates covers more of the image. It can only choose among
  // those candidates: the faintest third stays nearly empty for both (seen: 0.00 and 0.01).
  cv::Mat noise(480, 640, CV_8UC1), img;
  cv::RNG rng(7);
  rng.fill(noise, cv::RNG::UNIFORM, 0, 255);
  cv::GaussianBlur(noise, img, cv::Size(0, 0), 1.5);
  for (int x = 0; x < img.cols; ++x) {
    const double c = 1.0 - 0.7 * x / (img.cols - 1.0);
    img.col(x).convertTo(img.col(x), CV_8U, c, 128 * (1 - c));
  }
  auto coverage = [](const std::vector<cv::KeyPoint>& k) {  // share of 32 px cells with a feature
    std::set<int> cells;
    for (const auto& p : k) cells.insert(static_cast<int>(p.pt.y) / 32 * 20 + static_cast<int>(p.pt.x) / 32);
    return static_cast<double>(cells.size()) / (15 * 20);
  };
  auto right_share = [](const std::vector<cv::KeyPoint>& k) {
    return static_cast<double>(std::count_if(k.begin(), k.end(), [](const cv::KeyPoint& p) { return p.pt.x >= 427; })) /
           k.size();
  };
  std::vector<cv::KeyPoint> plain, ours;
  cv::ORB::create(1000)->detect(img, plain);
  cv::Mat desc;
  ul::OrbExtractor().Extract(img, &ours, &desc);
  std::printf("cells covered: plain ORB %.2f, grid %.2f; right third: plain %.2f, grid %.2f\n", coverage(plain),
              coverage(ours), right_share(plain), right_share(ours));
  EXPECT_EQ(desc.rows, static_cast<int>(ours.size()));
  EXPECT_EQ(desc.cols, 32);
  EXPECT_GE(ours.size(), 900u);
  EXPECT_GT(coverage(ours), coverage(plain) + 0.1);
  EXPECT_THROW(ul::OrbExtractor(ul::OrbOptions{10}), std::invalid_argument);

  // Rotation invariance: the image turned by 30 deg about its centre; a feature's best
  // descriptor match lands where the rotation maps it for most confident matches.
  cv::Mat tex;
  cv::GaussianBlur(noise, tex, cv::Size(0, 0), 1.5);
  const cv::Mat R = cv::getRotationMatrix2D(cv::Point2f(320, 240), 30.0, 1.0);
  cv::Mat rotated;
  cv::warpAffine(tex, rotated, R, tex.size(), cv::INTER_LINEAR, cv::BORDER_REFLECT);
  std::vector<cv::KeyPoint> k0, k1;
  cv::Mat d0, d1;
  const ul::OrbExtractor ex;
  ex.Extract(tex, &k0, &d0);
  ex.Extract(rotated, &k1, &d1);
  int confident = 0, correct = 0;
  for (int i = 0; i < d0.rows; ++i) {
    int best = 256, bj = -1;
    for (int j = 0; j < d1.rows; ++j) {
      const int d = ul::DescriptorDistance(d0.ptr<uint8_t>(i), d1.ptr<uint8_t>(j));
      if (d < best) {
        best = d;
        bj = j;
      }
    }
    if (best > 40) continue;
    ++confident;
    const cv::Point2f p = k0[static_cast<size_t>(i)].pt;
    const cv::Point2f q(static_cast<float>(R.at<double>(0, 0) * p.x + R.at<double>(0, 1) * p.y + R.at<double>(0, 2)),
                        static_cast<float>(R.at<double>(1, 0) * p.x + R.at<double>(1, 1) * p.y + R.at<double>(1, 2)));
    correct +=
        cv::norm(q - k1[static_cast<size_t>(bj)].pt) < 3.0 * (1 << std::max(0, k1[static_cast<size_t>(bj)].octave / 2))
            ? 1
            : 0;
  }
  std::printf("rotated 30 deg: %d confident matches, %d at the right place\n", confident, correct);
  EXPECT_GT(confident, 200);
  EXPECT_GT(correct, 0.9 * confident);
}

TEST(PoseGraph, LoopEdgeRemovesAccumulatedDrift) {
  // 40 keyframes on a circle; odometry edges exact but the initial guess accumulates a yaw and
  // scale drift; one loop edge (39 -> 0) with the true relative pose. After optimisation the
  // poses agree with the truth up to the gauge (keyframe 0 fixed).
  const int n = 40;
  std::vector<ul::Sim3> truth(n), guess(n);
  for (int k = 0; k < n; ++k) {
    const double a = 2 * M_PI * k / n;
    Eigen::Isometry3d T_wc = Eigen::Isometry3d::Identity();
    T_wc.linear() = Rot(0, 0, a + M_PI / 2);
    T_wc.translation() = Eigen::Vector3d(5 * std::cos(a), 5 * std::sin(a), 0);
    truth[static_cast<size_t>(k)] = ul::Sim3(T_wc.inverse());
  }
  std::vector<ul::PoseGraphEdge> edges;
  for (int k = 1; k < n; ++k)
    edges.push_back({k, k - 1, truth[static_cast<size_t>(k)] * truth[static_cast<size_t>(k - 1)].inverse()});
  edges.push_back({n - 1, 0, truth[static_cast<size_t>(n - 1)] * truth[0].inverse()});
  // Drifted chain: each relative step is perturbed by 0.01 rad of yaw and 1% of scale.
  guess[0] = truth[0];
  const ul::Sim3 drift(1.01, Rot(0, 0, 0.01), Eigen::Vector3d::Zero());
  for (int k = 1; k < n; ++k)
    guess[static_cast<size_t>(k)] = drift * edges[static_cast<size_t>(k - 1)].S_ij * guess[static_cast<size_t>(k - 1)];
  auto max_err = [&](const std::vector<ul::Sim3>& S) {
    double e = 0;
    for (int k = 0; k < n; ++k)
      e = std::max(e, (S[static_cast<size_t>(k)].inverse().t - truth[static_cast<size_t>(k)].inverse().t).norm());
    return e;
  };
  const double before = max_err(guess);
  ul::OptimizePoseGraph(&guess, std::vector<bool>(n, true), edges, {0}, 50);
  const double after = max_err(guess);
  std::printf("pose graph: max position error %.3f -> %.6f\n", before, after);
  EXPECT_GT(before, 1.0);
  EXPECT_LT(after, 1e-4);  // consistent edges: the optimum is the truth
}

TEST(MonoSlam, BadInputIsRejected) {
  ul::PinholeCamera cam = Pinhole((Eigen::Matrix3d() << 320, 0, 320, 0, 320, 240, 0, 0, 1).finished());
  ul::MonoSlamOptions bad;
  bad.keyframe_tracked_ratio = 1.5;
  EXPECT_THROW(ul::MonoSlam(cam, {}, bad, nullptr), std::invalid_argument);
  ul::MonoSlamOptions bad_atlas;
  bad_atlas.atlas_max_maps = -1;
  try {
    const ul::MonoSlam refused(cam, {}, bad_atlas, nullptr);
    ADD_FAILURE() << "a negative atlas size was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("atlas_max_maps must be in [0, 100], got -1"), std::string::npos) << e.what();
  }
  ul::PinholeCamera zero;
  EXPECT_THROW(ul::MonoSlam(zero, {}, {}, nullptr), std::invalid_argument);
  ul::MonoSlam slam(cam, {}, {}, nullptr);
  EXPECT_EQ(slam.Track(cv::Mat(), 0.0).state, ul::SlamState::kInvalidInput);
  EXPECT_EQ(slam.Track(cv::Mat(100, 100, CV_8UC1, cv::Scalar(3)), 0.0).state, ul::SlamState::kInvalidInput);
  EXPECT_EQ(slam.Track(cv::Mat(480, 640, CV_8UC1, cv::Scalar(3)), NAN).state, ul::SlamState::kInvalidInput);
  // A featureless image is not an error: the system waits to initialise.
  EXPECT_EQ(slam.Track(cv::Mat(480, 640, CV_8UC1, cv::Scalar(90)), 0.0).state, ul::SlamState::kInitializing);
}

// StraightPath (slam_flights.hpp): 6 m north 1.5 m above the pipe, swaying and yawing, as the
// pipe-following controller flies it. Loaded once for all tests.
const RenderedRun& StraightRun() {
  static const RenderedRun run = Load("straight");
  return run;
}

std::shared_ptr<const ul::BowVocabulary> Vocabulary() {
  return std::make_shared<ul::BowVocabulary>(
      ul::BowVocabulary::Load(std::string(UNAV_REPO_ROOT) + "/config/vocabulary/orb_vocabulary.bin"));
}

TEST(MonoSlam, StraightRunOverTheSeabedWithKnownMotion) {
  const RenderedRun& run = StraightRun();
  ul::MonoSlam slam(Pinhole(run.K), {}, {}, nullptr);
  const auto [first_tracked, lost] = TrackAll(slam, run);
  size_t n = 0;
  double path = 0;
  const double ape = Ape(slam, run, &n, &path);
  const auto st = slam.stats();
  std::printf(
      "straight run: initialised at frame %d, %zu poses, %d lost, %d keyframes, %d points; APE %.4f m over %.2f m "
      "(%.2f%%)\n",
      first_tracked, n, lost, st.keyframes, st.points, ape, path, 100 * ape / path);
  EXPECT_GE(first_tracked, 1);
  EXPECT_LE(first_tracked, 15);  // needs parallax: a few frames of 6 cm at 1.4 m
  EXPECT_EQ(lost, 0);
  EXPECT_GE(n, 85u);
  // Bound: 1% of the distance, twice the 0.5% typical of ORB-SLAM on such a run; seen: see log.
  EXPECT_LT(ape, 0.01 * path);
  // The bounded trajectory (what the node publishes as its path) is the whole one's tail, exactly.
  const auto all = slam.Trajectory(), tail = slam.Trajectory(10);
  ASSERT_EQ(tail.size(), 10u);
  for (size_t i = 0; i < tail.size(); ++i) {
    const auto& w = all[all.size() - tail.size() + i];
    EXPECT_EQ(tail[i].stamp, w.stamp);
    EXPECT_TRUE(tail[i].T_wc.isApprox(w.T_wc, 0.0)) << i;
  }
  EXPECT_EQ(slam.Trajectory(100000).size(), all.size());
}

// Forward motion, as a vehicle flies along a pipe with its front camera (or a car drives), 1.5 m
// above the seabed, the camera looking ahead and pitched down. Two things made this fail before:
// the points near the focus of expansion have no parallax however far the camera moves (the
// initialisation judged the median point), and the seabed ahead is nearly a plane, whose two
// views have two exact motions (the true one and a twin translating along the plane's normal
// while turning: it was taken, and the trajectory turned 120 deg over 6 s). Three speeds and
// pitches: 0.6, 1.0 and 1.5 m/s at 10 Hz.
TEST(MonoSlam, ForwardLookingCameraInitialisesWithinFifteenFramesAndHolds) {
  // ForwardPath(step_m) seen through ForwardMount(pitch_deg) (slam_flights.hpp).
  for (const auto& c : unav::localization::testing::kForwardCases) {
    const RenderedRun run = Load("forward_" + std::to_string(c.pitch_deg));
    ul::MonoSlam slam(Pinhole(run.K), {}, {}, nullptr);
    const auto [first_tracked, lost] = TrackAll(slam, run);
    size_t n = 0;
    double path = 0;
    const double ape = Ape(slam, run, &n, &path);
    std::printf(
        "forward camera, pitch %.0f deg, %.2f m/frame: initialised at frame %d, %zu poses, %d lost; APE %.4f m "
        "over %.2f m (%.2f%%)\n",
        static_cast<double>(c.pitch_deg), c.step_m, first_tracked, n, lost, ape, path, 100 * ape / path);
    EXPECT_GE(first_tracked, 1);
    EXPECT_LE(first_tracked, 15);  // seen: 1..4
    EXPECT_EQ(lost, 0);
    EXPECT_GE(n, 45u);
    // Seen 0.15-0.26 %; the twin motion gave 7-26 %. 1 % of the path, twice the down camera's
    // typical error, leaves room for platform differences.
    EXPECT_LT(ape, 0.01 * path);
  }
}

TEST(MonoSlam, SaysWhenTrackingIsLostAndRelocalises) {
  // Frames 50-54 are blank (the camera blinded: silt, a light failure). The SLAM must report
  // kLost for them, then find its map again by bag of words + PnP (kRelocalized) and go on with
  // the same map: one trajectory, accurate after Sim(3) alignment.
  const RenderedRun& run = StraightRun();
  ul::MonoSlam slam(Pinhole(run.K), {}, {}, Vocabulary());
  int lost_in_gap = 0, relocalized_at = -1, lost_after = 0;
  for (size_t k = 0; k < run.gray.size(); ++k) {
    const bool blank = k >= 50 && k < 55;
    const cv::Mat img = blank ? cv::Mat(480, 640, CV_8UC1, cv::Scalar(70)) : run.gray[k];
    const auto s = slam.Track(img, run.stamps[k]);
    if (blank && s.state == ul::SlamState::kLost) {
      ++lost_in_gap;
      EXPECT_FALSE(s.message.empty());
    }
    if (!blank && k > 50 && s.state == ul::SlamState::kRelocalized && relocalized_at < 0)
      relocalized_at = static_cast<int>(k);
    if (!blank && k > 55 && relocalized_at >= 0 && s.state == ul::SlamState::kLost) ++lost_after;
  }
  size_t n = 0;
  double path = 0;
  const double ape = Ape(slam, run, &n, &path);
  const auto st = slam.stats();
  std::printf(
      "blank frames 50-54: %d reported lost, relocalised at frame %d, %d re-initialisations; APE %.4f m over %.2f m, "
      "%zu poses\n",
      lost_in_gap, relocalized_at, st.reinitializations, ape, path, n);
  EXPECT_EQ(lost_in_gap, 5);
  EXPECT_EQ(relocalized_at, 55);  // the first image after the gap: 30 cm further, still over mapped seabed
  EXPECT_EQ(lost_after, 0);
  EXPECT_EQ(st.reinitializations, 0);
  EXPECT_EQ(st.loops, 0);  // a straight run has no loop to close (the seabed must not alias)
  EXPECT_GE(n, 90u);       // every frame but the 5 blank ones and the few before initialisation
  EXPECT_LT(ape, 0.01 * path);
}

// The relocalisation plausibility gate: after two blank frames at frame 60 the video jumps back
// to frame 5, 3.3 m behind (1.1 m a frame would be needed: 18x the run's 6 cm). The map has that
// place, so bag of words + PnP find it; a continuous video cannot be there, so the gate rejects
// it (as it would a repetitive seabed aliasing) and the SLAM re-initialises a new map instead:
// the gate (3x the fastest recent motion per frame lost) would admit the place only after ~14
// frames, relocalisation gives up after 10. With the gate off (a kidnapped camera) the same
// frames relocalise at once.
TEST(MonoSlam, RelocalisationGateRejectsAPoseTheCameraCannotHaveReached) {
  const RenderedRun& run = StraightRun();
  std::vector<int> order;
  order.reserve(92);
  for (int k = 0; k < 60; ++k) order.push_back(k);
  order.push_back(-1);
  order.push_back(-1);
  for (int k = 5; k < 35; ++k) order.push_back(k);
  auto fly = [&](const ul::MonoSlamOptions& o, int* relocalized_at, std::string* message) {
    ul::MonoSlam slam(Pinhole(run.K), {}, o, Vocabulary());
    *relocalized_at = -1;
    for (size_t i = 0; i < order.size(); ++i) {
      const int k = order[i];
      const cv::Mat img = k < 0 ? cv::Mat(480, 640, CV_8UC1, cv::Scalar(70)) : run.gray[static_cast<size_t>(k)];
      // Stamps keep increasing through the jump (the video goes on).
      const auto s = slam.Track(img, 0.1 * static_cast<double>(i));
      if (s.state == ul::SlamState::kRelocalized && *relocalized_at < 0) *relocalized_at = static_cast<int>(i);
      if (s.message.find("rejected") != std::string::npos && message->empty()) *message = s.message;
    }
    return slam.stats();
  };
  int reloc_gated = -1, reloc_open = -1;
  std::string msg_gated, msg_open;
  const ul::SlamStats gated = fly(ul::MonoSlamOptions{}, &reloc_gated, &msg_gated);
  ul::MonoSlamOptions off;
  off.reloc_gate_speed_factor = 0.0;
  const ul::SlamStats open = fly(off, &reloc_open, &msg_open);
  std::printf(
      "jump of 3.3 m after 2 blank frames: gate on: %d rejected, relocalised at %d, %d re-initialisations (%s); "
      "gate off: relocalised at %d\n",
      gated.relocalizations_rejected, reloc_gated, gated.reinitializations, msg_gated.c_str(), reloc_open);
  EXPECT_EQ(reloc_open, 62);  // the first frame after the jump: the place is in the map
  EXPECT_EQ(open.relocalizations_rejected, 0);
  EXPECT_EQ(reloc_gated, -1);
  EXPECT_GE(gated.relocalizations_rejected, 1);
  EXPECT_EQ(gated.reinitializations, 1);
  EXPECT_NE(msg_gated.find("from the last tracked pose"), std::string::npos) << msg_gated;
}

TEST(MonoSlam, ReinitialisesWhenItCannotRelocalise) {
  // Without a vocabulary there is no relocalisation: after a blank gap the SLAM starts a new map
  // that continues from the last good pose (map index 1) and tracks again.
  const RenderedRun& run = StraightRun();
  ul::MonoSlam slam(Pinhole(run.K), {}, {}, nullptr);
  bool reinit = false;
  int tracking_after = 0;
  for (size_t k = 0; k < run.gray.size(); ++k) {
    const bool blank = k >= 50 && k < 55;
    const auto s = slam.Track(blank ? cv::Mat(480, 640, CV_8UC1, cv::Scalar(70)) : run.gray[k], run.stamps[k]);
    reinit = reinit || s.reinitialized;
    if (k > 55 && s.state == ul::SlamState::kTracking) ++tracking_after;
  }
  const auto traj = slam.Trajectory();
  ASSERT_FALSE(traj.empty());
  std::printf("re-initialised: %d, tracking after the gap: %d frames, %zu poses, last map %d\n", reinit ? 1 : 0,
              tracking_after, traj.size(), traj.back().map);
  EXPECT_TRUE(reinit);
  EXPECT_EQ(slam.stats().reinitializations, 1);
  EXPECT_EQ(traj.back().map, 1);
  EXPECT_GE(tracking_after, 30);  // a new two-view initialisation needs a few frames of parallax
  // The new map starts at the last good pose: no jump larger than the gap's motion (5 x 6 cm)
  // times the map scale uncertainty.
  for (size_t i = 1; i < traj.size(); ++i)
    if (traj[i].map != traj[i - 1].map) {
      const double jump = (traj[i].T_wc.translation() - traj[i - 1].T_wc.translation()).norm();
      const double step = (traj[i - 1].T_wc.translation() - traj[i - 2].T_wc.translation()).norm();
      std::printf("map change at %.1f s: jump %.3f, previous step %.3f (map units)\n", traj[i].stamp, jump, step);
      EXPECT_LT(jump, 20 * step);
    }
}

// SquarePath (slam_flights.hpp): a 3.6 m square at constant heading and 1.2 m on past the start;
// the camera sees its first images again after 14.4 m. Loaded once.
const RenderedRun& SquareRun() {
  static const RenderedRun run = Load("square");
  return run;
}

TEST(MonoSlam, ClosesALoopAroundASquare) {
  // The loop must be detected by bag of words, verified by Sim(3) and closed.
  const RenderedRun& run = SquareRun();
  ul::MonoSlam slam(Pinhole(run.K), {}, {}, Vocabulary());
  int loop_frame = -1;
  for (size_t k = 0; k < run.gray.size(); ++k)
    if (slam.Track(run.gray[k], run.stamps[k]).loop_closed && loop_frame < 0) loop_frame = static_cast<int>(k);
  size_t n = 0;
  double path = 0;
  const double ape = Ape(slam, run, &n, &path);
  std::printf("square: loop closed at frame %d (%zu frames), %d loops; APE %.4f m over %.2f m, %zu poses\n", loop_frame,
              run.gray.size(), slam.stats().loops, ape, path, n);
  EXPECT_GE(slam.stats().loops, 1);
  EXPECT_GE(loop_frame, 200);  // only once the start area is in view again
  EXPECT_LT(ape, 0.005 * path);
}

// The square with the camera blind for 16 frames in its second leg (turbidity, a light failure):
// relocalisation fails, a new map starts after the corner. When the square comes back to its
// start, the atlas recognises the lost map's first place and merges the lost map into the new
// one: the output is one trajectory in one frame. (The new map's first keyframes overlap the lost
// map's last ones by ~40 % of the image at most: not enough matches to verify a Sim(3) there.)
TEST(MonoSlam, AtlasMergesTheLostMapIntoTheNewOne) {
  const RenderedRun& run = SquareRun();
  const auto fly = [&run](bool merge, int* merged_at, int* loop_at) {
    ul::MonoSlamOptions o;
    o.merge_maps = merge;
    auto slam = std::make_unique<ul::MonoSlam>(Pinhole(run.K), std::vector<double>{}, o, Vocabulary());
    *merged_at = *loop_at = -1;
    for (size_t k = 0; k < run.gray.size(); ++k) {
      const bool blind = k >= 100 && k < 116;
      const auto s = slam->Track(blind ? cv::Mat(480, 640, CV_8UC1, cv::Scalar(40)) : run.gray[k], run.stamps[k]);
      if (s.maps_merged && *merged_at < 0) *merged_at = static_cast<int>(k);
      if (s.loop_closed && *loop_at < 0) *loop_at = static_cast<int>(k);
    }
    return slam;
  };
  int merged_at = -1, loop_at = -1, apart_merged_at = -1, apart_loop_at = -1;
  const auto slam = fly(true, &merged_at, &loop_at);
  const auto apart = fly(false, &apart_merged_at, &apart_loop_at);
  size_t n = 0, n_apart = 0;
  double path = 0;
  const double ape = Ape(*slam, run, &n, &path), ape_apart = Ape(*apart, run, &n_apart, &path);
  const auto st = slam->stats();
  const auto traj = slam->Trajectory();
  std::set<int> maps_out;
  for (const auto& p : traj) maps_out.insert(p.map);
  std::printf(
      "atlas: %d maps, %d merged (at frame %d), loop closed at frame %d; %zu poses in %zu map(s), APE %.4f m over "
      "%.2f m; maps kept apart: %zu poses, loop at %d, APE %.4f m\n",
      st.maps, st.merges, merged_at, loop_at, n, maps_out.size(), ape, path, n_apart, apart_loop_at, ape_apart);
  EXPECT_EQ(st.reinitializations, 1);
  EXPECT_EQ(st.merges, 1);
  EXPECT_GE(merged_at, 200);              // once the start is in view again (it is from frame ~220 on)
  EXPECT_EQ(maps_out, std::set<int>{1});  // every pose follows the merged map's keyframes
  EXPECT_EQ(apart->stats().merges, 0);
  // Bound: the unbroken square's (0.5 % of the path; the loop closes over the merged map).
  EXPECT_LT(ape, 0.005 * path);
  EXPECT_LT(ape, 0.5 * ape_apart);  // kept apart, the second map's scale is a guess
  // The merged map's frames interleave with nothing else: the bounded trajectory (the node's
  // path) is still the whole one's tail.
  const auto tail = slam->Trajectory(30);
  ASSERT_EQ(tail.size(), 30u);
  for (size_t i = 0; i < tail.size(); ++i) EXPECT_EQ(tail[i].stamp, traj[traj.size() - tail.size() + i].stamp);
}

TEST(MonoSlam, InitialisesAndTracksOnThe320x180DemoCamera) {
  // The demo's down camera: 320 x 180, 90 deg, with its read noise (0.008). Feature-count
  // thresholds scale with the image (a 640x480 tuning needed 60 two-view matches; ~35 exist
  // here) and CLAHE evens out the lamp-lit, low-contrast seabed.
  const RenderedRun run = Load("straight_320x180_noise");
  ul::MonoSlamOptions o;
  o.clahe_clip = 3.0;
  ul::MonoSlam slam(Pinhole(run.K, 320, 180), {}, o, nullptr);
  const auto [first_tracked, lost] = TrackAll(slam, run);
  size_t n = 0;
  double path = 0;
  const double ape = Ape(slam, run, &n, &path);
  std::printf("320x180 run: initialised at frame %d, %zu poses, %d lost; APE %.4f m over %.2f m (%.2f%%)\n",
              first_tracked, n, lost, ape, path, 100 * ape / path);
  EXPECT_GE(first_tracked, 1);
  EXPECT_LE(first_tracked, 15);
  EXPECT_EQ(lost, 0);
  EXPECT_GE(n, 85u);
  // A quarter of the pixels: bound at 2% of the path (the 640x480 run's bound is 1%).
  EXPECT_LT(ape, 0.02 * path);
}

// WeaveFlight (slam_flights.hpp): 10 s weaving north with the accelerations an inertial
// initialisation needs, its IMU in closed form; its 100 frames loaded once.
const RenderedRun& WeaveRun() {
  static const RenderedRun run = Load("weave");
  return run;
}

namespace {
// Sim(3) scale and SE(3) APE (no scale fitted) of a run's trajectory against the truth.
void MetricFit(const ul::MonoSlam& slam, const RenderedRun& run, double* scale, double* se3_ape) {
  std::vector<Eigen::Vector3d> gt, est;
  for (const auto& p : slam.Trajectory()) {
    gt.push_back(run.X_WC[static_cast<size_t>(std::lround(p.stamp / 0.1))].translation());
    est.push_back(p.T_wc.translation());
  }
  AlignedRmse(gt, est, scale);
  *se3_ape = AlignedRmse(gt, est, nullptr, true);
}
}  // namespace

TEST(MonoSlam, InertialModeGivesAMetricTrajectory) {
  // The same SLAM on the same images, with a 200 Hz IMU (samples at each interval's middle, a
  // 0.005 rad/s gyro bias): once its keyframes span 2 s the map is scaled to metres, so the
  // trajectory's best Sim(3) alignment to the truth has scale ~1 (without the IMU: the first
  // map's median depth is 1 unit, here ~1.5 m).
  const RenderedRun& run = WeaveRun();
  const Eigen::Vector3d g(0.0, 0.0, 9.81), gyro_bias(0.0, 0.0, 0.005);
  auto fly = [&](bool with_imu, double* scale, double* se3_ape, bool inertial_ba = true) {
    ul::MonoSlamOptions o;
    o.inertial_ba = inertial_ba;
    ul::MonoSlam slam(Pinhole(run.K), {}, o, nullptr);
    if (with_imu) slam.EnableInertial(Eigen::Isometry3d::Identity(), ul::ImuNoise{});  // camera at the IMU
    double t_imu = 0.0;
    for (size_t k = 0; k < run.gray.size(); ++k) {
      for (; with_imu && t_imu <= run.stamps[k] + 1e-9; t_imu += 0.005) {
        const double tm = t_imu + 0.0025;
        const Eigen::Matrix3d R = Rot(0, 0, WeaveFlight::Yaw(tm));
        slam.AddImu(t_imu, Eigen::Vector3d(0.0, 0.0, WeaveFlight::YawRate(tm)) + gyro_bias,
                    R.transpose() * (WeaveFlight::A(tm) - g));
      }
      slam.Track(run.gray[k], run.stamps[k]);
    }
    MetricFit(slam, run, scale, se3_ape);
    return slam.stats();
  };
  double scale_vo = 0, ape_vo = 0, scale_vi = 0, ape_vi = 0, scale_rot = 0, ape_rot = 0;
  const auto st_vo = fly(false, &scale_vo, &ape_vo);
  const auto st_vi = fly(true, &scale_vi, &ape_vi);
  const auto st_rot = fly(true, &scale_rot, &ape_rot, false);
  std::printf(
      "weave: visual only: Sim(3) scale %.3f, SE(3) APE %.3f m; inertial: %d init(s) at %.4f m per unit, gravity %.1f "
      "deg off the camera axis, %d refinement(s), %ld inertial factors, Sim(3) scale %.4f, SE(3) APE %.4f m; without "
      "the visual-inertial BA (%ld rotation factors): scale %.4f, APE %.4f m\n",
      scale_vo, ape_vo, st_vi.inertial_inits, st_vi.inertial_scale, st_vi.inertial_gravity_deg,
      st_vi.inertial_refinements, st_vi.inertial_factors, scale_vi, ape_vi, st_rot.gyro_factors, scale_rot, ape_rot);
  EXPECT_EQ(st_vo.inertial_inits, 0);
  EXPECT_EQ(st_vi.inertial_inits, 1);
  EXPECT_EQ(st_vi.inertial_refinements, 1);  // at 5 s of keyframes (the one at 15 s never comes in 10 s)
  EXPECT_EQ(st_vi.imu_samples_rejected, 0);
  // The inertial-only initialisation is exact on the true poses of this flight (scale 1.6500 of
  // 1.65 over 2, 5 and 9 s); on the SLAM's keyframes alone its scale comes out low (1.443 after
  // 2 s, then x 1.094 at 5 s: 4.7 % short in all, APE 0.041 m): with this gentle weave
  // (0.3 m/s^2) the keyframes' few-mm errors weigh like signal, which shrinks a least-squares
  // scale (regression dilution). The visual-inertial bundle adjustments (a global one after each
  // initialisation, then the local ones) estimate scale, velocities and biases with the points:
  // seen scale 1.0004, APE 0.004 m. Bounds: 2 % and 2 cm, 5x and 50x what is seen.
  EXPECT_GT(st_vi.inertial_factors, 100);
  EXPECT_LT(st_vi.gyro_factors, st_rot.gyro_factors / 2);  // after the initialisation the inertial factors hold it
  EXPECT_NEAR(scale_vi, 1.0, 0.02);
  EXPECT_LT(st_vi.inertial_gravity_deg, 10.0);  // the down camera looks along gravity
  EXPECT_LT(ape_vi, 0.02);                      // metres, no scale fitted, over a 5 m path (visual only: 0.58 m)
  // Without the visual-inertial adjustment (rotation factors only; seen: scale 1.016, 0.024 m).
  EXPECT_EQ(st_rot.inertial_factors, 0);
  EXPECT_GT(st_rot.gyro_factors, 100);
  EXPECT_LT(ape_vi, 0.5 * ape_rot);
}

TEST(MonoSlam, ImuPredictionTracksThroughAGapInTheImages) {
  // The weave with the camera's frames 50-57 lost (0.8 s: 0.4 m of travel and a sway reversal)
  // while the IMU runs on. The constant-velocity model predicts one frame of motion across the
  // gap; the IMU predicts the pose where the vehicle is.
  const RenderedRun& run = WeaveRun();
  const Eigen::Vector3d g(0.0, 0.0, 9.81);
  auto fly = [&](bool imu_prediction, int* tracked_after_gap) {
    ul::MonoSlamOptions o;
    o.imu_prediction = imu_prediction;
    ul::MonoSlam slam(Pinhole(run.K), {}, o, nullptr);
    slam.EnableInertial(Eigen::Isometry3d::Identity(), ul::ImuNoise{});
    double t_imu = 0.0;
    *tracked_after_gap = -1;
    for (size_t k = 0; k < run.gray.size(); ++k) {
      for (; t_imu <= run.stamps[k] + 1e-9; t_imu += 0.005) {
        const double tm = t_imu + 0.0025;
        const Eigen::Matrix3d R = Rot(0, 0, WeaveFlight::Yaw(tm));
        slam.AddImu(t_imu, Eigen::Vector3d(0.0, 0.0, WeaveFlight::YawRate(tm)),
                    R.transpose() * (WeaveFlight::A(tm) - g));
      }
      if (k >= 50 && k < 58) continue;
      const auto s = slam.Track(run.gray[k], run.stamps[k]);
      if (k == 58) *tracked_after_gap = s.state == ul::SlamState::kTracking ? 1 : 0;
    }
    return slam.stats();
  };
  int after_imu = -1, after_cv = -1;
  const auto st_imu = fly(true, &after_imu);
  const auto st_cv = fly(false, &after_cv);
  std::printf(
      "gap of 8 frames: IMU prediction: %d frames predicted, %d missed, tracked after the gap %d, %d lost; constant "
      "velocity: %d missed, tracked after the gap %d, %d lost\n",
      st_imu.imu_predicted_frames, st_imu.motion_model_misses, after_imu, st_imu.lost_frames, st_cv.motion_model_misses,
      after_cv, st_cv.lost_frames);
  EXPECT_EQ(after_imu, 1);
  EXPECT_EQ(st_imu.lost_frames, 0);
  EXPECT_EQ(st_imu.reinitializations, 0);
  EXPECT_GT(st_imu.imu_predicted_frames, 50);  // every frame from the inertial initialisation (~2.5 s) on
  // What it improves on: one frame of constant velocity lands 0.35 m short; the reference
  // keyframe's appearance matching fails too, and (no vocabulary here) a new map starts.
  EXPECT_EQ(after_cv, 0);
  EXPECT_GE(st_cv.motion_model_misses, 1);
}

TEST(MonoSlam, DvlAidedModeGivesAMetricTrajectoryThatKeepsItsScale) {
  // The same SLAM on the same images with a 10 Hz DVL 0.25 m behind and 0.1 m below the camera
  // (its velocity: the body's plus the yaw rate's lever-arm term, 1 cm/s noise per axis): the
  // DVL's displacement between keyframes scales the map to metres after 2 s (no gravity, no
  // accelerations needed) and, as factors of the bundle adjustments, holds the scale from then on.
  const RenderedRun& run = WeaveRun();
  const Eigen::Vector3d r_d(-0.25, 0.0, 0.1);  // the DVL's origin in the body (= camera) frame
  Eigen::Isometry3d T_dc = Eigen::Isometry3d::Identity();
  T_dc.translation() = -r_d;  // the camera in the DVL frame (same axes)
  const Eigen::Vector3d g(0.0, 0.0, 9.81);
  auto fly = [&](bool factors, double* scale, double* se3_ape, bool gyro = false) {
    ul::MonoSlamOptions o;
    o.dvl_factors = factors;
    ul::MonoSlam slam(Pinhole(run.K), {}, o, nullptr);
    slam.EnableDvl(T_dc);
    if (gyro) slam.EnableInertial(Eigen::Isometry3d::Identity(), ul::ImuNoise{});
    double t_imu = 0.0;
    std::mt19937 rng(7);
    std::normal_distribution<double> noise(0.0, 0.01);
    for (size_t k = 0; k < run.gray.size(); ++k) {
      const double t = run.stamps[k];
      const Eigen::Vector3d w_B(0.0, 0.0, WeaveFlight::YawRate(t));
      const Eigen::Vector3d v_D = Rot(0, 0, WeaveFlight::Yaw(t)).transpose() * WeaveFlight::V(t) + w_B.cross(r_d) +
                                  Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
      slam.AddDvl(t, v_D, true);
      for (; gyro && t_imu <= t + 1e-9; t_imu += 0.005) {  // the inertial test's ideal 200 Hz IMU
        const double tm = t_imu + 0.0025;
        slam.AddImu(t_imu, Eigen::Vector3d(0.0, 0.0, WeaveFlight::YawRate(tm)),
                    Rot(0, 0, WeaveFlight::Yaw(tm)).transpose() * (WeaveFlight::A(tm) - g));
      }
      slam.Track(run.gray[k], t);
    }
    MetricFit(slam, run, scale, se3_ape);
    return slam.stats();
  };
  double scale_f = 0, ape_f = 0, scale_nf = 0, ape_nf = 0, scale_g = 0, ape_g = 0;
  const auto st_f = fly(true, &scale_f, &ape_f);
  fly(false, &scale_nf, &ape_nf);
  const auto st_g = fly(true, &scale_g, &ape_g, /*gyro=*/true);
  std::printf(
      "weave, DVL: %d scaling(s), %d refinement(s), last %.4f m per unit; with factors Sim(3) scale %.4f, SE(3) APE "
      "%.4f m; scaling only: scale %.4f, APE %.4f m; with the gyroscope too (%ld rotation factors): scale %.4f, APE "
      "%.4f m\n",
      st_f.dvl_inits, st_f.dvl_refinements, st_f.dvl_scale, scale_f, ape_f, scale_nf, ape_nf, st_g.gyro_factors,
      scale_g, ape_g);
  // With the IMU on too, the DVL still scales (the IMU's initialisation does not run) and the
  // gyroscope adds rotation factors.
  EXPECT_EQ(st_g.dvl_inits, 1);
  EXPECT_EQ(st_g.inertial_inits, 0);
  EXPECT_GT(st_g.gyro_factors, 0);
  EXPECT_NEAR(scale_g, 1.0, 0.02);
  EXPECT_LT(ape_g, 0.03);
  EXPECT_EQ(st_f.dvl_inits, 1);
  EXPECT_EQ(st_f.dvl_rejections, 0);
  EXPECT_EQ(st_f.dvl_samples_rejected, 0);
  EXPECT_EQ(st_f.inertial_inits, 0);
  EXPECT_NEAR(scale_f, 1.0, 0.02);
  EXPECT_NEAR(scale_nf, 1.0, 0.02);
  EXPECT_GT(st_f.dvl_factors, 0);
  // Seen: scale 1.007 and 10 mm either way (10 s is too short for a visual scale to drift); bound
  // at ~4x that (visual only: 0.58 m; the IMU's initialisation on this flight: 0.065 m).
  EXPECT_LT(ape_f, 0.03);  // metres, no scale fitted, over a 5 m path
}

TEST(MonoSlam, DvlInputIsChecked) {
  const ul::PinholeCamera cam = ul::PinholeCamera::FromK(Eigen::Matrix3d::Identity() * 300, 640, 480);
  ul::MonoSlam slam(cam, {}, {}, nullptr);
  Eigen::Isometry3d skewed = Eigen::Isometry3d::Identity();
  skewed.linear()(0, 1) = 0.5;  // not a rotation
  EXPECT_THROW(slam.EnableDvl(skewed), std::invalid_argument);
  slam.EnableDvl(Eigen::Isometry3d::Identity());
  slam.AddDvl(1.0, Eigen::Vector3d(0.5, 0, 0), true);
  slam.AddDvl(0.5, Eigen::Vector3d(0.5, 0, 0), true);   // out of order
  slam.AddDvl(2.0, Eigen::Vector3d(NAN, 0, 0), true);   // not finite
  slam.AddDvl(2.1, Eigen::Vector3d(NAN, 0, 0), false);  // no bottom lock: kept (it breaks the integration)
  EXPECT_EQ(slam.stats().dvl_samples_rejected, 2);
  ul::MonoSlamOptions o;
  o.dvl_factor_sigma_m = 0.0;
  std::string why;
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("dvl_factor_sigma_m"), std::string::npos) << why;
}

TEST(MonoSlam, InertialInputIsChecked) {
  const ul::PinholeCamera cam = ul::PinholeCamera::FromK(Eigen::Matrix3d::Identity() * 300, 640, 480);
  ul::MonoSlam slam(cam, {}, {}, nullptr);
  Eigen::Isometry3d skewed = Eigen::Isometry3d::Identity();
  skewed.linear()(0, 1) = 0.5;  // not a rotation
  EXPECT_THROW(slam.EnableInertial(skewed, ul::ImuNoise{}), std::invalid_argument);
  slam.EnableInertial(Eigen::Isometry3d::Identity(), ul::ImuNoise{});
  slam.AddImu(1.0, Eigen::Vector3d::Zero(), Eigen::Vector3d(0, 0, -9.81));
  slam.AddImu(0.5, Eigen::Vector3d::Zero(), Eigen::Vector3d(0, 0, -9.81));     // out of order
  slam.AddImu(2.0, Eigen::Vector3d(NAN, 0, 0), Eigen::Vector3d(0, 0, -9.81));  // not finite
  EXPECT_EQ(slam.stats().imu_samples_rejected, 2);
}
