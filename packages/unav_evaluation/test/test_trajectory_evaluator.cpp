// trajectory_evaluator over DDS: ground truth and a monocular-like estimate (scaled, shifted,
// rotated copy) in; on destruction: TUM files, results (APE ~0 after Sim(3)), and a PNG.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "nav_msgs/msg/path.hpp"
#include "trajectory_evaluator.hpp"
#include "unav_runtime/conversions.hpp"
#include "unav_runtime/testing.hpp"
#include "unav_scene/camera.hpp"

using namespace std::chrono_literals;
using unav::testing::make_link;

namespace {
// A trajectory_evaluator with `params` (name:=value each) and a probe node, each on a participant
// of its own (the node test pattern, unav::testing::NodeUnderTest).
// The probe publishes the ground truth (gt) from the start; spin() lets both sides work 2 ms.
struct EvaluatorRun : unav::testing::NodeUnderTest<unav::evaluation::TrajectoryEvaluator> {
  EvaluatorRun(const std::vector<std::string>& params, const unav::ContextOptions& o)
      : NodeUnderTest("trajectory_evaluator", ros_params(params), o),
        gt(publisher<nav_msgs::msg::Odometry>("/rov/ground_truth/odom")) {}
  template <class T>
  std::shared_ptr<unav::Publisher<T>> publisher(const std::string& topic) {
    return probe.create_publisher<T>(topic, unav::QoS::reliable(100));
  }
  void spin() { spin_for(2ms); }
  bool delivered(const std::vector<unav::testing::Link>& links) {
    return unav::testing::wait_for_delivery({&node_ctx, &test_ctx}, links);
  }
  static std::vector<std::string> ros_params(const std::vector<std::string>& params) {
    std::vector<std::string> a{"--ros-args"};
    for (const auto& p : params) a.insert(a.end(), {"-p", p});
    return a;
  }
  std::shared_ptr<unav::Publisher<nav_msgs::msg::Odometry>> gt;
};

using unav::testing::odometry_at;
}  // namespace

TEST(TrajectoryEvaluator, WritesTableTumAndPlotOnShutdown) {
  const unav::ContextOptions o = unav::testing::test_context_options();
  const std::string out = ::testing::TempDir() + "eval_node_out";
  std::filesystem::remove_all(out);
  const std::string p_out = "output_dir:=" + out;
  EvaluatorRun harness({p_out, "estimates:=[mono]", "trajectory_name:=linear"}, o);
  auto& node = harness.node;
  auto& gt_pub = harness.gt;
  auto est_pub = harness.publisher<nav_msgs::msg::Odometry>("/rov/localization/mono/odom");
  // Both sides matched before the first pose; every pose delivered and taken before the node
  // writes its outputs (see unav_runtime/testing.hpp).
  const std::vector<unav::testing::Link> links = {make_link(*gt_pub, *node), make_link(*est_pub, *node)};
  ASSERT_TRUE(harness.match(links));
  const Eigen::AngleAxisd R(0.4, Eigen::Vector3d::UnitZ());
  for (int i = 0; i < 100; ++i) {
    const double t = 0.1 * i, a = 0.05 * i;
    const Eigen::Vector3d p(5 * std::sin(a), 2 * std::cos(a), 8.0 + 0.1 * std::sin(3 * a));
    const Eigen::Quaterniond q(Eigen::AngleAxisd(a, Eigen::Vector3d::UnitZ()));
    auto msg = [&](const Eigen::Vector3d& pos, const Eigen::Quaterniond& qq) { return odometry_at(t, pos, qq); };
    gt_pub->publish(msg(p, q));
    est_pub->publish(msg(0.3 * (R * p) + Eigen::Vector3d(1, 2, 3), Eigen::Quaterniond(R) * q));  // Sim(3) copy
    harness.spin();
  }
  ASSERT_TRUE(harness.delivered(links));
  node.reset();  // shutdown: writes everything
  for (const char* f : {"ground_truth.tum", "mono.tum", "results.md", "results.csv", "results.json", "top_view.png"})
    EXPECT_TRUE(std::filesystem::exists(out + "/" + f)) << f;
  // The poses were spooled on disk while they came; once written out, the spool is gone.
  for (const auto& e : std::filesystem::directory_iterator(out))
    EXPECT_EQ(e.path().filename().string().rfind(".spool", 0), std::string::npos) << e.path();
  nlohmann::json j;
  std::ifstream(out + "/results.json") >> j;
  ASSERT_EQ(j.size(), 1u);
  EXPECT_EQ(j[0]["trajectory"], "linear");
  EXPECT_EQ(j[0]["poses"], 100);
  // A Sim(3) copy: zero error after alignment (TUM-free path, doubles over DDS: ~1e-12).
  EXPECT_LT(j[0]["ape_m"]["rmse"].get<double>(), 1e-6);
  EXPECT_LT(j[0]["ape_rad"]["rmse"].get<double>(), 1e-6);
  EXPECT_NEAR(j[0]["scale"].get<double>(), 1.0 / 0.3, 1e-6);
  const cv::Mat png = cv::imread(out + "/top_view.png");
  EXPECT_EQ(png.cols, 800);
}

