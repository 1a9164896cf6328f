#include "unav_common/resources.hpp"

#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <sstream>

#include "unav_common/errors.hpp"

namespace fs = std::filesystem;

namespace unav::common {
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

bool path_exists(const fs::path& path) {
  std::error_code ec;
  return fs::exists(path, ec);
}

std::string absolute_normal(const fs::path& path) {
  std::error_code ec;
  const fs::path a = fs::absolute(path, ec);
  return (ec ? path : a).lexically_normal().string();
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

std::optional<std::string> find_executable(const std::string& package, const std::string& executable,
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

std::vector<std::string> resource_roots() {
  std::vector<std::string> roots = split_env("UNAV_RESOURCE_PATH");
  if (const auto share = find_package_share(kResourcePackage)) {
    if (std::find(roots.begin(), roots.end(), *share) == roots.end()) roots.push_back(*share);
  }
  return roots;
}

std::optional<std::string> try_find_resource(const std::string& path) {
  if (path.empty()) return std::nullopt;
  const fs::path p(path);
  if (p.is_absolute()) {
    if (path_exists(p)) return path;
    return std::nullopt;
  }
  for (const auto& root : resource_roots()) {
    const fs::path candidate = fs::path(root) / p;
    if (path_exists(candidate)) return absolute_normal(candidate);
  }
  return std::nullopt;
}

std::string resource_or_empty(const std::string& path) { return try_find_resource(path).value_or(""); }

std::string find_resource(const std::string& path) {
  if (auto found = try_find_resource(path)) return *found;
  if (path.empty()) throw ConfigError("", "resource", "\"\"", "empty path");
  std::string looked;
  if (fs::path(path).is_absolute()) {
    looked = "the file does not exist";
  } else {
    std::vector<std::string> places;
    for (const auto& root : split_env("UNAV_RESOURCE_PATH")) places.push_back(root + "/" + path);
    const auto share = find_package_share(kResourcePackage);
    if (share) places.push_back(*share + "/" + path);
    looked = "not found; looked in: ";
    if (places.empty()) {
      looked += "nothing";
    } else {
      for (std::size_t i = 0; i < places.size(); ++i) looked += (i ? ", " : "") + places[i];
    }
    if (!share)
      looked += " (" + std::string(kResourcePackage) +
                " is not installed: source install/setup.bash or set UNAV_RESOURCE_PATH)";
    else if (std::getenv("UNAV_RESOURCE_PATH") == nullptr)
      looked += " (UNAV_RESOURCE_PATH is not set)";
  }
  throw ConfigError("", "resource", path, looked);
}

}  // namespace unav::common
