#include "unav_runtime/shm_cleanup.hpp"

#include <cctype>
#include <filesystem>
#include <system_error>

namespace unav::shm {

namespace fs = std::filesystem;

namespace {

constexpr const char* kPrefix = "fast_datasharing_";

int hex_byte(const std::string& s, std::size_t at) {
  int v = 0;
  for (std::size_t i = at; i < at + 2; ++i) {
    const char c = static_cast<char>(std::tolower(static_cast<unsigned char>(s[i])));
    if (c >= '0' && c <= '9') {
      v = v * 16 + (c - '0');
    } else if (c >= 'a' && c <= 'f') {
      v = v * 16 + (c - 'a' + 10);
    } else {
      return -1;
    }
  }
  return v;
}

}  // namespace

std::optional<Segment> parse_data_sharing_name(const std::string& name) {
  const std::string prefix = kPrefix;
  if (name.compare(0, prefix.size(), prefix) != 0) return std::nullopt;
  // 12 bytes "xx." (the last without the dot), then '_' and the entity id.
  const std::size_t at = prefix.size();
  if (name.size() < at + std::size_t{36}) return std::nullopt;
  std::array<int, 12> b{};
  for (std::size_t i = 0; i < 12; ++i) {
    b[i] = hex_byte(name, at + 3 * i);
    const char sep = name[at + 3 * i + 2];
    if (b[i] < 0 || sep != (i == 11 ? '_' : '.')) return std::nullopt;
  }
  if (b[0] != 0x01 || b[1] != 0x0f) return std::nullopt;  // eProsima's vendor id
  Segment s;
  s.name = name;
  s.host = {static_cast<std::uint8_t>(b[2]), static_cast<std::uint8_t>(b[3])};
  s.pid16 = static_cast<std::uint16_t>(b[4] | (b[5] << 8));
  return s;
}

std::vector<bool> live_pid16() {
  std::vector<bool> live(65536, false);
  std::error_code ec;
  for (const auto& e : fs::directory_iterator("/proc", ec)) {
    const std::string n = e.path().filename().string();
    if (n.empty() || n.find_first_not_of("0123456789") != std::string::npos) continue;
    live[static_cast<std::size_t>(std::stoull(n) & 0xFFFFu)] = true;
  }
  return live;
}

CleanReport clean_data_sharing(const std::string& dir, bool dry_run,
                               std::optional<std::array<std::uint8_t, 2>> host_id) {
  CleanReport r;
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) return r;
  std::vector<bool> live;  // read from /proc at the first segment: a participant's start with none costs no scan
  for (const auto& e : fs::directory_iterator(dir, ec)) {
    std::optional<Segment> s = parse_data_sharing_name(e.path().filename().string());
    if (!s) continue;
    if (live.empty()) live = live_pid16();
    s->bytes = e.is_regular_file(ec) ? static_cast<std::uint64_t>(e.file_size(ec)) : 0;
    s->dead = !live[s->pid16] && (!host_id || *host_id == s->host);
    if (s->dead && !dry_run) {
      std::error_code rm;
      if (fs::remove(e.path(), rm)) {
        ++r.removed;
        r.removed_bytes += s->bytes;
      } else if (rm) {  // gone already (another process cleaned it) is not an error
        r.errors.push_back(s->name + ": " + rm.message());
      }
    }
    r.segments.push_back(*s);
  }
  return r;
}

}  // namespace unav::shm
