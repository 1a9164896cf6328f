#include "unav_runtime/logging.hpp"

#include <spdlog/pattern_formatter.h>
#include <spdlog/sinks/stdout_color_sinks.h>

#include <mutex>

namespace unav {
namespace {

// ROS 2 prints upper-case level names (INFO, WARN, ERROR, FATAL, DEBUG).
class RosLevelFlag : public spdlog::custom_flag_formatter {
 public:
  void format(const spdlog::details::log_msg& msg, const std::tm&, spdlog::memory_buf_t& dest) override {
    static const char* names[] = {"TRACE", "DEBUG", "INFO", "WARN", "ERROR", "FATAL", "OFF"};
    const char* n = names[static_cast<int>(msg.level)];
    dest.append(n, n + std::char_traits<char>::length(n));
  }
  std::unique_ptr<custom_flag_formatter> clone() const override { return std::make_unique<RosLevelFlag>(); }
};

std::mutex& level_mutex() {
  static std::mutex m;
  return m;
}
spdlog::level::level_enum& current_level() {
  static spdlog::level::level_enum level = spdlog::level::info;
  return level;
}

spdlog::level::level_enum parse_level(std::string s) {
  for (auto& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (s == "debug") return spdlog::level::debug;
  if (s == "warn") return spdlog::level::warn;
  if (s == "error") return spdlog::level::err;
  if (s == "fatal") return spdlog::level::critical;
  return spdlog::level::info;
}

}  // namespace

Logger make_logger(const std::string& name) {
  std::string logger_name = name;
  if (!logger_name.empty() && logger_name[0] == '/') logger_name.erase(0, 1);
  for (auto& c : logger_name)
    if (c == '/') c = '.';
  if (auto existing = spdlog::get(logger_name)) return existing;
  auto logger = spdlog::stderr_color_mt(logger_name);
  auto formatter = std::make_unique<spdlog::pattern_formatter>();
  formatter->add_flag<RosLevelFlag>('*').set_pattern("%^[%*]%$ [%E.%F] [%n]: %v");
  logger->set_formatter(std::move(formatter));
  std::lock_guard<std::mutex> lock(level_mutex());
  logger->set_level(current_level());
  logger->flush_on(spdlog::level::warn);
  return logger;
}

void set_log_level(const std::string& level) {
  std::lock_guard<std::mutex> lock(level_mutex());
  current_level() = parse_level(level);
  spdlog::apply_all([](const Logger& l) { l->set_level(current_level()); });
}

}  // namespace unav
