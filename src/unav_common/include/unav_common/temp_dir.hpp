// A throwaway folder for tests and tools: created fresh under the system's temp folder (mkdtemp),
// removed with everything in it when the object goes away.
#pragma once

#include <string>

namespace unav::common {

class TempDir {
 public:
  /// Creates <tmp>/<prefix>.XXXXXX. Throws std::runtime_error when it cannot.
  explicit TempDir(const std::string& prefix = "unav");
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;

  const std::string& path() const { return path_; }
  /// Writes `text` to path()/`relative` (its folders created) and returns the full path.
  /// Throws std::runtime_error when the file cannot be written.
  std::string write(const std::string& relative, const std::string& text = "") const;

 private:
  std::string path_;
};

}  // namespace unav::common
