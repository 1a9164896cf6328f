#include "unav_physics/acoustic_modem.hpp"

#include <algorithm>

namespace unav::physics {

namespace {
constexpr double kDefaultSoundSpeed = 1500.0;  // m/s, without a world's water
}  // namespace

AcousticModem::AcousticModem(const AcousticModemParams& params, std::uint64_t seed) : p_(params), gen_(seed) {
  if (!(p_.sound_speed_mps > 0.0)) p_.sound_speed_mps = kDefaultSoundSpeed;
  station_W_ = p_.station_position;  // a carried station's until set_station_position()
}

AcousticModem::Send AcousticModem::send(double t, End from, std::vector<std::uint8_t> data) {
  if (static_cast<long>(data.size()) > p_.max_packet_bytes) return Send::kTooLong;
  Queue& q = from == End::kVehicle ? vehicle_ : station_;
  if (static_cast<long>(q.waiting.size()) >= p_.queue_packets) return Send::kQueueFull;
  Packet pk;
  pk.to = from == End::kVehicle ? End::kStation : End::kVehicle;
  pk.data = std::move(data);
  pk.sent = t;
  q.waiting.push_back(std::move(pk));
  return Send::kQueued;
}

int AcousticModem::step(double t, const Eigen::Vector3d& p_W, std::vector<Packet>* out) {
  if (!p_.enabled) return 0;
  int lost = 0;
  // Emissions due by t: each end sends its queue one packet after another, from when it is free.
  for (Queue* q : {&vehicle_, &station_}) {
    while (!q->waiting.empty() && std::max(q->free_at, q->waiting.front().sent) <= t) {
      Packet pk = std::move(q->waiting.front());
      q->waiting.pop_front();
      const double start = std::max(q->free_at, pk.sent);
      const double duration = 8.0 * static_cast<double>(pk.data.size()) / p_.bit_rate_bps;
      q->free_at = start + duration;
      pk.range_m = (p_W - station_W_).norm();
      pk.arrival = start + pk.range_m / p_.sound_speed_mps + duration;
      const double share = std::min(1.0, pk.range_m / p_.max_range_m);
      const bool drop = uniform_(gen_) < p_.loss_at_max_range * share * share;  // drawn for every packet
      if (drop || pk.range_m > p_.max_range_m)
        ++lost;
      else
        in_flight_.push_back(std::move(pk));
    }
  }
  // Arrivals by t, in arrival order (stable: equal times keep the emission order).
  std::stable_sort(in_flight_.begin(), in_flight_.end(),
                   [](const Packet& a, const Packet& b) { return a.arrival < b.arrival; });
  auto arrived = in_flight_.begin();
  while (arrived != in_flight_.end() && arrived->arrival <= t + 1e-12) ++arrived;
  for (auto it = in_flight_.begin(); it != arrived; ++it) out->push_back(std::move(*it));
  in_flight_.erase(in_flight_.begin(), arrived);
  return lost;
}

}  // namespace unav::physics
