// unav_eval: evo_ape / evo_rpe / evo_traj on trajectory files (TUM, KITTI, EuRoC) or topics of a
// rosbag2, printed like evo. Also `unav eval ape|rpe|traj ...` (the CLI runs this executable, so the
// framework does not link the evaluation package).
#include <CLI/CLI.hpp>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <stdexcept>
#include <string>

#include <nlohmann/json.hpp>

#include "bag_trajectory.hpp"
#include "unav_evaluation/metrics.hpp"
#include "unav_evaluation/report.hpp"
#include "unav_evaluation/trajectory.hpp"

namespace fs = std::filesystem;
namespace ev = unav::evaluation;

namespace {

/// A user-facing error: printed as one line, exit code 2.
struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct EvalOptions {
  std::vector<std::string> inputs;  // ref est | bag ref_topic est_topic
  std::string format = "tum", ref_format, est_format;
  std::string align = "sim3", relation = "trans", delta_unit = "f";
  double max_diff = 0.01, offset = 0.0, delta = 1.0;
  bool all_pairs = false;
  std::string plot, save_results;
};

ev::PoseRelation relation_from(const std::string& r) {
  using ev::PoseRelation;
  if (r == "trans" || r == "trans_part") return PoseRelation::kTranslation;
  if (r == "angle_rad") return PoseRelation::kRotationAngleRad;
  if (r == "angle_deg") return PoseRelation::kRotationAngleDeg;
  if (r == "full") return PoseRelation::kFull;
  throw UsageError("--pose_relation '" + r + "': expected trans, angle_rad, angle_deg or full");
}

// The two trajectories named on the command line, read in their formats.
struct Inputs {
  ev::Trajectory ref, est;
  std::string ref_name, est_name;
  bool by_index = false;  // KITTI: no stamps, pairs by index
};

Inputs read_inputs(const EvalOptions& o) {
  Inputs in;
  if (o.format == "bag") {
    if (o.inputs.size() != 3) throw UsageError("--format bag takes BAG REF_TOPIC EST_TOPIC");
    in.ref = ev::read_bag_trajectory(o.inputs[0], o.inputs[1]);
    in.est = ev::read_bag_trajectory(o.inputs[0], o.inputs[2]);
    in.ref_name = o.inputs[1];
    in.est_name = o.inputs[2];
    return in;
  }
  if (o.inputs.size() != 2) throw UsageError("give REF EST (or --format bag BAG REF_TOPIC EST_TOPIC)");
  // evo's euroc mode: the reference is the EuRoC ground-truth CSV, the estimate a TUM file.
  const std::string rf = !o.ref_format.empty() ? o.ref_format : o.format;
  const std::string ef = !o.est_format.empty() ? o.est_format : (o.format == "euroc" ? "tum" : o.format);
  in.ref = ev::read_trajectory(o.inputs[0], ev::trajectory_format_from_string(rf));
  in.est = ev::read_trajectory(o.inputs[1], ev::trajectory_format_from_string(ef));
  in.ref_name = o.inputs[0];
  in.est_name = o.inputs[1];
  in.by_index = rf == "kitti" || ef == "kitti";
  return in;
}

nlohmann::json stats_json(const ev::Statistics& st) {
  return {{"rmse", st.rmse}, {"mean", st.mean}, {"median", st.median}, {"std", st.std},
          {"min", st.min},   {"max", st.max},   {"sse", st.sse},       {"count", st.count}};
}

int eval(bool is_ape, const EvalOptions& o) {
  try {
    const auto t0 = std::chrono::steady_clock::now();
    const Inputs in = read_inputs(o);
    auto [ref, est] =
        in.by_index ? ev::pair_by_index(in.ref, in.est) : ev::associate(in.ref, in.est, o.max_diff, o.offset);
    const ev::Alignment mode = ev::alignment_from_string(o.align);
    const ev::Sim3 S = ev::align(est, ref, mode);
    const ev::PoseRelation rel = relation_from(o.relation);
    ev::RpeOptions ro;
    ro.delta = o.delta;
    ro.all_pairs = o.all_pairs;
    if (o.delta_unit == "m")
      ro.unit = ev::DeltaUnit::kMeters;
    else if (o.delta_unit != "f")
      throw UsageError("--delta_unit '" + o.delta_unit + "': expected f (frames) or m (meters)");
    const auto errors = is_ape ? ev::ape(ref, est, rel) : ev::rpe(ref, est, rel, ro);
    const ev::Statistics st = ev::statistics(errors);
    const char* what = rel == ev::PoseRelation::kTranslation        ? "translation part (m)"
                       : rel == ev::PoseRelation::kRotationAngleRad ? "rotation angle in radians"
                       : rel == ev::PoseRelation::kRotationAngleDeg ? "rotation angle in degrees"
                                                                    : "full transformation (unit-less)";
    char title[256];
    std::snprintf(title, sizeof(title), "%s w.r.t. %s", is_ape ? "APE" : "RPE", what);
    std::printf("%s", title);
    if (!is_ape)
      std::printf(" for delta = %g (%s) using %s pairs", o.delta, o.delta_unit == "m" ? "m" : "frames",
                  o.all_pairs ? "all" : "consecutive");
    const char* align_text = mode == ev::Alignment::kSim3        ? "\n(with Sim(3) Umeyama alignment)"
                             : mode == ev::Alignment::kSE3       ? "\n(with SE(3) Umeyama alignment)"
                             : mode == ev::Alignment::kScaleOnly ? "\n(scale corrected)"
                                                                 : "\n(not aligned)";
    std::printf("%s\n\n", align_text);
    std::printf(
        "       max\t%f\n      mean\t%f\n    median\t%f\n       min\t%f\n      rmse\t%f\n       sse\t%f\n"
        "       std\t%f\n",
        st.max, st.mean, st.median, st.min, st.rmse, st.sse, st.std);
    std::printf("(%zu pose pairs of %zu reference and %zu estimated poses%s)\n", st.count, in.ref.size(), in.est.size(),
                in.by_index ? ", paired by index" : "");
    // Per-error stamps: the estimate's pose (APE) or the second pose of each pair (RPE).
    std::vector<double> stamps;
    std::vector<double> per_pose(est.size(), 0.0);
    if (is_ape) {
      stamps = est.stamps;
      per_pose = errors;
    } else {
      const auto pairs = ev::rpe_pairs(est, ro);
      for (size_t k = 0; k < pairs.size() && k < errors.size(); ++k) {
        stamps.push_back(est.stamps[pairs[k].second]);
        per_pose[pairs[k].second] = errors[k];
      }
    }
    if (!o.plot.empty()) {
      ev::write_error_map_png(o.plot, ref, est, per_pose, std::string(title) + (is_ape ? "" : " (at the 2nd pose)"));
      std::printf("plot: %s\n", o.plot.c_str());
    }
    if (!o.save_results.empty()) {
      nlohmann::json r;
      r["info"] = {{"title", title},
                   {"metric", is_ape ? "ape" : "rpe"},
                   {"pose_relation", o.relation},
                   {"alignment", o.align},
                   {"ref_name", in.ref_name},
                   {"est_name", in.est_name},
                   {"format", o.format},
                   {"paired_by", in.by_index ? "index" : "timestamp"},
                   {"t_max_diff", o.max_diff},
                   {"t_offset", o.offset},
                   {"ref_poses", in.ref.size()},
                   {"est_poses", in.est.size()}};
      if (!is_ape) r["info"]["delta"] = {{"value", o.delta}, {"unit", o.delta_unit}, {"all_pairs", o.all_pairs}};
      r["alignment"] = {
          {"scale", S.s},
          {"rotation",
           {S.R(0, 0), S.R(0, 1), S.R(0, 2), S.R(1, 0), S.R(1, 1), S.R(1, 2), S.R(2, 0), S.R(2, 1), S.R(2, 2)}},
          {"translation", {S.t.x(), S.t.y(), S.t.z()}}};
      r["stats"] = stats_json(st);
      r["timestamps"] = stamps;
      r["errors"] = errors;
      std::ofstream f(o.save_results);
      f << r.dump(1) << "\n";
      f.flush();
      if (!f) throw UsageError(o.save_results + ": cannot write");
      std::printf("results: %s\n", o.save_results.c_str());
    }
    if (std::getenv("UNAV_EVAL_TIMING"))
      std::fprintf(stderr, "unav_eval: %.3f s\n",
                   std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    return 0;
  } catch (const ev::TrajectoryError& e) {
    throw UsageError(e.what());
  }
}

// evo_traj: what each trajectory is; optionally aligned to a reference, plotted, converted.
int traj(const std::vector<std::string>& files, const std::string& format, const std::string& ref_file,
         const std::string& align, const std::string& plot, bool save_as_tum, bool save_as_kitti) {
  try {
    const ev::TrajectoryFormat fmt = ev::trajectory_format_from_string(format);
    ev::Trajectory ref;
    if (!ref_file.empty()) ref = ev::read_trajectory(ref_file, fmt);
    std::vector<std::pair<std::string, ev::Trajectory>> all;
    all.reserve(files.size());
    for (const auto& f : files) all.emplace_back(fs::path(f).stem().string(), ev::read_trajectory(f, fmt));
    auto info = [](const std::string& name, const ev::Trajectory& t) {
      const Eigen::Vector3d a = t.poses.front().translation(), b = t.poses.back().translation();
      std::printf(
          "name:\t%s\ninfos:\n\tduration (s)\t%.6f\n\tnr. of poses\t%zu\n\tpath length (m)\t%.6f\n"
          "\tpos_end (m)\t[%.6f %.6f %.6f]\n\tpos_start (m)\t[%.6f %.6f %.6f]\n\tt_end (s)\t%.6f\n"
          "\tt_start (s)\t%.6f\n",
          name.c_str(), t.stamps.back() - t.stamps.front(), t.size(), t.path_length(), b.x(), b.y(), b.z(), a.x(),
          a.y(), a.z(), t.stamps.back(), t.stamps.front());
    };
    if (!ref.empty()) info("reference " + fs::path(ref_file).stem().string(), ref);
    for (auto& [name, t] : all) {
      if (!ref.empty() && align != "none") {
        auto [r, e] = fmt == ev::TrajectoryFormat::kKitti ? ev::pair_by_index(ref, t) : ev::associate(ref, t);
        const ev::Sim3 S = ev::align(e, r, ev::alignment_from_string(align));
        for (auto& P : t.poses) {
          Eigen::Isometry3d Q = Eigen::Isometry3d::Identity();
          Q.linear() = S.R * P.linear();
          Q.translation() = S.s * (S.R * P.translation()) + S.t;
          P = Q;
        }
      }
      info(name, t);
      const std::string stem = fs::path(name).string();
      if (save_as_tum) ev::write_tum(stem + ".tum", t);
      if (save_as_kitti) ev::write_kitti(stem + ".kitti", t);
    }
    if (!plot.empty()) {
      ev::write_top_view_png(plot, ref.empty() ? all.front().second : ref, all);
      std::printf("plot: %s\n", plot.c_str());
    }
    return 0;
  } catch (const ev::TrajectoryError& e) {
    throw UsageError(e.what());
  }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"unav eval: trajectory metrics as evo computes them (TUM, KITTI, EuRoC files; rosbag2 topics)",
               "unav eval"};
  app.require_subcommand(1);
  EvalOptions o;
  CLI::App* eval_ape = app.add_subcommand("ape", "absolute pose error (evo_ape)");
  CLI::App* eval_rpe = app.add_subcommand("rpe", "relative pose error (evo_rpe)");
  for (CLI::App* c : {eval_ape, eval_rpe}) {
    c->add_option("inputs", o.inputs, "REF EST files, or with --format bag: BAG REF_TOPIC EST_TOPIC")
        ->required()
        ->expected(2, 3);
    c->add_option("--format", o.format,
                  "tum (default), kitti (pairs by index), euroc (ref: EuRoC csv, est: TUM), bag (topics or "
                  "/tf:PARENT.CHILD)")
        ->check(CLI::IsMember({"tum", "kitti", "euroc", "bag"}));
    c->add_option("--ref_format", o.ref_format, "format of REF when it differs (tum, kitti, euroc)");
    c->add_option("--est_format", o.est_format, "format of EST when it differs (tum, kitti, euroc)");
    c->add_option("-a,--align", o.align, "none, se3, sim3 (default), scale");
    c->add_option("-r,--pose_relation", o.relation, "trans (default), angle_rad, angle_deg, full");
    c->add_option("--t_max_diff", o.max_diff, "max timestamp difference for association [s] (0.01)");
    c->add_option("--t_offset", o.offset, "time offset added to est [s]");
    c->add_option("-p,--plot", o.plot, "PNG: reference and estimate coloured by the error");
    c->add_option("--save_results", o.save_results, "JSON: info, alignment, statistics, per-pose errors and stamps");
  }
  eval_rpe->add_option("-d,--delta", o.delta, "delta between pose pairs (1)");
  eval_rpe->add_option("-u,--delta_unit", o.delta_unit, "f (frames, default) or m (meters)");
  eval_rpe->add_flag("--all_pairs", o.all_pairs, "use all pairs, not only consecutive ones");
  std::vector<std::string> traj_files;
  std::string traj_format = "tum", traj_ref, traj_align = "none", traj_plot;
  bool save_tum = false, save_kitti = false;
  CLI::App* traj_cmd = app.add_subcommand("traj", "trajectory information, alignment, plots, conversion (evo_traj)");
  traj_cmd->add_option("files", traj_files, "trajectory files")->required();
  traj_cmd->add_option("--format", traj_format, "tum (default), kitti, euroc")
      ->check(CLI::IsMember({"tum", "kitti", "euroc"}));
  traj_cmd->add_option("--ref", traj_ref, "reference trajectory (same format)");
  traj_cmd->add_option("-a,--align", traj_align, "align to --ref: none (default), se3, sim3, scale");
  traj_cmd->add_option("-p,--plot", traj_plot, "PNG top view of the trajectories");
  traj_cmd->add_flag("--save_as_tum", save_tum, "write <name>.tum");
  traj_cmd->add_flag("--save_as_kitti", save_kitti, "write <name>.kitti");
  CLI11_PARSE(app, argc, argv);
  try {
    if (traj_cmd->parsed()) return traj(traj_files, traj_format, traj_ref, traj_align, traj_plot, save_tum, save_kitti);
    return eval(eval_ape->parsed(), o);
  } catch (const UsageError& e) {
    std::cerr << "unav: error: " << e.what() << std::endl;
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "unav: fatal: " << e.what() << std::endl;
    return 1;
  }
}
