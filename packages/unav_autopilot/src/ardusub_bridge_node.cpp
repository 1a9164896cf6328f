#include "ardusub_bridge_node.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

#include "unav_common/errors.hpp"
#include "unav_common/resources.hpp"

namespace unav::autopilot {

ArduSubBridge::ArduSubBridge(const unav::NodeOptions& options) : Node("ardusub_bridge", options, "rov") {
  ArduSubBridgeParams p;
  p.scenario.file = unav::common::resource_or_empty("config/scenarios/ardusub_pipe.yaml");
  p.motor_map = unav::common::resource_or_empty("config/autopilot/ardusub_bluerov2_heavy.yaml");
  declare_params(&p);
  if (!p.scenario.given() || p.motor_map.empty())
    throw unav::ParameterError("node '" + name() +
                               "': 'scenario' and 'motor_map' are required (unav_resources is not installed, so "
                               "there is no default)");
  const unav::scene::Scenario sc = p.scenario.load();
  backend_ =
      std::make_unique<JsonBackend>(sc, unav::scene::scenario_world(sc), load_motor_map(p.motor_map), p.motor_map);
  publish_period_ = p.publish_period;

  in_addr addr{};
  if (::inet_pton(AF_INET, p.address.c_str(), &addr) != 1)
    throw unav::ParameterError("node '" + name() + "': parameter 'address' = '" + p.address + "': not an IPv4 address");
  if ((ntohl(addr.s_addr) >> 24) != 127)
    logger()->warn("binding {}:{}, not a loopback address: any host that reaches it can drive the vehicle", p.address,
                   p.port);
  fd_ = ::socket(AF_INET, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd_ < 0) throw std::runtime_error(std::string("ardusub_bridge: socket: ") + std::strerror(errno));
  sockaddr_in sa{};
  sa.sin_family = AF_INET;
  sa.sin_addr = addr;
  sa.sin_port = htons(static_cast<std::uint16_t>(p.port));
  if (::bind(fd_, reinterpret_cast<const sockaddr*>(&sa), sizeof(sa)) != 0) {
    const std::string err = std::strerror(errno);
    ::close(fd_);
    throw unav::ParameterError("node '" + name() + "': cannot bind UDP " + p.address + ":" + std::to_string(p.port) +
                               ": " + err);
  }
  socklen_t len = sizeof(sa);
  ::getsockname(fd_, reinterpret_cast<sockaddr*>(&sa), &len);
  bound_port_ = ntohs(sa.sin_port);

  ports_ = std::make_unique<physics::VehiclePorts>(*this, backend_->vehicle(), p.frames);
  ports_->publish_state(backend_->simulator());
  next_publish_ = publish_period_;
  timer_ = create_wall_timer(std::chrono::milliseconds(1), [this] { drain(); });
  logger()->info("ArduPilot JSON backend on udp {}:{} (scenario {}, motor map {}); waiting for SITL", p.address,
                 bound_port_, p.scenario.file, p.motor_map);
}

ArduSubBridge::~ArduSubBridge() {
  const BackendStats& s = backend_->stats();
  logger()->info(
      "{} packets: {} frames, {} physics steps ({:.3f} s), {} repeats, {} restarts, {} gaps, {} dropped; "
      "handle() p50 {:.1f} us, p99 {:.1f} us",
      s.packets, s.frames, s.steps, backend_->simulator().time(), s.repeats, s.resets, s.gaps, s.dropped_total(),
      handle_us_percentile(0.5), handle_us_percentile(0.99));
  if (fd_ >= 0) ::close(fd_);
}

double ArduSubBridge::handle_us_percentile(double q) const {
  if (handle_us_.empty()) return 0.0;
  std::vector<float> v = handle_us_;
  const auto k = static_cast<std::size_t>(q * static_cast<double>(v.size() - 1));
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return v[k];
}

void ArduSubBridge::drain() {
  // ArduPilot sends the next packet as soon as it has our reply: once one came, keep answering
  // while packets follow within a millisecond, up to 20 ms a call so the executor serves the rest.
  // Nothing waiting: return at once (the 1 ms timer comes back).
  const auto start = std::chrono::steady_clock::now();
  std::uint8_t buf[512];
  int wait_ms = 0;
  while (std::chrono::steady_clock::now() - start < std::chrono::milliseconds(20)) {
    pollfd pfd{fd_, POLLIN, 0};
    if (::poll(&pfd, 1, wait_ms) <= 0) break;
    wait_ms = 1;
    sockaddr_in from{};
    socklen_t from_len = sizeof(from);
    const ssize_t n = ::recvfrom(fd_, buf, sizeof(buf), 0, reinterpret_cast<sockaddr*>(&from), &from_len);
    if (n < 0) break;
    const auto t0 = std::chrono::steady_clock::now();
    const std::string reply = backend_->handle(buf, static_cast<std::size_t>(n));
    if (!reply.empty())
      ::sendto(fd_, reply.data(), reply.size(), 0, reinterpret_cast<const sockaddr*>(&from), from_len);
    if (handle_us_.size() < 1000000)
      handle_us_.push_back(
          static_cast<float>(std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count()));
    const physics::Simulator& sim = backend_->simulator();
    ports_->publish_sensors(sim);
    const double t = sim.time();
    if (t + 1e-9 >= next_publish_ || t + 1e-9 < next_publish_ - 2 * publish_period_) {
      ports_->publish_state(sim);  // (the second case: SITL restarted, time went back)
      ports_->publish_thruster_state(sim);
      next_publish_ = t + publish_period_;
    }
  }
  log_drops();
}

void ArduSubBridge::log_drops() {
  const BackendStats& s = backend_->stats();
  if (s.dropped_total() == logged_drops_) return;
  const auto now = std::chrono::steady_clock::now();
  if (now - last_drop_log_ < std::chrono::seconds(1)) return;
  last_drop_log_ = now;
  logged_drops_ = s.dropped_total();
  logger()->warn(
      "dropped {} malformed packets so far (short {}, unknown magic {}, frame_rate 0 {}, PWM out of range {})",
      s.dropped_total(), s.dropped[1], s.dropped[2], s.dropped[3], s.dropped[4]);
}

}  // namespace unav::autopilot
