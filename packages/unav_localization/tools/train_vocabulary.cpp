// unav_train_vocabulary: trains a bag-of-binary-words vocabulary (unav::localization::BowVocabulary)
// on ORB features of the png/jpg images in one or more directories and saves it.
//
//   unav_train_vocabulary --images DIR [--images DIR2 ...] --out FILE [--features 1000]
//       [--branching 10] [--levels 4] [--max-images N] [--iterations 10] [--seed 1]
//
// Exit codes: 0 success, 1 failure while running (unreadable images, training, writing),
// 2 bad command line (the message names the option).
#include <CLI/CLI.hpp>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include <opencv2/features2d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "unav_localization/bow_vocabulary.hpp"
#include "unav_localization/orb_extractor.hpp"

namespace fs = std::filesystem;
namespace ul = unav::localization;

namespace {

constexpr const char* kName = "unav_train_vocabulary";

/// Bad command line: printed as one line, exit code 2.
struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

bool IsImage(const fs::path& p) {
  std::string ext = p.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext == ".png" || ext == ".jpg" || ext == ".jpeg";
}

/// Images of each directory (not recursive), sorted by name, directories in the given order.
std::vector<fs::path> ListImages(const std::vector<std::string>& dirs) {
  std::vector<fs::path> all;
  for (const std::string& d : dirs) {
    std::error_code ec;
    if (!fs::is_directory(d, ec)) throw UsageError("--images " + d + ": not a directory");
    std::vector<fs::path> files;
    for (const auto& entry : fs::directory_iterator(d, ec))
      if (entry.is_regular_file(ec) && IsImage(entry.path())) files.push_back(entry.path());
    if (ec) throw UsageError("--images " + d + ": cannot list: " + ec.message());
    std::sort(files.begin(), files.end());
    all.insert(all.end(), files.begin(), files.end());
  }
  if (all.empty()) throw UsageError("--images: no .png/.jpg/.jpeg files in the given directories");
  return all;
}

/// max_images evenly spaced images of the list (all when max_images is 0 or not smaller).
std::vector<fs::path> Subsample(const std::vector<fs::path>& images, size_t max_images) {
  if (max_images == 0 || max_images >= images.size()) return images;
  std::vector<fs::path> out;
  for (size_t i = 0; i < max_images; ++i) out.push_back(images[i * images.size() / max_images]);
  return out;
}

double Seconds(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

int Run(const std::vector<std::string>& dirs, const std::string& out, int features, int max_images,
        const ul::VocabularyOptions& options) {
  if (features < 1) throw UsageError("--features must be >= 1, got " + std::to_string(features));
  if (max_images < 0) throw UsageError("--max-images must be >= 0 (0: all), got " + std::to_string(max_images));
  if (options.branching < 2 || options.branching > 64)
    throw UsageError("--branching must be in [2, 64], got " + std::to_string(options.branching));
  if (options.levels < 1 || options.levels > 10)
    throw UsageError("--levels must be in [1, 10], got " + std::to_string(options.levels));
  if (options.kmeans_iterations < 1)
    throw UsageError("--iterations must be >= 1, got " + std::to_string(options.kmeans_iterations));
  std::string msg;
  if (!options.IsValid(&msg)) throw UsageError("--branching/--levels: " + msg);
  const fs::path out_dir = fs::path(out).parent_path();
  std::error_code ec;
  if (!out_dir.empty() && !fs::is_directory(out_dir, ec))
    throw UsageError("--out " + out + ": directory " + out_dir.string() + " does not exist");

  const std::vector<fs::path> images = Subsample(ListImages(dirs), static_cast<size_t>(max_images));
  std::printf("%s: extracting up to %d ORB features from each of %zu images\n", kName, features, images.size());
  std::fflush(stdout);
  const auto t_extract = std::chrono::steady_clock::now();
  // The SLAM's own extractor (grid-spread ORB), so the words describe the features it matches.
  unav::localization::OrbOptions orb_options;
  orb_options.features = features;
  const unav::localization::OrbExtractor orb(orb_options);
  std::vector<cv::Mat> descriptors;
  size_t total = 0, skipped = 0;
  for (const fs::path& p : images) {
    const cv::Mat bgr = cv::imread(p.string(), cv::IMREAD_COLOR);
    cv::Mat gray;
    if (!bgr.empty()) cv::cvtColor(bgr, gray, cv::COLOR_BGR2GRAY);
    if (gray.empty()) {
      std::fprintf(stderr, "%s: warning: cannot read %s, skipped\n", kName, p.c_str());
      ++skipped;
      continue;
    }
    std::vector<cv::KeyPoint> keypoints;
    cv::Mat d;
    orb.Extract(gray, &keypoints, &d);
    total += static_cast<size_t>(d.rows);
    descriptors.push_back(d);
  }
  if (descriptors.empty()) {
    std::fprintf(stderr, "%s: error: none of the %zu images could be read\n", kName, images.size());
    return 1;
  }
  std::printf("%s: %zu images (%zu skipped), %zu descriptors (%.1f per image), extraction %.2f s\n", kName,
              descriptors.size(), skipped, total, static_cast<double>(total) / descriptors.size(), Seconds(t_extract));
  std::fflush(stdout);

  const auto t_train = std::chrono::steady_clock::now();
  const ul::BowVocabulary voc = ul::BowVocabulary::Train(descriptors, options);
  std::printf("%s: trained k = %d, L = %d: %zu words in %.2f s\n", kName, options.branching, options.levels, voc.size(),
              Seconds(t_train));
  voc.Save(out);
  std::printf("%s: wrote %s (%ju bytes)\n", kName, out.c_str(), static_cast<uintmax_t>(fs::file_size(out, ec)));
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Trains a bag-of-binary-words vocabulary on ORB features of images (png/jpg) and saves it.", kName};
  std::vector<std::string> dirs;
  std::string out;
  int features = 1000, max_images = 0;
  ul::VocabularyOptions options;
  app.option_defaults()->always_capture_default();  // --help shows the defaults
  app.add_option("--images", dirs, "directory of training images (repeatable; not recursive, sorted by name)")
      ->required();
  app.add_option("--out", out, "vocabulary file to write")->required();
  app.add_option("--features", features,
                 "ORB features per image (the SLAM's extractor: grid-spread, scale 1.2, 8 levels)");
  app.add_option("--branching", options.branching, "children per tree node, k");
  app.add_option("--levels", options.levels, "tree depth, L (up to k^L words)");
  app.add_option("--max-images", max_images, "use at most N images, evenly spaced over the sorted list (0: all)");
  app.add_option("--iterations", options.kmeans_iterations, "k-majority iterations per node");
  app.add_option("--seed", options.seed, "seed of the k-means++ seeding");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == static_cast<int>(CLI::ExitCodes::Success)) return app.exit(e);  // --help
    std::fprintf(stderr, "%s: error: %s\nRun with --help for the options.\n", kName, e.what());
    return 2;
  }
  try {
    return Run(dirs, out, features, max_images, options);
  } catch (const UsageError& e) {
    std::fprintf(stderr, "%s: error: %s\n", kName, e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: error: %s\n", kName, e.what());
    return 1;
  }
}
