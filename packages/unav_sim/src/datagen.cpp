#include "unav_sim/datagen.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include <nlohmann/json.hpp>

#include <fstream>
#include <functional>
#include <iomanip>
#include <sstream>

#include "unav_datagen/dataset_writer.hpp"
#include "unav_datagen/manifest.hpp"
#include "unav_renderer/sonar_renderer.hpp"
#include "unav_scene/sonar.hpp"
#include "unav_sim/episode.hpp"
#include "unav_sim/scenario_run.hpp"

namespace fs = std::filesystem;

namespace unav::sim {
namespace {

// The sonar output of a sample: pings as 8-bit polar PNGs (row = range bin, nearest first;
// column = beam, port to starboard; side-scan: port, starboard) under sonar/<name>/, an index
// with the acoustic frame's pose per ping, and the geometry for the manifest.
class SonarOutput {
 public:
  SonarOutput(const std::string& root, const std::string& config, const std::string& name, const World& world,
              std::uint64_t seed, std::shared_ptr<unav::renderer::EglContext> context)
      : model_(unav::scene::load_sonar(config, name)), dir_(fs::path(root) / "sonar" / name) {
    unav::renderer::SonarOptions o;
    o.seed = seed;
    sonar_ = std::make_unique<unav::renderer::SonarRenderer>(world, std::vector<unav::scene::SonarModel>{model_}, o,
                                                             std::move(context));
    fs::create_directories(dir_);
    index_.open(dir_ / "pings.txt");
    if (!index_) throw unav::ConfigError((dir_ / "pings.txt").string() + ": cannot write");
    index_ << "# t_s file x y z qx qy qz qw  (frame " << name << "_link in world_ned: z forward, x up)\n";
    index_ << std::fixed << std::setprecision(9);
  }
  double period() const { return 1.0 / model_.ping_rate_hz; }
  void ping(const Eigen::Isometry3d& X_WB, double t) {
    const auto p = sonar_->ping(X_WB, model_.name, t);
    std::ostringstream f;
    f << std::fixed << std::setprecision(6) << t << ".png";
    unav::renderer::write_png_mono(p.image, p.channels, p.bins, (dir_ / f.str()).string());
    const Eigen::Quaterniond q(p.X_WS.linear());
    const Eigen::Vector3d x = p.X_WS.translation();
    index_ << t << ' ' << f.str() << ' ' << x.x() << ' ' << x.y() << ' ' << x.z() << ' ' << q.x() << ' ' << q.y() << ' '
           << q.z() << ' ' << q.w() << '\n';
    if (pings_++ == 0) {
      sound_speed_ = p.sound_speed_mps;
      absorption_ = p.absorption_db_per_m;
      azimuths_ = p.azimuth_rad;
    }
  }
  std::string manifest_json() {
    index_.close();
    const Eigen::Isometry3d X = model_.frame_acoustic();
    const Eigen::Quaterniond q(X.linear());
    nlohmann::json j = {
        {"name", model_.name},
        {"type", model_.type_name()},
        {"frame", model_.name + "_link"},
        {"parent_frame", "base_link_frd"},
        {"frame_axes", "z forward (boresight), x up (marine_acoustic_msgs)"},
        {"mount_xyz_m", {X.translation().x(), X.translation().y(), X.translation().z()}},
        {"mount_quaternion_xyzw", {q.x(), q.y(), q.z(), q.w()}},
        {"channels", model_.channels()},
        {"bins", model_.bins},
        {"min_range_m", model_.min_range_m},
        {"max_range_m", model_.max_range_m},
        {"bin_width_m", model_.bin_width_m()},
        {"channel_azimuth_rad", azimuths_},
        {"horizontal_aperture_rad", model_.horizontal_aperture_rad},
        {"vertical_aperture_rad", model_.vertical_aperture_rad},
        {"tilt_rad", model_.tilt_rad},
        {"frequency_hz", model_.frequency_hz},
        {"sound_speed_mps", sound_speed_},
        {"absorption_db_per_m", absorption_},
        {"tvg_db_per_decade", model_.tvg ? model_.tvg_db_per_decade : 0.0},
        {"gain_db", model_.gain_db},
        {"dynamic_range_db", model_.dynamic_range_db},
        {"display", model_.display},
        {"display_gamma", model_.display_gamma},
        {"ping_rate_hz", model_.ping_rate_hz},
        {"pings", pings_},
        {"index", "sonar/" + model_.name + "/pings.txt"},
        {"png", std::string("mono8, row = range bin (centre min_range_m + (k + 0.5) bin_width_m), "
                            "column = channel; value ") +
                    (model_.display == "gamma" ? "255 (I 10^(gain_db / 10))^(display_gamma / 2), clamped"
                                               : "255 (1 + (10 log10 I + gain_db) / dynamic_range_db), "
                                                 "clamped")}};
    return j.dump();
  }