// Two runs share one folder (combine): each publishes ground truth of the body, and an estimate
// of the down camera (a Sim(3) copy) as a Path up to frame 79 and odometry after it; odometry
// before the path's end is garbage and must be superseded by the path. Ground truth is moved to
// the camera with the camera's mount, so the APE is ~0, and results.json holds both rows.
namespace {

// mount_on_tf: the camera mount comes from /tf_static (as the renderer publishes it) instead of
// the camera YAML; the results must be the same.
void RunCombined(const std::string& out, const std::string& run, int domain, bool mount_on_tf) {
  const std::string root = UNAV_REPO_ROOT;
  const std::string cams = root + "/config/sensors/bluerov2_down_vslam.yaml";
  Eigen::Isometry3d X_BC = Eigen::Isometry3d::Identity();
  for (const auto& c : unav::scene::load_cameras(cams))
    if (c.name == "down") X_BC = c.X_BC;
  unav::ContextOptions o;
  o.domain_id = domain;
  o.handle_signals = false;
  const std::string p_out = "output_dir:=" + out, p_run = "trajectory_name:=" + run, p_cams = "cameras_config:=" + cams;
  std::vector<std::string> params{p_out, "estimates:=[mono]", p_run, "combine:=true", "camera:=down"};
  if (!mount_on_tf) params.push_back(p_cams);
  EvaluatorRun harness(params, o);
  unav::Node& probe = harness.probe;
  auto& node = harness.node;
  auto& gt_pub = harness.gt;
  auto est_pub = harness.publisher<nav_msgs::msg::Odometry>("/rov/localization/mono/odom");
  auto path_pub = probe.create_publisher<nav_msgs::msg::Path>("/rov/localization/mono/path", unav::QoS::reliable(2));
  std::vector<unav::testing::Link> links = {make_link(*gt_pub, *node), make_link(*est_pub, *node),
                                            make_link(*path_pub, *node)};
  std::shared_ptr<unav::Publisher<tf2_msgs::msg::TFMessage>> tf_pub;
  if (mount_on_tf) {
    tf_pub = probe.create_publisher<tf2_msgs::msg::TFMessage>("/tf_static", unav::QoS::static_latched());
    tf2_msgs::msg::TFMessage mounts;
    mounts.transforms().push_back(unav::to_transform_stamped(X_BC, 0.0, "base_link_frd", "down_optical"));
    tf_pub->publish(mounts);  // before matching: latched, the evaluator gets it when it matches
    links.push_back(make_link(*tf_pub, *node));
  }
  ASSERT_TRUE(harness.match(links));
  auto pose_msg = [](double t, const Eigen::Isometry3d& X) {
    return odometry_at(t, X.translation(), Eigen::Quaterniond(X.linear()));
  };
  const Eigen::Isometry3d G(Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitX()));
  nav_msgs::msg::Path path;
  for (int i = 0; i < 100; ++i) {
    const double t = 0.1 * i, a = 0.04 * i;
    Eigen::Isometry3d X_WB = Eigen::Isometry3d::Identity();
    X_WB.translation() = Eigen::Vector3d(4 * std::sin(a), 3 * std::cos(a), 8.0);
    X_WB.linear() = Eigen::AngleAxisd(a, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    gt_pub->publish(pose_msg(t, X_WB));
    Eigen::Isometry3d X_C = G * X_WB * X_BC;  // the camera, in another frame
    X_C.translation() *= 0.5;                 // and another scale
    if (i < 50) {
      Eigen::Isometry3d wrong = X_C;
      wrong.translation().x() += 3.0;
      est_pub->publish(pose_msg(t, wrong));
    }
    if (i < 80) {
      geometry_msgs::msg::dds_::PoseStamped_ ps;
      const auto m = pose_msg(t, X_C);
      ps.header() = m.header();
      ps.pose() = m.pose().pose();
      path.poses().push_back(ps);
    } else {
      est_pub->publish(pose_msg(t, X_C));
    }
    if (i == 79) path_pub->publish(path);
    harness.spin();
  }
  ASSERT_TRUE(harness.delivered(links));
  node.reset();
}

}  // namespace

