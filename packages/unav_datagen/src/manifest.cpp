#include "unav_datagen/manifest.hpp"

#include <openssl/evp.h>

#include <yaml-cpp/yaml.h>
#include <algorithm>
#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>
#include <unordered_map>

#include "unav_datagen_version.hpp"

namespace unav::datagen {
namespace fs = std::filesystem;

namespace {

class Sha256 {
 public:
  Sha256() : ctx_(EVP_MD_CTX_new(), EVP_MD_CTX_free) {
    if (!ctx_ || EVP_DigestInit_ex(ctx_.get(), EVP_sha256(), nullptr) != 1)
      throw DatasetError("SHA-256: OpenSSL digest initialisation failed");
  }
  void update(const char* data, std::size_t n) { EVP_DigestUpdate(ctx_.get(), data, n); }
  std::string hex() {
    std::array<unsigned char, EVP_MAX_MD_SIZE> md{};
    unsigned int len = 0;
    EVP_DigestFinal_ex(ctx_.get(), md.data(), &len);
    std::ostringstream os;
    for (unsigned int i = 0; i < len; ++i)
      os << std::hex << std::setw(2) << std::setfill('0') << static_cast<int>(md[i]);
    return os.str();
  }

 private:
  std::unique_ptr<EVP_MD_CTX, decltype(&EVP_MD_CTX_free)> ctx_;
};

}  // namespace

std::string sha256_bytes(const std::string& bytes) {
  Sha256 h;
  h.update(bytes.data(), bytes.size());
  return h.hex();
}

void write_file_logged(const std::string& root, const std::string& relative, const std::vector<std::uint8_t>& bytes) {
  const std::string path = root + "/" + relative;
  const auto* data = reinterpret_cast<const char*>(bytes.data());
  {
    std::ofstream f(path, std::ios::binary);
    if (!f || !f.write(data, static_cast<std::streamsize>(bytes.size())))
      throw DatasetError(path + ": cannot be written");
  }
  Sha256 h;
  h.update(data, bytes.size());
  std::ofstream log(root + "/.sha256", std::ios::app);
  log << h.hex() << ' ' << bytes.size() << ' ' << relative << '\n';
  if (!log) throw DatasetError(root + "/.sha256: cannot be written");
}

std::string sha256_file(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  if (!f) throw DatasetError(path + ": cannot be read for its checksum");
  Sha256 h;
  std::array<char, 1 << 16> buf{};
  while (f) {
    f.read(buf.data(), static_cast<std::streamsize>(buf.size()));
    h.update(buf.data(), static_cast<std::size_t>(f.gcount()));
  }
  if (f.bad()) throw DatasetError(path + ": read error while computing its checksum");
  return h.hex();
}

std::string software_commit() { return UNAV_GIT_COMMIT; }

namespace {
// A resolved randomization sample (YAML) as JSON: numbers stay numbers, booleans booleans.
nlohmann::json yaml_to_json(const YAML::Node& n) {
  if (n.IsMap()) {
    nlohmann::json o = nlohmann::json::object();
    for (const auto& kv : n) o[kv.first.Scalar()] = yaml_to_json(kv.second);
    return o;
  }
  if (n.IsSequence()) {
    nlohmann::json a = nlohmann::json::array();
    for (const auto& v : n) a.push_back(yaml_to_json(v));
    return a;
  }
  if (!n.IsScalar()) return nullptr;
  const std::string& t = n.Scalar();
  if (n.Tag() != "!") {  // unquoted: a number or a boolean when it reads as one
    int64_t i = 0;
    double d = 0;
    bool b = false;
    if (YAML::convert<int64_t>::decode(n, i) && t.find_first_of(".eE") == std::string::npos) return i;
    if (YAML::convert<double>::decode(n, d)) return d;
    if (YAML::convert<bool>::decode(n, b)) return b;
  }
  return t;
}
}  // namespace

void write_manifest(const SequenceWriter& writer, const ManifestInput& in) {
  using nlohmann::json;
  const fs::path root(writer.root());
  json m;
  m["format"] = writer.format();
  m["software"] = {{"name", "unav-sim"}, {"commit", software_commit()}};
  const CameraIntrinsics& k = in.intrinsics;
  const Eigen::Quaterniond q(in.X_BC.linear());
  const Eigen::Vector3d t = in.X_BC.translation();
  m["camera"] = {{"name", in.camera},
                 {"frame", in.camera + "_optical"},
                 {"parent_frame", in.parent_frame},
                 {"width", k.width},
                 {"height", k.height},
                 {"fx", k.fx},
                 {"fy", k.fy},
                 {"cx", k.cx},
                 {"cy", k.cy},
                 {"distortion_model", "plumb_bob"},
                 {"distortion", k.distortion},
                 {"mount_known", in.mount_known},
                 {"mount_xyz_m", {t.x(), t.y(), t.z()}},
                 {"mount_quaternion_xyzw", {q.x(), q.y(), q.z(), q.w()}}};
  m["source"] = in.source;
  if (!in.randomization_yaml.empty()) m["randomization"] = yaml_to_json(YAML::Load(in.randomization_yaml));
  const SequenceCounts n = writer.counts();
  m["counts"] = {
      {"images", n.images}, {"depth", n.depth}, {"segmentation", n.segmentation}, {"poses", n.poses}, {"imu", n.imu}};
  json labels = json::object();
  for (const auto& [id, name] : in.labels) labels[std::to_string(id)] = name;
  m["labels"] = labels;
  for (const auto& [key, text] : in.extra_json) m[key] = json::parse(text);
  m["depth"] = {{"png", "uint16"},
                {"units_per_metre", writer.depth_units_per_metre()},
                {"zero", "no return, or beyond 65535 units"}};
  // Every file of the layout, sorted by path (directory iteration order is unspecified).
  std::vector<std::string> files;
  std::error_code ec;
  std::vector<std::string> entries = writer.layout_entries();
  entries.insert(entries.end(), in.extra_entries.begin(), in.extra_entries.end());
  for (const std::string& entry : entries) {
    const fs::path p = root / entry;
    if (fs::is_regular_file(p, ec)) {
      files.push_back(entry);
    } else if (fs::is_directory(p, ec)) {
      for (const auto& e : fs::recursive_directory_iterator(p, ec))
        if (e.is_regular_file()) files.push_back(fs::relative(e.path(), root).generic_string());
    }
  }
  std::sort(files.begin(), files.end());
  // Digests logged as the files were written (write_file_logged): used when the size still matches.
  std::unordered_map<std::string, std::pair<std::uintmax_t, std::string>> logged;
  const fs::path log_path = root / ".sha256";
  if (std::ifstream log(log_path); log) {
    std::string sha, rel;
    std::uintmax_t bytes = 0;
    while (log >> sha >> bytes && std::getline(log >> std::ws, rel)) logged[rel] = {bytes, sha};
  }
  json list = json::array();
  for (const std::string& f : files) {
    const fs::path p = root / f;
    const std::uintmax_t bytes = fs::file_size(p);
    const auto it = logged.find(f);
    const std::string sha =
        it != logged.end() && it->second.first == bytes ? it->second.second : sha256_file(p.string());
    list.push_back({{"path", f}, {"bytes", bytes}, {"sha256", sha}});
  }
  m["files"] = list;
  const std::string out = (root / "manifest.json").string(), tmp = out + ".tmp";
  {
    std::ofstream f(tmp);
    if (!f) throw DatasetError(tmp + ": cannot be written");
    f << m.dump(2) << '\n';
    if (!f) throw DatasetError(tmp + ": write failed");
  }
  fs::rename(tmp, out, ec);
  if (ec) throw DatasetError(out + ": cannot be written: " + ec.message());
  fs::remove(log_path, ec);  // its content is in the manifest now
}

}  // namespace unav::datagen
