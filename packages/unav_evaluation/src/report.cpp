#include "unav_evaluation/report.hpp"

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <iomanip>
#include <sstream>

#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace unav::evaluation {

AlgorithmResult evaluate(const Trajectory& gt, const Trajectory& est, const std::string& trajectory,
                         const std::string& algorithm, Alignment alignment, const RpeOptions& rpe_options,
                         double max_diff_s) {
  auto [ref, aligned] = associate(gt, est, max_diff_s);
  if (ref.size() < 3) throw TrajectoryError(algorithm + ": only " + std::to_string(ref.size()) + " associated poses");
  AlgorithmResult r;
  r.trajectory = trajectory;
  r.algorithm = algorithm;
  r.poses = ref.size();
  r.alignment = alignment;
  r.scale = align(aligned, ref, alignment).s;
  r.ape_m = statistics(ape(ref, aligned, PoseRelation::kTranslation));
  r.ape_rad = statistics(ape(ref, aligned, PoseRelation::kRotationAngleRad));
  r.rpe_m = statistics(rpe(ref, aligned, PoseRelation::kTranslation, rpe_options));
  r.rpe_rad = statistics(rpe(ref, aligned, PoseRelation::kRotationAngleRad, rpe_options));
  return r;
}

namespace {

nlohmann::json stats_json(const Statistics& s) {
  return {{"rmse", s.rmse}, {"mean", s.mean}, {"median", s.median}, {"std", s.std},
          {"min", s.min},   {"max", s.max},   {"sse", s.sse},       {"count", s.count}};
}

std::ofstream open_out(const std::string& path) {
  std::ofstream f(path);
  if (!f) throw TrajectoryError(path + ": cannot be written");
  return f;
}

}  // namespace

void write_results(const std::string& stem, const std::vector<AlgorithmResult>& results, Alignment alignment) {
  std::ofstream md = open_out(stem + ".md");
  md << "| trajectory | algorithm | APE [m] | RPE [m] | APE [rad] | RPE [rad] | poses | scale |\n"
     << "|---|---|---|---|---|---|---|---|\n"
     << std::fixed;
  for (const auto& r : results)
    md << "| " << r.trajectory << " | " << r.algorithm << " | " << std::setprecision(3) << r.ape_m.rmse << " | "
       << r.rpe_m.rmse << " | " << r.ape_rad.rmse << " | " << r.rpe_rad.rmse << " | " << r.poses << " | "
       << std::setprecision(4) << r.scale << " |\n";
  auto describe = [](Alignment a) {
    return a == Alignment::kSim3        ? "Sim(3) Umeyama alignment"
           : a == Alignment::kSE3       ? "SE(3) Umeyama alignment"
           : a == Alignment::kScaleOnly ? "scale-only alignment"
                                        : "no alignment";
  };
  std::string how = describe(alignment);
  // Rows aligned otherwise than the table's default (an estimate_alignments entry) say so.
  for (const auto& r : results)
    if (r.alignment != alignment) how += std::string(", ") + describe(r.alignment) + " for " + r.algorithm;
  md << "\nRMSE values; " << how
     << "; metrics as evo defines them (APE: pose error after "
        "alignment; RPE: relative motion error between consecutive pose pairs).\n";
  std::ofstream csv = open_out(stem + ".csv");
  csv << "trajectory,algorithm,ape_m,rpe_m,ape_rad,rpe_rad,poses,scale\n" << std::setprecision(9);
  for (const auto& r : results)
    csv << r.trajectory << ',' << r.algorithm << ',' << r.ape_m.rmse << ',' << r.rpe_m.rmse << ',' << r.ape_rad.rmse
        << ',' << r.rpe_rad.rmse << ',' << r.poses << ',' << r.scale << '\n';
  nlohmann::json j = nlohmann::json::array();
  for (const auto& r : results)
    j.push_back({{"trajectory", r.trajectory},
                 {"algorithm", r.algorithm},
                 {"poses", r.poses},
                 {"scale", r.scale},
                 {"alignment", alignment_name(r.alignment)},
                 {"ape_m", stats_json(r.ape_m)},
                 {"rpe_m", stats_json(r.rpe_m)},
                 {"ape_rad", stats_json(r.ape_rad)},
                 {"rpe_rad", stats_json(r.rpe_rad)}});
  open_out(stem + ".json") << j.dump(2) << '\n';
}