TEST(TrajectoryEvaluator, CombinesRunsPrefersPathsAndComparesInTheCameraFrame) {
  const std::string out = ::testing::TempDir() + "eval_node_combined";
  std::filesystem::remove_all(out);
  const int domain = unav::testing::unique_domain_id();
  RunCombined(out, "linear", domain, false);
  RunCombined(out, "with_loop", domain, true);
  for (const char* f :
       {"linear_ground_truth.tum", "linear_mono.tum", "linear_top_view.png", "with_loop_mono.tum",
        "with_loop_top_view.png", "rows/linear.tsv", "rows/with_loop.tsv", "results.md", "results.json"})
    EXPECT_TRUE(std::filesystem::exists(out + "/" + f)) << f;
  nlohmann::json j;
  std::ifstream(out + "/results.json") >> j;
  ASSERT_EQ(j.size(), 2u);
  EXPECT_EQ(j[0]["trajectory"], "linear");
  EXPECT_EQ(j[1]["trajectory"], "with_loop");
  for (const auto& row : j) {
    EXPECT_EQ(row["poses"], 100);
    EXPECT_LT(row["ape_m"]["rmse"].get<double>(), 1e-6);  // the path won over the wrong odometry
    EXPECT_NEAR(row["scale"].get<double>(), 2.0, 1e-6);
  }
}

// Any estimator, same table: a PoseStamped topic and a /tf frame pair given as `inputs` (as a
// user adds a ROS 2 VSLAM they run themselves) are evaluated like our odometry: here Sim(3)
// copies of the ground truth, so zero error after alignment, one row each.
TEST(TrajectoryEvaluator, TakesPoseStampedAndTfInputs) {
  const std::string kInputs =
      "inputs:=[ext_pose=pose:/ext/camera_pose, ext_tf=tf:ext_map.ext_camera, ext_sensor=pose:/ext/sensor_pose@sensor]";
  const unav::ContextOptions o = unav::testing::test_context_options();
  const std::string out = ::testing::TempDir() + "eval_node_inputs";
  std::filesystem::remove_all(out);
  const std::string p_out = "output_dir:=" + out;
  // One estimate aligned otherwise (estimate_alignments): SE(3) leaves its scale of 2 in the error.
  EvaluatorRun harness({p_out, kInputs, "estimate_alignments:=[ext_tf=se3]"}, o);
  auto& node = harness.node;
  auto& gt_pub = harness.gt;
  auto pose_pub = harness.publisher<geometry_msgs::msg::PoseStamped>("/ext/camera_pose");
  auto tf_pub = harness.publisher<tf2_msgs::msg::TFMessage>("/tf");
  auto sensor_pub = harness.publisher<geometry_msgs::msg::PoseStamped>("/ext/sensor_pose");
  auto static_pub = harness.probe.create_publisher<tf2_msgs::msg::TFMessage>("/tf_static", unav::QoS::static_latched());
  // The frame mapping: the third estimator reports `sensor`, 0.5 m ahead of the body and turned
  // 90 deg about its x axis, as /tf_static says.
  Eigen::Isometry3d X_BS = Eigen::Isometry3d::Identity();
  X_BS.translation() = Eigen::Vector3d(0.5, 0.0, 0.1);
  X_BS.linear() = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitX()).toRotationMatrix();
  {
    tf2_msgs::msg::TFMessage mounts;
    geometry_msgs::msg::TransformStamped m;
    m.header().frame_id("base_link_frd");
    m.child_frame_id("sensor");
    m.transform().translation().x(0.5);
    m.transform().translation().z(0.1);
    const Eigen::Quaterniond qs(X_BS.linear());
    m.transform().rotation().x(qs.x());
    m.transform().rotation().w(qs.w());
    mounts.transforms({m});
    static_pub->publish(mounts);
  }
  const std::vector<unav::testing::Link> links = {make_link(*gt_pub, *node), make_link(*pose_pub, *node),
                                                  make_link(*tf_pub, *node), make_link(*sensor_pub, *node),
                                                  make_link(*static_pub, *node)};
  ASSERT_TRUE(harness.match(links));
  const Eigen::AngleAxisd R(-0.7, Eigen::Vector3d::UnitZ());
  for (int i = 0; i < 80; ++i) {
    const double t = 0.1 * i, a = 0.05 * i;
    const Eigen::Vector3d p(4 * std::sin(a), 3 * std::cos(a), 9.0 + 0.2 * std::sin(2 * a));
    const Eigen::Quaterniond q(Eigen::AngleAxisd(a, Eigen::Vector3d::UnitZ()));
    const nav_msgs::msg::Odometry gt = odometry_at(t, p, q);
    const Eigen::Vector3d pe = 2.0 * (R * p) + Eigen::Vector3d(-1, 0.5, 2);
    const Eigen::Quaterniond qe = Eigen::Quaterniond(R) * q;
    geometry_msgs::msg::PoseStamped ps;
    ps.header() = gt.header();
    ps.header().frame_id("ext_map");
    ps.pose(unav::to_msg(pe, qe));
    tf2_msgs::msg::TFMessage tf;
    geometry_msgs::msg::TransformStamped tr;
    tr.header() = ps.header();
    tr.child_frame_id("ext_camera");
    tr.transform().translation(unav::to_vector3_msg(pe));
    tr.transform().rotation(ps.pose().orientation());
    geometry_msgs::msg::TransformStamped other = tr;  // another frame pair: ignored
    other.child_frame_id("something_else");
    other.transform().translation().x(100.0);
    tf.transforms({other, tr});
    gt_pub->publish(gt);
    pose_pub->publish(ps);
    tf_pub->publish(tf);
    Eigen::Isometry3d X_WB = Eigen::Isometry3d::Identity();
    X_WB.translation() = p;
    X_WB.linear() = q.toRotationMatrix();
    const Eigen::Isometry3d X_WS = X_WB * X_BS;
    const Eigen::Vector3d ps_s = 2.0 * (R * X_WS.translation()) + Eigen::Vector3d(-1, 0.5, 2);
    const Eigen::Quaterniond qs_s = Eigen::Quaterniond(R) * Eigen::Quaterniond(X_WS.linear());
    geometry_msgs::msg::PoseStamped sp;
    sp.header() = ps.header();
    sp.pose(unav::to_msg(ps_s, qs_s));
    sensor_pub->publish(sp);
    harness.spin();
  }
  ASSERT_TRUE(harness.delivered(links));
  node.reset();
  nlohmann::json j;
  std::ifstream(out + "/results.json") >> j;
  ASSERT_EQ(j.size(), 3u);
  for (const auto& row : j) {
    EXPECT_EQ(row["poses"], 80) << row["algorithm"];
    if (row["algorithm"] == "ext_tf") {
      EXPECT_EQ(row["alignment"], "se3");
      EXPECT_DOUBLE_EQ(row["scale"].get<double>(), 1.0);
      EXPECT_GT(row["ape_m"]["rmse"].get<double>(), 1.0);  // twice the size of a path of ~4 m radius
      continue;
    }
    EXPECT_EQ(row["alignment"], "sim3");
    EXPECT_LT(row["ape_m"]["rmse"].get<double>(), 1e-6) << row["algorithm"];
    EXPECT_LT(row["ape_rad"]["rmse"].get<double>(), 1e-6) << row["algorithm"];  // the mapped frame's attitude
    EXPECT_NEAR(row["scale"].get<double>(), 0.5, 1e-6) << row["algorithm"];
  }
  std::ifstream md(out + "/results.md");
  const std::string table((std::istreambuf_iterator<char>(md)), std::istreambuf_iterator<char>());
  EXPECT_NE(table.find("Sim(3) Umeyama alignment, SE(3) Umeyama alignment for ext_tf"), std::string::npos) << table;
  EXPECT_TRUE(std::filesystem::exists(out + "/ext_pose.tum"));
  EXPECT_TRUE(std::filesystem::exists(out + "/ext_tf.tum"));
}

