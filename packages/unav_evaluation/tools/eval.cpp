// unav_eval: evo_ape / evo_rpe on two TUM files, printed like evo. Also `unav eval ape|rpe ...`
// (the CLI runs this executable, so the framework does not link the evaluation package).
#include <CLI/CLI.hpp>

#include <cstdio>
#include <iostream>
#include <stdexcept>
#include <string>

#include "unav_evaluation/metrics.hpp"
#include "unav_evaluation/trajectory.hpp"

namespace {

/// A user-facing error: printed as one line, exit code 2.
struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct EvalOptions {
  std::string ref, est, align = "sim3", relation = "trans", delta_unit = "f";
  double max_diff = 0.01, offset = 0.0, delta = 1.0;
  bool all_pairs = false;
};

unav::evaluation::PoseRelation relation_from(const std::string& r) {
  using unav::evaluation::PoseRelation;
  if (r == "trans" || r == "trans_part") return PoseRelation::kTranslation;
  if (r == "angle_rad") return PoseRelation::kRotationAngleRad;
  if (r == "angle_deg") return PoseRelation::kRotationAngleDeg;
  if (r == "full") return PoseRelation::kFull;
  throw UsageError("--pose_relation '" + r + "': expected trans, angle_rad, angle_deg or full");
}

// `unav eval ape|rpe`: evo_ape / evo_rpe on two TUM files, printed like evo.
int eval(bool is_ape, const EvalOptions& o) {
  namespace ev = unav::evaluation;
  try {
    const ev::Trajectory ref_all = ev::read_tum(o.ref);
    const ev::Trajectory est_all = ev::read_tum(o.est);
    auto [ref, est] = ev::associate(ref_all, est_all, o.max_diff, o.offset);
    const ev::Alignment mode = ev::alignment_from_string(o.align);
    ev::align(est, ref, mode);
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
    std::printf("%s w.r.t. %s", is_ape ? "APE" : "RPE", what);
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
    std::printf("(%zu pose pairs of %zu reference and %zu estimated poses)\n", st.count, ref_all.size(),
                est_all.size());
    return 0;
  } catch (const ev::TrajectoryError& e) {
    throw UsageError(e.what());
  }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"unav eval: trajectory metrics on TUM files, as evo computes them", "unav eval"};
  app.require_subcommand(1);
  EvalOptions eval_opts;
  CLI::App* eval_ape = app.add_subcommand("ape", "absolute pose error (evo_ape)");
  CLI::App* eval_rpe = app.add_subcommand("rpe", "relative pose error (evo_rpe)");
  for (CLI::App* c : {eval_ape, eval_rpe}) {
    c->add_option("ref", eval_opts.ref, "reference trajectory (TUM)")->required();
    c->add_option("est", eval_opts.est, "estimated trajectory (TUM)")->required();
    c->add_option("-a,--align", eval_opts.align, "none, se3, sim3 (default), scale");
    c->add_option("-r,--pose_relation", eval_opts.relation, "trans (default), angle_rad, angle_deg, full");
    c->add_option("--t_max_diff", eval_opts.max_diff, "max timestamp difference for association [s] (0.01)");
    c->add_option("--t_offset", eval_opts.offset, "time offset added to est [s]");
  }
  eval_rpe->add_option("-d,--delta", eval_opts.delta, "delta between pose pairs (1)");
  eval_rpe->add_option("-u,--delta_unit", eval_opts.delta_unit, "f (frames, default) or m (meters)");
  eval_rpe->add_flag("--all_pairs", eval_opts.all_pairs, "use all pairs, not only consecutive ones");
  CLI11_PARSE(app, argc, argv);
  try {
    return eval(eval_ape->parsed(), eval_opts);
  } catch (const UsageError& e) {
    std::cerr << "unav: error: " << e.what() << std::endl;
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "unav: fatal: " << e.what() << std::endl;
    return 1;
  }
}
