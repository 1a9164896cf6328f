// Bag write throughput with camera-sized messages: MB/s for MCAP (none, zstd) and sqlite3, and
// the file size each gives for the same content. Usage: bench_unav_bag [OUT_DIR] [SECONDS_OF_VIDEO]
// Machine-readable: BENCH bag/write_{mcap_none,mcap_zstd,sqlite3_none}_mb_per_s.
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <random>
#include <string>

#include "unav_bag/bag.hpp"
#include "unav_common/bench.hpp"

namespace fs = std::filesystem;

int main(int argc, char** argv) {
  const std::string out = argc > 1 ? argv[1] : (fs::temp_directory_path() / "unav_bench_bag").string();
  const int seconds = argc > 2 ? std::stoi(argv[2]) : 10;
  fs::remove_all(out);
  // 30 Hz 640x480 rgb8 images (rendered-like: smooth gradient + noise, so zstd has something to
  // do but no more than on real frames) and 200 Hz 320-byte IMU-sized messages.
  std::vector<uint8_t> image(640 * 480 * 3 + 64);
  std::mt19937 rng(1);
  for (size_t i = 0; i < image.size(); ++i) image[i] = static_cast<uint8_t>((i / 3 % 640) / 4 + rng() % 8);
  const std::vector<uint8_t> imu(320, 1);
  std::printf("%-14s %10s %10s %12s %10s\n", "storage", "messages", "MB", "seconds", "MB/s");
  for (const auto& [storage, compression] :
       {std::pair{"mcap", "none"}, std::pair{"mcap", "zstd"}, std::pair{"sqlite3", "none"}}) {
    unav::bag::BagWriter::Options opt;
    opt.storage_id = storage;
    opt.compression = compression;
    const std::string dir = out + "/" + storage + "_" + compression;
    const auto t0 = std::chrono::steady_clock::now();
    uint64_t n = 0;
    {
      unav::bag::BagWriter w(dir, opt);
      w.add_topic({"/rov/camera/image", "sensor_msgs/msg/Image", "cdr", "", ""});
      w.add_topic({"/rov/imu", "sensor_msgs/msg/Imu", "cdr", "", ""});
      for (int64_t k = 0; k < static_cast<int64_t>(seconds) * 600; ++k) {  // 600 ticks of 5/3 ms per second
        const int64_t t = k * 1666667;
        if (k % 20 == 0) {
          image[0] = static_cast<uint8_t>(k);
          w.write(0, t, image.data(), image.size());
          ++n;
        }
        if (k % 3 == 0) {
          w.write(1, t, imu.data(), imu.size());
          ++n;
        }
      }
      w.close();
    }
    const double dt = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    uint64_t bytes = 0;
    for (const auto& e : fs::directory_iterator(dir)) bytes += fs::file_size(e.path());
    const double payload_mb = (seconds * 30.0 * static_cast<double>(image.size()) + seconds * 200.0 * 320) / 1e6;
    std::printf("%-14s %10llu %10.1f %12.3f %10.1f   (file %.1f MB)\n",
                (std::string(storage) + "/" + compression).c_str(), static_cast<unsigned long long>(n), payload_mb, dt,
                payload_mb / dt, static_cast<double>(bytes) / 1e6);
    unav::common::print_bench(std::string("bag/write_") + storage + "_" + compression + "_mb_per_s", payload_mb / dt,
                              "MB_per_s");
  }
  fs::remove_all(out);
  return 0;
}
