// The type registry: finds IDL files by type name under its roots and keeps what the parser
// (idl_parser.cpp) read; ROS <-> DDS type names.
#include "idl_internal.hpp"

#include <unistd.h>
#include <cstdlib>
#include <set>
#include <sstream>

namespace unav::introspection {

IdlError::IdlError(const std::string& file, int line, const std::string& message)
    : std::runtime_error(line > 0 ? file + ":" + std::to_string(line) + ": " + message : file + ": " + message),
      file_(file),
      line_(line) {}

std::string ros_to_dds_name(const std::string& ros_name) {
  const std::vector<std::string> parts = split(ros_name, "/");
  const bool ok = (parts.size() == 2 || parts.size() == 3) && std::all_of(parts.begin(), parts.end(), is_identifier);
  if (!ok) {
    throw UnknownTypeError("malformed ROS type name '" + ros_name + "' (expected 'pkg/msg/Type' or 'pkg/Type')");
  }
  const std::string& kind = parts.size() == 3 ? parts[1] : std::string("msg");
  return parts[0] + "::" + kind + "::dds_::" + parts.back() + "_";
}

std::string dds_to_ros_name(const std::string& dds_name) {
  std::string name = dds_name;
  if (name.rfind("::", 0) == 0) name = name.substr(2);
  const std::vector<std::string> parts = split(name, "::");
  const bool ids = std::all_of(parts.begin(), parts.end(), is_identifier);
  if (ids && parts.size() == 4 && parts[2] == "dds_" && parts[3].size() > 1 && parts[3].back() == '_') {
    return parts[0] + "/" + parts[1] + "/" + parts[3].substr(0, parts[3].size() - 1);
  }
  if (ids && parts.size() == 3 && parts[1] != "dds_") {
    return parts[0] + "/" + parts[1] + "/" + parts[2];
  }
  throw UnknownTypeError("malformed DDS type name '" + dds_name +
                         "' (expected 'pkg::msg::dds_::Type_' or 'pkg::msg::Type')");
}

struct TypeRegistry::Impl : detail::RegistryState {};

namespace {

// Relative IDL path for a scoped name: "a::msg::dds_::B_" and "a::msg::B" -> "a/msg/B.idl".
std::optional<std::string> relative_idl_path(const std::string& scoped_name) {
  const std::vector<std::string> parts = split(scoped_name, "::");
  if (!std::all_of(parts.begin(), parts.end(), is_identifier)) return std::nullopt;
  const size_t n = parts.size();
  if (n >= 4 && parts[n - 2] == "dds_" && parts[n - 1].size() > 1 && parts[n - 1].back() == '_') {
    const std::string type = parts[n - 1].substr(0, parts[n - 1].size() - 1);
    return join(parts, "/", 0, n - 2) + "/" + type + ".idl";
  }
  if (n >= 3) return join(parts, "/") + ".idl";
  return std::nullopt;
}

// Scoped names a user-given type name may stand for, most likely first.
std::vector<std::string> candidate_names(const std::string& type_name) {
  if (type_name.find('/') != std::string::npos) {
    const std::string dds = ros_to_dds_name(type_name);
    const std::vector<std::string> parts = split(dds, "::");
    const std::string plain = parts[0] + "::" + parts[1] + "::" + parts[3].substr(0, parts[3].size() - 1);
    return {dds, plain};
  }
  std::string name = type_name;
  if (name.rfind("::", 0) == 0) name = name.substr(2);
  return {name};
}

}  // namespace

std::string detail::RegistryState::roots_text() const {
  return roots.empty() ? std::string("(none)") : join(roots, ", ");
}

std::string detail::RegistryState::root_of(const fs::path& path) const {
  std::error_code ec;
  const fs::path canonical = fs::weakly_canonical(path, ec);
  for (const std::string& r : roots) {
    const fs::path root = fs::weakly_canonical(r, ec);
    const std::string prefix = root.string() + "/";
    if (canonical.string().rfind(prefix, 0) == 0) return r;
  }
  // Not under a registered root: assume the <root>/<pkg>/msg/<Type>.idl layout.
  return canonical.parent_path().parent_path().parent_path().string();
}

std::vector<const StructType*> detail::RegistryState::parse_file(const fs::path& path, const std::string& root) {
  std::error_code ec;
  const std::string key = fs::weakly_canonical(path, ec).string();
  if (files_seen.count(key)) return file_structs[key];  // done, or in progress (include cycle)
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IdlError(path.string(), 0, "cannot read file");
  std::stringstream buffer;
  buffer << in.rdbuf();
  files_seen.insert(key);
  try {
    std::vector<const StructType*> declared =
        idl::parse(*this, path.string(), root, tokenize(buffer.str(), path.string()));
    file_structs[key] = declared;
    return declared;
  } catch (...) {
    files_seen.erase(key);  // report the same error again on the next attempt
    throw;
  }
}

const StructType* detail::RegistryState::try_load_by_name(const std::string& scoped_name) {
  const auto rel = relative_idl_path(scoped_name);
  if (!rel) return nullptr;
  for (const std::string& root : roots) {
    const fs::path path = fs::path(root) / *rel;
    std::error_code ec;
    if (!fs::is_regular_file(path, ec)) continue;
    parse_file(path, root);
    const auto it = structs.find(scoped_name);
    if (it != structs.end()) return it->second.get();
  }
  return nullptr;
}

TypeRegistry::TypeRegistry() : impl_(std::make_unique<Impl>()) {}
TypeRegistry::~TypeRegistry() = default;
TypeRegistry::TypeRegistry(TypeRegistry&&) noexcept = default;
TypeRegistry& TypeRegistry::operator=(TypeRegistry&&) noexcept = default;

void TypeRegistry::add_root(const std::string& path) {
  if (std::find(impl_->roots.begin(), impl_->roots.end(), path) == impl_->roots.end()) {
    impl_->roots.push_back(path);
  }
}

size_t TypeRegistry::add_install_prefix(const std::string& prefix) {
  std::vector<std::string> found;
  std::error_code ec;
  for (fs::directory_iterator it(fs::path(prefix) / "share", ec), end; !ec && it != end; it.increment(ec)) {
    const fs::path idl = it->path() / "idl";
    std::error_code ec2;
    if (fs::is_directory(idl, ec2)) found.push_back(idl.string());
  }
  std::sort(found.begin(), found.end());
  for (const std::string& root : found) add_root(root);
  return found.size();
}

size_t TypeRegistry::add_workspace(const std::string& install_root) {
  std::set<std::string> prefixes;
  for (const char* var : {"UNAV_IDL_PREFIXES", "AMENT_PREFIX_PATH", "CMAKE_PREFIX_PATH", "COLCON_PREFIX_PATH"}) {
    const char* v = std::getenv(var);
    if (!v) continue;
    std::stringstream ss(v);
    std::string p;
    while (std::getline(ss, p, ':'))
      if (!p.empty()) prefixes.insert(p);
  }
  if (!install_root.empty()) prefixes.insert(install_root);
  size_t added = 0;
  for (const auto& p : prefixes)
    for (const std::string& q : {p, p + "/ros2_msgs", p + "/unav_msgs"}) added += add_install_prefix(q);
  return added;
}

std::string executable_install_root(int levels) {
  char exe[4096] = {};
  if (readlink("/proc/self/exe", exe, sizeof(exe) - 1) <= 0) return "";
  std::string root(exe);
  for (int i = 0; i < levels; ++i) root = root.substr(0, root.find_last_of('/'));
  return root;
}

const std::vector<std::string>& TypeRegistry::roots() const { return impl_->roots; }

const StructType* TypeRegistry::find(const std::string& type_name) const {
  std::vector<std::string> names;
  try {
    names = candidate_names(type_name);
  } catch (const UnknownTypeError&) {
    return nullptr;
  }
  for (const std::string& name : names) {
    const auto it = impl_->structs.find(name);
    if (it != impl_->structs.end()) return it->second.get();
  }
  return nullptr;
}

const StructType& TypeRegistry::load(const std::string& type_name) {
  if (const StructType* s = find(type_name)) return *s;
  const std::vector<std::string> names = candidate_names(type_name);
  for (const std::string& name : names) {
    if (const StructType* s = impl_->try_load_by_name(name)) return *s;
  }
  const auto rel = relative_idl_path(names.front());
  throw UnknownTypeError("unknown type '" + type_name + "': no " +
                         (rel ? "file " + *rel + " declaring " + names.front() : std::string("IDL file declaring it")) +
                         " under the IDL roots: " + impl_->roots_text());
}

std::vector<const StructType*> TypeRegistry::load_file(const std::string& path) {
  return impl_->parse_file(path, impl_->root_of(path));
}

const Constant* TypeRegistry::find_constant(const std::string& scoped_name) const {
  std::string name = scoped_name;
  if (name.rfind("::", 0) == 0) name = name.substr(2);
  const auto it = impl_->constants.find(name);
  return it == impl_->constants.end() ? nullptr : &it->second;
}

std::vector<const Constant*> TypeRegistry::constants_of(const std::string& type_name) const {
  // "sensor_msgs::msg::dds_::Range_" -> "sensor_msgs::msg::Range_Constants::"
  const std::string ros =
      dds_to_ros_name(type_name.find("::") != std::string::npos ? type_name : ros_to_dds_name(type_name));
  const size_t a = ros.find('/'), b = ros.rfind('/');
  const std::string prefix =
      ros.substr(0, a) + "::" + ros.substr(a + 1, b - a - 1) + "::" + ros.substr(b + 1) + "_Constants::";
  std::vector<const Constant*> out;
  for (auto it = impl_->constants.lower_bound(prefix); it != impl_->constants.end(); ++it) {
    if (it->first.compare(0, prefix.size(), prefix) != 0) break;
    if (it->first.find("::", prefix.size()) == std::string::npos) out.push_back(&it->second);
  }
  return out;
}

std::vector<std::string> TypeRegistry::list() const {
  std::set<std::string> names;
  for (const std::string& root : impl_->roots) {
    std::error_code ec;
    for (fs::directory_iterator pkg(root, ec), end; !ec && pkg != end; pkg.increment(ec)) {
      std::error_code ec2;
      if (!pkg->is_directory(ec2)) continue;
      for (fs::directory_iterator kind(pkg->path(), ec2); !ec2 && kind != end; kind.increment(ec2)) {
        std::error_code ec3;
        if (!kind->is_directory(ec3)) continue;
        for (fs::directory_iterator file(kind->path(), ec3); !ec3 && file != end; file.increment(ec3)) {
          const fs::path& p = file->path();
          if (p.extension() != ".idl") continue;
          names.insert(pkg->path().filename().string() + "/" + kind->path().filename().string() + "/" +
                       p.stem().string());
        }
      }
    }
  }
  return {names.begin(), names.end()};
}

}  // namespace unav::introspection
