// Helpers of the fuzz targets: parsers that read files get the input through a file in /dev/shm.
#pragma once

#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <string>

namespace unav::fuzz {

/// Writes the input to a per-process file with the given name suffix; returns its path.
inline std::string write_input(const uint8_t* data, size_t size, const std::string& suffix) {
  const std::string dir = access("/dev/shm", W_OK) == 0 ? "/dev/shm" : "/tmp";
  const std::string path = dir + "/unav_fuzz_" + std::to_string(getpid()) + suffix;
  FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) std::abort();
  if (size) std::fwrite(data, 1, size, f);
  std::fclose(f);
  return path;
}

}  // namespace unav::fuzz
