// Results of a localization benchmark in the layout of the paper's Table II, written as
// Markdown, CSV and JSON, and a top-view (north-east) trajectory plot as PNG.
#pragma once

#include <string>
#include <vector>

#include "unav_evaluation/metrics.hpp"

namespace unav::evaluation {

struct AlgorithmResult {
  std::string trajectory;  ///< e.g. "linear", "with loop"
  std::string algorithm;   ///< e.g. "orb_slam", "klt_vo"
  Statistics ape_m, rpe_m, ape_rad, rpe_rad;
  std::size_t poses = 0;  ///< associated poses
  double scale = 1.0;     ///< Sim(3) scale applied to the estimate
  Alignment alignment = Alignment::kSim3;
};

/// Evaluates one estimate against ground truth: association (max_diff), alignment, APE and RPE
/// (translation and rotation angle). Throws TrajectoryError (no overlap, too few poses).
AlgorithmResult evaluate(const Trajectory& gt, const Trajectory& est, const std::string& trajectory,
                         const std::string& algorithm, Alignment alignment = Alignment::kSim3,
                         const RpeOptions& rpe_options = {}, double max_diff_s = 0.02);

/// Writes <stem>.md, <stem>.csv and <stem>.json (rmse values in the Table II columns, plus every
/// statistic in the JSON). Throws TrajectoryError naming the file on I/O failure.
void write_results(const std::string& stem, const std::vector<AlgorithmResult>& results,
                   Alignment alignment = Alignment::kSim3);

/// Rows of results in a lossless tab-separated form (one AlgorithmResult per line, every
/// statistic), so several runs can be combined into one table. read_result_rows throws
/// TrajectoryError "<file>:<line>: ..." for a malformed line.
void write_result_rows(const std::string& path, const std::vector<AlgorithmResult>& results);
std::vector<AlgorithmResult> read_result_rows(const std::string& path);

/// Top view: x = east (right), y = north (up), ground truth black, estimates (already aligned)
/// in colours, with a legend and a metre scale bar. Throws TrajectoryError on I/O failure.
void write_top_view_png(const std::string& path, const Trajectory& gt,
                        const std::vector<std::pair<std::string, Trajectory>>& estimates, int size_px = 800);

/// evo's `--plot` for APE: the reference (grey) and the aligned estimate coloured by each pose's
/// error (blue = min, red = max, colour bar in the error's unit), on the plane of the two axes
/// with the largest extent (x-y for NED, x-z for a KITTI camera path). errors.size() ==
/// est.size(). Throws TrajectoryError on I/O failure or a size mismatch.
void write_error_map_png(const std::string& path, const Trajectory& ref, const Trajectory& est,
                         const std::vector<double>& errors, const std::string& title, int size_px = 800);

}  // namespace unav::evaluation