 private:
  unav::scene::SonarModel model_;
  fs::path dir_;
  std::unique_ptr<unav::renderer::SonarRenderer> sonar_;
  std::ofstream index_;
  std::uint64_t pings_ = 0;
  double sound_speed_ = 0.0, absorption_ = 0.0;
  std::vector<float> azimuths_;
};

// The vehicle's navigation sensors as they sampled, each at its own rate and every sample kept
// (checked after every physics step): CSV files under nav/ with a header line, times in
// simulated seconds; the tether's length and pull at every frame when the vehicle has one.
class NavOutput {
 public:
  NavOutput(const fs::path& root, const physics::Simulator& sim) : dir_(root / "nav") {
    fs::create_directories(dir_);
    open(&pressure_, "pressure.csv", "t,valid,pressure_pa,depth_m");
    open(&dvl_, "dvl.csv",
         "t,valid,vx_mps,vy_mps,vz_mps,altitude_m,locked_beams,"
         "range0_m,range1_m,range2_m,range3_m,beam_velocity0_mps,beam_velocity1_mps,beam_velocity2_mps,"
         "beam_velocity3_mps");
    open(&usbl_, "usbl.csv",
         "ping_t,t,valid,range_m,azimuth_rad,elevation_rad,x_m,y_m,z_m,truth_x_m,truth_y_m,truth_z_m,"
         "truth_range_m,outlier");
    if (sim.tether() != nullptr) open(&tether_, "tether.csv", "t,length_m,force_x_n,force_y_n,force_z_n");
  }
  void after_step(const physics::Simulator& sim) {
    const physics::SensorReadings& r = sim.sensors();
    if (fresh(&pressure_, r.pressure.seq)) {
      pressure_.out << r.pressure.stamp << ',' << r.pressure.valid << ',' << r.pressure.pressure_pa << ','
                    << r.pressure.depth_m << '\n';
    }
    if (fresh(&dvl_, r.dvl.seq)) {
      const physics::DvlReading& d = r.dvl;
      std::ofstream& o = dvl_.out;
      o << d.stamp << ',' << d.valid << ',' << d.velocity_B.x() << ',' << d.velocity_B.y() << ',' << d.velocity_B.z()
        << ',' << d.altitude_m << ',' << d.locked_beams;
      for (int i = 0; i < 4; ++i) o << ',' << (d.beam_valid[i] ? d.beam_range_m[i] : std::nan(""));
      for (int i = 0; i < 4; ++i) o << ',' << (d.beam_valid[i] ? d.beam_velocity[i] : std::nan(""));
      o << '\n';
    }
    if (fresh(&usbl_, r.usbl.seq)) {
      const physics::UsblReading& u = r.usbl;
      usbl_.out << u.ping_stamp << ',' << u.stamp << ',' << u.valid << ',' << u.range_m << ',' << u.azimuth_rad << ','
                << u.elevation_rad << ',' << u.p_W.x() << ',' << u.p_W.y() << ',' << u.p_W.z() << ',' << u.truth_p_W.x()
                << ',' << u.truth_p_W.y() << ',' << u.truth_p_W.z() << ',' << u.truth_range_m << ',' << u.outlier
                << '\n';
    }
  }
  void at_frame(const physics::Simulator& sim) {
    if (sim.tether() == nullptr) return;
    const Eigen::Vector3d f = sim.tether_force_W();
    tether_.out << sim.time() << ',' << sim.tether()->length() << ',' << f.x() << ',' << f.y() << ',' << f.z() << '\n';
    ++tether_.rows;
  }
  std::string manifest_json() {
    const bool tethered = tether_.out.is_open();
    for (Csv* c : {&pressure_, &dvl_, &usbl_, &tether_}) {
      if (!c->out.is_open()) continue;
      c->out.flush();
      if (!c->out) throw unav::ConfigError(dir_.string() + ": cannot write the navigation sensors' files");
      c->out.close();
    }
    nlohmann::json j = {
        {"pressure", {{"file", "nav/pressure.csv"}, {"rows", pressure_.rows}, {"units", "Pa, m (depth)"}}},
        {"dvl",
         {{"file", "nav/dvl.csv"},
          {"rows", dvl_.rows},
          {"frame", "base_link_frd"},
          {"units", "m/s seabed-relative velocity (FRD), m; per beam slant range and velocity, nan when unlocked"}}},
        {"usbl",
         {{"file", "nav/usbl.csv"},
          {"rows", usbl_.rows},
          {"frame", "world_ned (x y z), transceiver axes (azimuth, elevation)"},
          {"units", "s (interrogation, reply), m, rad; truth_* the transponder when the ping reached it"}}}};
    if (tethered)
      j["tether"] = {{"file", "nav/tether.csv"}, {"rows", tether_.rows}, {"units", "m, N (pull on the vehicle, NED)"}};
    return j.dump();
  }