namespace {
// Each of `bad` (after `given`) makes the node's construction fail with an error naming `key`.
void ExpectRefused(const std::vector<std::string>& given, const std::vector<std::string>& bad, const std::string& key) {
  for (const std::string& b : bad) {
    std::vector<std::string> args = EvaluatorRun::ros_params(given);
    args.insert(args.begin(), "trajectory_evaluator");
    args.insert(args.end(), {"-p", b});
    std::vector<const char*> argv;
    argv.reserve(args.size());
    for (const auto& a : args) argv.push_back(a.c_str());
    unav::Context ctx(static_cast<int>(argv.size()), argv.data(), unav::testing::test_context_options());
    try {
      unav::evaluation::TrajectoryEvaluator node(unav::NodeOptions{&ctx});
      ADD_FAILURE() << b << " accepted";
    } catch (const unav::ParameterError& e) {
      EXPECT_NE(std::string(e.what()).find("parameter '" + key + "'"), std::string::npos) << e.what();
    }
  }
}
}  // namespace

TEST(TrajectoryEvaluator, RejectsMalformedInputs) {
  ExpectRefused({}, {"inputs:=[nokind]", "inputs:=[a=radar:/x]", "inputs:=[a=tf:onlyparent]", "inputs:=[a=pose:/x@]"},
                "inputs");
}

TEST(TrajectoryEvaluator, RejectsBadEstimateAlignments) {
  ExpectRefused(
      {"estimates:=[orb_slam]"},
      {"estimate_alignments:=[ghost=se3]", "estimate_alignments:=[orb_slam=warp]", "estimate_alignments:=[orb_slam]"},
      "estimate_alignments");
}
