#include "unav_launch/package_index.hpp"

#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <sstream>

namespace fs = std::filesystem;

namespace unav::launch {
namespace {

std::vector<std::string> split_env(const char* variable) {
  std::vector<std::string> out;
  const char* value = std::getenv(variable);
  if (value == nullptr) {
    return out;
  }
  std::stringstream stream(value);
  std::string item;
  while (std::getline(stream, item, ':')) {
    while (item.size() > 1 && item.back() == '/') {
      item.pop_back();
    }
    if (!item.empty()) {
      out.push_back(item);
    }
  }
  return out;
}

bool is_dir(const fs::path& path) {
  std::error_code ec;
  return fs::is_directory(path, ec);
}

}  // namespace

std::vector<std::string> package_search_prefixes(const std::string& package) {
  std::vector<std::string> out;
  auto add = [&out](const std::string& prefix) {
    if (std::find(out.begin(), out.end(), prefix) == out.end()) {
      out.push_back(prefix);
    }
  };
  for (const char* variable : {"AMENT_PREFIX_PATH", "CMAKE_PREFIX_PATH"}) {
    for (const auto& prefix : split_env(variable)) {
      add(prefix);
    }
  }
  for (const auto& root : split_env("COLCON_PREFIX_PATH")) {
    add(root + "/" + package);
    add(root);
  }
  return out;
}

std::optional<std::string> find_package_prefix(const std::string& package) {
  if (package.empty() || package.find('/') != std::string::npos) {
    return std::nullopt;
  }
  for (const auto& prefix : package_search_prefixes(package)) {
    if (is_dir(fs::path(prefix) / "share" / package)) {
      return prefix;
    }
  }
  return std::nullopt;
}

std::optional<std::string> find_package_share(const std::string& package) {
  auto prefix = find_package_prefix(package);
  if (!prefix) {
    return std::nullopt;
  }
  return *prefix + "/share/" + package;
}

std::optional<std::string> find_executable(const std::string& package,
                                           const std::string& executable,
                                           std::vector<std::string>* searched_dirs) {
  if (package.empty() || package.find('/') != std::string::npos || executable.empty() ||
      executable.find('/') != std::string::npos) {
    return std::nullopt;
  }
  for (const auto& prefix : package_search_prefixes(package)) {
    if (!is_dir(fs::path(prefix) / "share" / package)) {
      continue;
    }
    const std::string dir = prefix + "/lib/" + package;
    if (searched_dirs != nullptr) {
      searched_dirs->push_back(dir);
    }
    const std::string path = dir + "/" + executable;
    std::error_code ec;
    if (fs::is_regular_file(path, ec) && ::access(path.c_str(), X_OK) == 0) {
      return path;
    }
  }
  return std::nullopt;
}

}  // namespace unav::launch