void write_top_view_png(const std::string& path, const Trajectory& gt,
                        const std::vector<std::pair<std::string, Trajectory>>& estimates, int size_px) {
  double min_n = 1e300, max_n = -1e300, min_e = 1e300, max_e = -1e300;
  auto extend = [&](const Trajectory& t) {
    for (const auto& P : t.poses) {
      min_n = std::min(min_n, P.translation().x());
      max_n = std::max(max_n, P.translation().x());
      min_e = std::min(min_e, P.translation().y());
      max_e = std::max(max_e, P.translation().y());
    }
  };
  extend(gt);
  for (const auto& e : estimates) extend(e.second);
  if (gt.empty()) throw TrajectoryError(path + ": no ground truth to plot");
  const double span = std::max({max_n - min_n, max_e - min_e, 1.0});
  const int margin = 60;
  const double px_per_m = (size_px - 2 * margin) / span;
  cv::Mat img(size_px, size_px, CV_8UC3, cv::Scalar(255, 255, 255));
  auto to_px = [&](const Eigen::Vector3d& p) {
    return cv::Point(static_cast<int>(margin + (p.y() - min_e) * px_per_m),
                     static_cast<int>(size_px - margin - (p.x() - min_n) * px_per_m));
  };
  const cv::Scalar colours[] = {{40, 40, 220}, {200, 120, 30}, {40, 160, 40}, {160, 40, 160}};
  auto draw = [&](const Trajectory& t, const cv::Scalar& c, int thickness) {
    for (size_t i = 1; i < t.size(); ++i)
      cv::line(img, to_px(t.poses[i - 1].translation()), to_px(t.poses[i].translation()), c, thickness, cv::LINE_AA);
  };
  draw(gt, cv::Scalar(0, 0, 0), 2);
  int y = 30;
  cv::putText(img, "ground truth", cv::Point(margin, y), cv::FONT_HERSHEY_SIMPLEX, 0.6, cv::Scalar(0, 0, 0), 1,
              cv::LINE_AA);
  for (size_t k = 0; k < estimates.size(); ++k) {
    const cv::Scalar c = colours[k % 4];
    draw(estimates[k].second, c, 1);
    y += 22;
    cv::putText(img, estimates[k].first, cv::Point(margin, y), cv::FONT_HERSHEY_SIMPLEX, 0.6, c, 1, cv::LINE_AA);
  }
  // 1 m (or 5 m) scale bar and axes labels.
  const double bar_m = span > 20 ? 5.0 : 1.0;
  const cv::Point b0(size_px - margin - static_cast<int>(bar_m * px_per_m), size_px - 25);
  cv::line(img, b0, cv::Point(size_px - margin, size_px - 25), cv::Scalar(0, 0, 0), 2);
  cv::putText(img, std::to_string(static_cast<int>(bar_m)) + " m", cv::Point(b0.x, size_px - 32),
              cv::FONT_HERSHEY_SIMPLEX, 0.5, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  cv::putText(img, "north ^  east >  (top view, world_ned)", cv::Point(margin, size_px - 10), cv::FONT_HERSHEY_SIMPLEX,
              0.45, cv::Scalar(90, 90, 90), 1, cv::LINE_AA);
  if (!cv::imwrite(path, img)) throw TrajectoryError(path + ": PNG write failed");
}

void write_error_map_png(const std::string& path, const Trajectory& ref, const Trajectory& est,
                         const std::vector<double>& errors, const std::string& title, int size_px) {
  if (errors.size() != est.size())
    throw TrajectoryError(path + ": " + std::to_string(errors.size()) + " errors for " + std::to_string(est.size()) +
                          " poses");
  if (est.empty()) throw TrajectoryError(path + ": nothing to plot");
  Eigen::Vector3d lo = est.poses[0].translation(), hi = lo;
  for (const Trajectory* t : {&ref, &est})
    for (const auto& P : t->poses) {
      lo = lo.cwiseMin(P.translation());
      hi = hi.cwiseMax(P.translation());
    }
  // The two axes with the largest extent: horizontal a, vertical b.
  const Eigen::Vector3d ext = hi - lo;
  int a = 0, b = 1;
  if (ext.z() > std::min(ext.x(), ext.y())) (ext.x() >= ext.y() ? b : a) = 2;
  if (a > b) std::swap(a, b);
  const char* names = "xyz";
  const double span = std::max({ext(a), ext(b), 1e-3});
  const int margin = 60, bar_w = 18;
  const double px_per_m = (size_px - 2 * margin - 3 * bar_w) / span;
  cv::Mat img(size_px, size_px, CV_8UC3, cv::Scalar(255, 255, 255));
  auto to_px = [&](const Eigen::Vector3d& p) {
    return cv::Point(static_cast<int>(margin + (p(a) - lo(a)) * px_per_m),
                     static_cast<int>(size_px - margin - (p(b) - lo(b)) * px_per_m));
  };
  for (size_t i = 1; i < ref.size(); ++i)
    cv::line(img, to_px(ref.poses[i - 1].translation()), to_px(ref.poses[i].translation()), cv::Scalar(150, 150, 150),
             1, cv::LINE_AA);
  const auto [mn_it, mx_it] = std::minmax_element(errors.begin(), errors.end());
  const double mn = *mn_it, mx = *mx_it, range = std::max(mx - mn, 1e-12);
  cv::Mat lut(1, 256, CV_8UC1);
  for (int i = 0; i < 256; ++i) lut.at<uint8_t>(0, i) = static_cast<uint8_t>(i);
  cv::Mat colours;
  cv::applyColorMap(lut, colours, cv::COLORMAP_JET);
  auto colour = [&](double e) {
    const int k = std::clamp(static_cast<int>(255.0 * (e - mn) / range), 0, 255);
    const cv::Vec3b c = colours.at<cv::Vec3b>(0, k);
    return cv::Scalar(c[0], c[1], c[2]);
  };
  for (size_t i = 1; i < est.size(); ++i)
    cv::line(img, to_px(est.poses[i - 1].translation()), to_px(est.poses[i].translation()),
             colour(0.5 * (errors[i - 1] + errors[i])), 2, cv::LINE_AA);
  // Colour bar with min and max.
  const int x0 = size_px - margin - bar_w, y0 = margin, y1 = size_px - margin;
  for (int y = y0; y < y1; ++y)
    cv::line(img, cv::Point(x0, y), cv::Point(x0 + bar_w, y),
             colour(mx - (mx - mn) * static_cast<double>(y - y0) / std::max(1, y1 - y0)), 1);
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.4g", mx);
  cv::putText(img, buf, cv::Point(x0 - 20, y0 - 8), cv::FONT_HERSHEY_SIMPLEX, 0.45, cv::Scalar(0, 0, 0), 1,
              cv::LINE_AA);
  std::snprintf(buf, sizeof(buf), "%.4g", mn);
  cv::putText(img, buf, cv::Point(x0 - 20, y1 + 18), cv::FONT_HERSHEY_SIMPLEX, 0.45, cv::Scalar(0, 0, 0), 1,
              cv::LINE_AA);
  cv::putText(img, title, cv::Point(margin, 30), cv::FONT_HERSHEY_SIMPLEX, 0.6, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  const std::string axes = std::string(1, names[a]) + " [m] >   " + names[b] + " [m] ^   reference grey";
  cv::putText(img, axes, cv::Point(margin, size_px - 15), cv::FONT_HERSHEY_SIMPLEX, 0.45, cv::Scalar(90, 90, 90), 1,
              cv::LINE_AA);
  if (!cv::imwrite(path, img)) throw TrajectoryError(path + ": PNG write failed");
}

namespace {
constexpr int kRowFields = 4 + 4 * 8;
void put_stats(std::ostream& o, const Statistics& st) {
  o << '\t' << st.rmse << '\t' << st.mean << '\t' << st.median << '\t' << st.std << '\t' << st.min << '\t' << st.max
    << '\t' << st.sse << '\t' << st.count;
}
}  // namespace

void write_result_rows(const std::string& path, const std::vector<AlgorithmResult>& results) {
  std::ofstream o(path);
  if (!o) throw TrajectoryError(path + ": cannot be written");
  o << std::setprecision(17);
  for (const auto& r : results) {
    if (r.trajectory.find('\t') != std::string::npos || r.algorithm.find('\t') != std::string::npos)
      throw TrajectoryError(path + ": names must not contain tabs");
    o << r.trajectory << '\t' << r.algorithm << '\t' << r.poses << '\t' << r.scale;
    for (const Statistics* st : {&r.ape_m, &r.rpe_m, &r.ape_rad, &r.rpe_rad}) put_stats(o, *st);
    o << '\n';
  }
  o.flush();
  if (!o) throw TrajectoryError(path + ": write failed");
}

std::vector<AlgorithmResult> read_result_rows(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw TrajectoryError(path + ": cannot be read");
  std::vector<AlgorithmResult> out;
  std::string line;
  int n = 0;
  while (std::getline(in, line)) {
    ++n;
    if (line.empty()) continue;
    std::vector<std::string> f;
    std::stringstream ss(line);
    std::string cell;
    while (std::getline(ss, cell, '\t')) f.push_back(cell);
    if (static_cast<int>(f.size()) != kRowFields)
      throw TrajectoryError(path + ":" + std::to_string(n) + ": expected " + std::to_string(kRowFields) +
                            " tab-separated fields, got " + std::to_string(f.size()));
    AlgorithmResult r;
    try {
      r.trajectory = f[0];
      r.algorithm = f[1];
      r.poses = static_cast<std::size_t>(std::stoull(f[2]));
      r.scale = std::stod(f[3]);
      size_t k = 4;
      for (Statistics* st : {&r.ape_m, &r.rpe_m, &r.ape_rad, &r.rpe_rad}) {
        st->rmse = std::stod(f[k++]);
        st->mean = std::stod(f[k++]);
        st->median = std::stod(f[k++]);
        st->std = std::stod(f[k++]);
        st->min = std::stod(f[k++]);
        st->max = std::stod(f[k++]);
        st->sse = std::stod(f[k++]);
        st->count = static_cast<size_t>(std::stoull(f[k++]));
      }
    } catch (const std::exception&) {
      throw TrajectoryError(path + ":" + std::to_string(n) + ": a field is not a number");
    }
    out.push_back(r);
  }
  return out;
}

}  // namespace unav::evaluation
