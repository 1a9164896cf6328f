// Helpers of the fuzz targets: parsers that read files get the input through a file in /dev/shm.
#pragma once

#include <unistd.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

namespace unav::fuzz {

/// The input files of this process, removed at exit (a CI run used to leave one per target
/// and run in /dev/shm).
struct InputFiles {
  std::vector<std::string> paths;
  InputFiles() = default;
  InputFiles(const InputFiles&) = delete;
  InputFiles& operator=(const InputFiles&) = delete;
  ~InputFiles() {
    for (const auto& p : paths) unlink(p.c_str());
  }
};

inline InputFiles& input_files() {
  static InputFiles files;
  return files;
}

/// Writes the input to a per-process file with the given name suffix; returns its path.
inline std::string write_input(const uint8_t* data, size_t size, const std::string& suffix) {
  const std::string dir = access("/dev/shm", W_OK) == 0 ? "/dev/shm" : "/tmp";
  const std::string path = dir + "/unav_fuzz_" + std::to_string(getpid()) + suffix;
  auto& known = input_files().paths;
  if (std::find(known.begin(), known.end(), path) == known.end()) known.push_back(path);
  FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) std::abort();
  if (size) std::fwrite(data, 1, size, f);
  std::fclose(f);
  return path;
}

}  // namespace unav::fuzz
