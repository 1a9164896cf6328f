// An acoustic modem link between the vehicle and a station fixed in the world (the support
// vessel's modem, often the USBL transceiver's own): packets of bytes sent from either end arrive
// at the other after the acoustic travel time plus their transmission time (8 bits per byte at
// bit_rate_bps), each end sending one packet at a time (a queue of queue_packets behind it); a
// packet is lost with probability loss_at_max_range (range / max_range_m)^2, and always beyond
// max_range_m. The travel time is the range at emission over the sound speed (the receiver's
// motion during the travel changes it by v / c: 0.07 % at 1 m/s). Deterministic under the seed.
// The station end may be another vehicle's modem (station_vehicle: a vehicle of the scenario; the
// station_position is then its mount on that vehicle, body FRD, and set_station_position() moves
// it): a link between two vehicles.
// DDS-free; the physics server carries the packets (modem/tx -> /surface/modem/rx and back).
#pragma once

#include <cstdint>
#include <deque>
#include <random>
#include <vector>

#include <Eigen/Core>

#include "unav_common/config.hpp"

namespace unav::physics {

struct AcousticModemParams {
  bool enabled = false;
  double bit_rate_bps = 100.0;  ///< SeaTrac-class links: ~100 bit/s; broadband modems: kbit/s
  /// "" = the station is fixed in the world; else the vehicle carrying the other end (the physics
  /// server's namespace name for its primary, a fleet name)
  std::string station_vehicle;
  Eigen::Vector3d station_position{0.0, 0.0, 1.0};  ///< world NED [m]; or on station_vehicle, FRD
  Eigen::Vector3d modem_xyz_m{-0.1, 0.0, -0.15};    ///< on the vehicle, body FRD [m]
  double sound_speed_mps = 0.0;                     ///< 0 = the world's water (1500 without one)
  double max_range_m = 1000.0;
  double loss_at_max_range = 0.3;
  int max_packet_bytes = 1024;
  int queue_packets = 16;  ///< per end; a packet beyond is refused

  template <class Archive>
  void Serialize(Archive* a) {
    using unav::common::Field;
    a->Visit(Field("enabled", &enabled).Doc("carry packets between the vehicle and the station"));
    a->Visit(Field("station_vehicle", &station_vehicle).Doc("carrier of the other end; empty = fixed"));
    a->Visit(Field("bit_rate_bps", &bit_rate_bps).Above(0.0).Max(1e6).Unit("bit/s"));
    a->Visit(Field("station_position", &station_position).Range(-1e5, 1e5).Unit("m").Doc("world NED"));
    a->Visit(Field("modem_xyz_m", &modem_xyz_m).Range(-10.0, 10.0).Unit("m").Doc("on the vehicle, FRD"));
    a->Visit(Field("sound_speed_mps", &sound_speed_mps).Range(0.0, 1700.0).Unit("m/s").Doc("0 = the world's water"));
    a->Visit(Field("max_range_m", &max_range_m).Above(0.0).Max(1e5).Unit("m").Doc("nothing arrives beyond"));
    a->Visit(Field("loss_at_max_range", &loss_at_max_range).Range(0.0, 1.0).Doc("~ (range / max)^2"));
    a->Visit(Field("max_packet_bytes", &max_packet_bytes).Range(1, 1 << 20).Doc("longer packets are refused"));
    a->Visit(Field("queue_packets", &queue_packets).Range(1, 100000).Doc("per end"));
  }
};

class AcousticModem {
 public:
  enum class End { kVehicle, kStation };
  struct Packet {
    End to = End::kStation;
    std::vector<std::uint8_t> data;
    double sent = 0.0;     ///< s, when it was handed to the sending modem
    double arrival = 0.0;  ///< s, when its last bit reached the receiver
    double range_m = 0.0;  ///< at emission
  };
  enum class Send { kQueued, kTooLong, kQueueFull };

  AcousticModem() = default;
  AcousticModem(const AcousticModemParams& params, std::uint64_t seed);
  /// Hands `data` to the modem of `from` at time t (it leaves when that modem is free).
  Send send(double t, End from, std::vector<std::uint8_t> data);
  /// Advances to time t with the vehicle's modem at p_W; appends the packets arrived by t, in
  /// arrival order, to *out; returns how many were lost since the last call (ground truth).
  int step(double t, const Eigen::Vector3d& p_W, std::vector<Packet>* out);
  const AcousticModemParams& params() const { return p_; }
  /// Where the station end is now (a carried one: its carrier's pose applied to its mount).
  void set_station_position(const Eigen::Vector3d& p_W) { station_W_ = p_W; }

 private:
  struct Queue {
    std::deque<Packet> waiting;
    double free_at = 0.0;  ///< the end's transducer is busy until
  };
  AcousticModemParams p_;
  std::mt19937_64 gen_;
  std::uniform_real_distribution<double> uniform_{0.0, 1.0};
  Queue vehicle_, station_;
  std::vector<Packet> in_flight_;
  Eigen::Vector3d station_W_ = Eigen::Vector3d::Zero();
};

}  // namespace unav::physics