 private:
  struct Csv {
    std::ofstream out;
    std::uint64_t seq = 0;   ///< the sensor's last sample written
    std::uint64_t rows = 0;  ///< rows written
  };
  /// True (and counted) when `seq` is a sample not written yet.
  static bool fresh(Csv* c, std::uint64_t seq) {
    if (seq == c->seq) return false;
    c->seq = seq;
    ++c->rows;
    return true;
  }
  void open(Csv* c, const std::string& name, const std::string& header) {
    c->out.open(dir_ / name);
    if (!c->out) throw unav::ConfigError((dir_ / name).string() + ": cannot write");
    c->out << std::setprecision(17) << "# " << header << '\n';
  }
  fs::path dir_;
  Csv pressure_, dvl_, usbl_, tether_;
};

// The sample as a scenario file, world/scenario.yaml (beside its current.yaml when it has one):
// the base world with the sample's generated world (`generate:`, the same draw, so the same world),
// the camera and render switches the sample was rendered with, the start of its path and the path
// as a mission (waypoints ~1 m apart, each leg as long as the setpoint takes at `speed`), so
// `unav run` and every launch file (`scenario:=`) re-fly it. The camera's noise/exposure/gain
// draws are the spec's and not in it.
void write_sample_scenario(unav::scene::Scenario sc, const std::vector<unav::datagen::PathPoint>& path, double speed,
                           double duration, const std::string& dir, bool current) {
  constexpr double kRadToDeg = 180.0 / M_PI;
  if (current) sc.current = "current.yaml";
  sc.vehicle.initial_position = path.front().p_W;
  sc.vehicle.initial_rpy_deg = Eigen::Vector3d(0.0, 0.0, path.front().yaw * kRadToDeg);
  sc.mission.duration_s = duration;
  sc.mission.speed_mps = speed;
  sc.mission.waypoints.clear();
  Eigen::Vector3d last = path.front().p_W;
  for (std::size_t i = 1; i < path.size(); ++i) {
    const double d = (path[i].p_W - last).norm();
    if (d < 1.0 && i + 1 < path.size()) continue;
    unav::scene::ScenarioWaypoint w;
    w.position = path[i].p_W;
    w.yaw_deg = path[i].yaw * kRadToDeg;
    w.hold_s = std::max(d / speed, 1e-3);
    sc.mission.waypoints.push_back(w);
    last = path[i].p_W;
  }
  write_concrete_scenario(sc, dir);
}

}  // namespace

std::string sample_name(std::uint64_t index) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "sample_%06llu", static_cast<unsigned long long>(index));
  return buf;
}

bool sample_finished(const std::string& out, std::uint64_t index) {
  std::error_code ec;
  return fs::exists(fs::path(out) / sample_name(index) / "manifest.json", ec);
}

SampleResult generate_sample(const unav::datagen::RandomizationSpec& spec, std::uint64_t index, const std::string& out,
                             const std::atomic<bool>* stop, const std::function<void(std::uint64_t)>& on_frame) {
  const auto t0 = std::chrono::steady_clock::now();
  const unav::datagen::DatagenSample s = spec.sample(index);
  const auto seed = static_cast<std::uint64_t>(s.seed);
  const fs::path final_dir = fs::path(out) / sample_name(index);
  const fs::path partial = fs::path(out) / ("." + sample_name(index) + ".partial");
  fs::remove_all(partial);
  fs::create_directories(partial);

  // The sample as a scenario, built by the one builder (scenario_world, load_episode_setup,
  // Episode): its world generated over the base world by the sample's `world` draw.
  unav::scene::Scenario sc;
  sc.name = sample_name(index);
  sc.seed = static_cast<int64_t>(seed);
  sc.world = s.base_world;
  sc.generate = s.world;
  const std::string current_file = unav::datagen::write_sample_current(s, (partial / "world").string());
  sc.current = current_file;
  World world = unav::scene::scenario_world(sc);
  sc.cameras.config = s.cameras_config;
  const std::string& camera = s.output.camera;
  sc.cameras.names = {camera};
  sc.cameras.width = s.output.width;
  sc.cameras.height = s.output.height;
  sc.cameras.rate_hz = s.output.rate_hz;
  sc.render = s.render;
  EpisodeSetup setup = load_episode_setup(sc);
  setup.cameras[0].noise_stddev = s.camera.noise_stddev * s.camera.gain;
  setup.cameras[0].exposure = s.camera.exposure * s.camera.gain;
  setup.cameras[0].jpeg_quality = s.camera.jpeg_quality;
  setup.cameras[0].white_balance.mode = s.camera.white_balance;
  // Behind a port, the intrinsics a dataset user needs are the water-side model.
  const unav::scene::CameraModel cam = setup.cameras[0].water_equivalent();

  const double rate = s.output.rate_hz;
  const double speed = s.trajectory.speed_mps;
  const double step = 0.05;  // path resolution [m]
  const auto path = unav::datagen::plan_trajectory(s, world, step);

  Episode ep(setup, world);
  RigidBodyState x0;
  x0.p_WB_W = path.front().p_W;
  x0.q_WB = Eigen::AngleAxisd(path.front().yaw, Eigen::Vector3d::UnitZ());
  ep.reset(seed, x0);
  write_sample_scenario(sc, path, speed, s.output.frames / rate, (partial / "world").string(), !current_file.empty());

  const std::string& format = s.output.format;
  auto writer = unav::datagen::make_sequence_writer(format, partial.string());
  unav::datagen::CameraIntrinsics k;
  k.width = cam.width;
  k.height = cam.height;
  k.fx = cam.fx;
  k.fy = cam.fy;
  k.cx = cam.cx;
  k.cy = cam.cy;
  k.distortion.assign(cam.distortion.data(), cam.distortion.data() + 5);
  writer->write_camera(k);
  Eigen::Isometry3d X_BC = Eigen::Isometry3d::Identity();
  X_BC.linear() = cam.X_BC.linear();
  X_BC.translation() = cam.X_BC.translation();
  writer->set_camera_mount(X_BC);

  const std::string& sonar_name = s.output.sonar;
  std::unique_ptr<SonarOutput> sonar;
  if (!sonar_name.empty())
    sonar = std::make_unique<SonarOutput>(partial.string(), s.sonars_config, sonar_name, world, seed,
                                          ep.renderer().shared_context());
  NavOutput nav(partial, ep.simulator());
  // The IMU log: the vehicle's IMU (its rate, noise and bias: sensors.imu) when it has one, else the
  // true angular rate and specific force at the control period.
  const bool imu_sensor = setup.plant.sensors.imu.enabled;
  std::uint64_t imu_seq = 0;
  const std::function<void()> record_nav = [&nav, &ep, &writer, &imu_seq, imu_sensor] {
    nav.after_step(ep.simulator());
    const physics::ImuReading& imu = ep.simulator().sensors().imu;
    if (imu_sensor && imu.valid && imu.seq != imu_seq) {
      imu_seq = imu.seq;
      writer->write_imu(imu.stamp, imu.angular_rate_B, imu.specific_force_B);
    }
  };
  double next_ping_t = 0.0;
  auto body_pose = [&ep] {
    Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
    X.linear() = ep.state().q_WB.toRotationMatrix();
    X.translation() = ep.state().p_WB_W;
    return X;
  };
  if (sonar) {
    sonar->ping(body_pose(), 0.0);  // pings at multiples of the sonar's period, like the frames
    next_ping_t = sonar->period();
  }
  const auto frames = static_cast<std::uint64_t>(s.output.frames);
  const double control_period = setup.scenario.control.period;
  const Eigen::Vector3d g_W(0.0, 0.0, setup.simulator.environment.gravity);
  SampleResult r;
  double t = 0.0;
  for (std::uint64_t f = 0; f < frames; ++f) {
    if (stop && stop->load()) {
      writer->close();
      r.frames = f;
      r.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      return r;  // the .partial folder stays: incomplete, never counted as finished
    }
    const double t_frame = static_cast<double>(f) / rate;
    // Fly to the frame time, a control period at a time, the setpoint moving along the path.
    while (t + 0.5 * control_period < t_frame) {
      const double arc = speed * (t + control_period);
      const auto& target = path[std::min(path.size() - 1, static_cast<size_t>(arc / step))];
      ep.set_setpoint(unav::control::PoseSetpoint::FromPositionYaw(target.p_W, target.yaw));
      ep.advance(control_period, record_nav);
      t = ep.time();
      const auto& x = ep.state();
      const auto nu_dot = ep.simulator().acceleration();
      // Specific force in body axes: d/dt v (inertial) minus gravity, FRD.
      const Eigen::Vector3d f_B = nu_dot.head<3>() + x.w_WB_B.cross(x.v_WB_B) - x.q_WB.conjugate() * g_W;
      if (!imu_sensor) writer->write_imu(t, x.w_WB_B, f_B);
      if (sonar && t + 0.5 * control_period >= next_ping_t) {
        sonar->ping(body_pose(), t);
        next_ping_t += sonar->period();
      }
    }
    Frame fr = ep.render(camera);
    nav.at_frame(ep.simulator());
    const auto& x = ep.state();
    Eigen::Isometry3d X_WB = Eigen::Isometry3d::Identity();
    X_WB.linear() = x.q_WB.toRotationMatrix();
    X_WB.translation() = x.p_WB_W;
    Eigen::Isometry3d X_WC = Eigen::Isometry3d::Identity();
    X_WC.linear() = fr.X_WC.linear();
    X_WC.translation() = fr.X_WC.translation();
    writer->write_rgb(t_frame, fr.width, fr.height, fr.rgb.data());
    writer->write_depth(t_frame, fr.width, fr.height, fr.depth.data());
    writer->write_segmentation(t_frame, fr.width, fr.height, fr.seg.data());
    writer->write_pose(t_frame, X_WC, X_WB);
    r.frames = f + 1;
    if (on_frame) on_frame(r.frames);
  }
  writer->close();

  unav::datagen::ManifestInput mi;
  mi.format = format;
  mi.camera = camera;
  mi.intrinsics = k;
  mi.mount_known = true;
  mi.X_BC = X_BC;
  mi.source = {{"spec", fs::path(spec.file()).filename().string()},
               {"world", "world/scenario.yaml"},
               {"base_world", fs::path(s.base_world).filename().string()},
               {"generator", "unav datagen (in-process episode)"}};
  mi.labels = scene::seg_class_labels();
  YAML::Emitter e;
  e.SetDoublePrecision(17);
  e << unav::common::ToYaml(s);
  mi.randomization_yaml = e.c_str();
  mi.extra_entries = {"world", "nav"};
  mi.extra_json["nav"] = nav.manifest_json();
  if (sonar) {
    mi.extra_entries.emplace_back("sonar");
    mi.extra_json["sonar"] = sonar->manifest_json();
  }
  unav::datagen::write_manifest(*writer, mi);  // the last file: its presence marks completion
  fs::remove_all(final_dir);
  fs::rename(partial, final_dir);
  r.finished = true;
  r.dir = final_dir.string();
  r.solver_failures = ep.solver_failures();
  r.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return r;
}

}  // namespace unav::sim
