// Publish-to-receive latency between two processes (fork), through the unav runtime and through
// a minimal raw Fast DDS program with the same QoS and transports, in the same run: both with and
// without data-sharing delivery (the Image type bounded to the image's size, registered under its
// ROS 2 name), and through the runtime with DDS Security on (SROS2 default governance: RTPS
// signed, data encrypted with AES-GCM); plus image throughput. Prints a Markdown table, then
// BENCH runtime/latency_{small,image}_<path>_{p50,p99}_ms and runtime/throughput_image_<path>_mb_per_s,
// path: raw, raw_data_sharing, runtime, runtime_data_sharing, runtime_secured.
// Usage: bench_latency [samples_small] [samples_image]
#include <sys/wait.h>
#include <unistd.h>

#include <time.h>
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include <fastdds/rtps/transport/UDPv4TransportDescriptor.h>
#include <fastdds/rtps/transport/shared_mem/SharedMemTransportDescriptor.h>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/DataReaderListener.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/topic/Topic.hpp>
#include <fastdds/dds/topic/TypeSupport.hpp>

#include "sensor_msgs/msg/image.hpp"
#include "unav_common/bench.hpp"
#include "unav_runtime/runtime.hpp"
#include "unav_runtime/security.hpp"

namespace fdds = eprosima::fastdds::dds;
using namespace std::chrono_literals;

namespace {

enum class Path { kRaw, kRawDataSharing, kRuntime, kRuntimeDataSharing, kRuntimeSecured };
// In BENCH ids, by Path.
const char* const kPathIds[] = {"raw", "raw_data_sharing", "runtime", "runtime_data_sharing", "runtime_secured"};
const char* path_name(Path p) {
  switch (p) {
    case Path::kRaw:
      return "raw Fast DDS";
    case Path::kRawDataSharing:
      return "raw Fast DDS, data-sharing";
    case Path::kRuntime:
      return "unav runtime";
    case Path::kRuntimeDataSharing:
      return "unav runtime, data-sharing";
    case Path::kRuntimeSecured:
      return "unav runtime, secured";
  }
  return "?";
}
bool is_raw(Path p) { return p == Path::kRaw || p == Path::kRawDataSharing; }
bool uses_data_sharing(Path p) { return p == Path::kRawDataSharing || p == Path::kRuntimeDataSharing; }

// Set by main() for the secured rows: a keystore made before any fork.
std::string g_keystore;  // NOLINT(cppcoreguidelines-avoid-non-const-global-variables)

unav::ContextOptions runtime_options(int domain, bool secured) {
  unav::ContextOptions o;
  o.domain_id = domain;
  o.handle_signals = false;
  unav::security::Environment env;
  if (secured) {
    env.enable = true;
    env.enforce = true;
    env.keystore = g_keystore;
    env.enclave_override = "/bench";
  }
  o.security = env;
  return o;
}

int64_t mono_ns() {
  timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return int64_t{ts.tv_sec} * 1000000000 + ts.tv_nsec;
}

// Payload: an Image; the small case has 100 bytes on the wire in total.
sensor_msgs::msg::Image make_sample(bool big) {
  sensor_msgs::msg::Image m;
  if (big) {
    m.height(480);
    m.width(640);
    m.encoding("rgb8");
    m.step(1920);
    m.data().assign(921600, 7);
  } else {
    m.encoding("x");
    m.data().assign(46, 7);  // 4 + 8 + 4+1(+3) + 4 + 4 + 4+2(+2) + 1(+3) + 4 + 4 + 46 = 100 bytes
  }
  return m;
}

void stamp(sensor_msgs::msg::Image& m, int64_t seq) {
  const int64_t t = mono_ns();
  m.header().stamp().sec(static_cast<int32_t>(t / 1000000000));
  m.header().stamp().nanosec(static_cast<uint32_t>(t % 1000000000));
  m.is_bigendian(0);
  m.height(m.height());
  (void)seq;
}

int64_t latency_of(const sensor_msgs::msg::Image& m) {
  return mono_ns() - (int64_t{m.header().stamp().sec()} * 1000000000 + m.header().stamp().nanosec());
}

struct Stats {
  double p50_ms, p99_ms, mbps;
  size_t n;
};

// --- raw Fast DDS (same QoS and transports as the runtime: reliable keep last 10, UDPv4, + SHM 32 MiB
// with UNAV_TRANSPORT=shm; data-sharing as the row says) ---
struct RawListener : fdds::DataReaderListener {
  std::vector<int64_t> lat;
  size_t bytes = 0;
  sensor_msgs::msg::Image sample;
  void on_data_available(fdds::DataReader* r) override {
    fdds::SampleInfo info;
    while (r->take_next_sample(&sample, &info) == ReturnCode_t::RETCODE_OK)
      if (info.valid_data) {
        lat.push_back(latency_of(sample));
        bytes += sample.data().size();
      }
  }
};

fdds::DomainParticipant* raw_participant(int domain) {
  fdds::DomainParticipantQos q;
  q.transport().use_builtin_transports = false;
  if (unav::shm_transport_from_environment()) {
    auto shm = std::make_shared<eprosima::fastdds::rtps::SharedMemTransportDescriptor>();
    shm->segment_size(32u * 1024u * 1024u);
    q.transport().user_transports.push_back(shm);
  }
  auto udp = std::make_shared<eprosima::fastdds::rtps::UDPv4TransportDescriptor>();
  udp->receiveBufferSize = udp->sendBufferSize = 4u * 1024u * 1024u;  // as the runtime's (context.cpp)
  q.transport().user_transports.push_back(udp);
  return fdds::DomainParticipantFactory::get_instance()->create_participant(domain, q);
}

template <typename Qos>
void raw_qos(Qos& q, bool data_sharing, bool writer) {
  q.reliability().kind = fdds::RELIABLE_RELIABILITY_QOS;
  q.history().kind = fdds::KEEP_LAST_HISTORY_QOS;
  q.history().depth = 10;
  q.endpoint().history_memory_policy = eprosima::fastrtps::rtps::PREALLOCATED_WITH_REALLOC_MEMORY_MODE;
  q.data_sharing().off();
  if (data_sharing) {
    q.data_sharing().automatic();
    q.endpoint().history_memory_policy = writer ? eprosima::fastrtps::rtps::PREALLOCATED_MEMORY_MODE
                                                : eprosima::fastrtps::rtps::DYNAMIC_REUSABLE_MEMORY_MODE;
  }
}

// The raw type support, bounded for data-sharing (the bound of the 640x480 image) or as generated.
fdds::TypeSupport raw_type(bool data_sharing) {
  auto* t = new unav::SwitchableBoundType<sensor_msgs::msg::dds_::Image_PubSubType>();
  if (data_sharing) t->set_bound(unav::serialized_bytes(make_sample(true)));
  return fdds::TypeSupport(t);
}

Stats summarize(std::vector<int64_t> lat, size_t bytes, double seconds) {
  Stats s{0, 0, 0, lat.size()};
  if (lat.empty()) return s;
  std::sort(lat.begin(), lat.end());
  s.p50_ms = lat[lat.size() / 2] * 1e-6;
  s.p99_ms = lat[std::min(lat.size() - 1, lat.size() * 99 / 100)] * 1e-6;
  s.mbps = static_cast<double>(bytes) / seconds / 1e6;
  return s;
}

// Child: subscribe, collect `n` samples (or until timeout), write Stats to `fd`.
void run_sub(Path path, int domain, size_t n, double period_s, int fd) {
  const double seconds = static_cast<double>(n) * period_s;
  Stats s{};
  if (is_raw(path)) {
    auto* p = raw_participant(domain);
    fdds::TypeSupport ts = raw_type(uses_data_sharing(path));
    ts.register_type(p);
    auto* t = p->create_topic("rt/bench", ts.get_type_name(), fdds::TOPIC_QOS_DEFAULT);
    auto* sub = p->create_subscriber(fdds::SUBSCRIBER_QOS_DEFAULT);
    fdds::DataReaderQos rq = sub->get_default_datareader_qos();
    raw_qos(rq, uses_data_sharing(path), false);
    RawListener l;
    auto* r = sub->create_datareader(t, rq, &l);
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds + 15.0);
    while (l.lat.size() < n && std::chrono::steady_clock::now() < end) std::this_thread::sleep_for(5ms);
    sub->delete_datareader(r);
    s = summarize(l.lat, l.bytes, seconds);
    p->delete_contained_entities();
    fdds::DomainParticipantFactory::get_instance()->delete_participant(p);
  } else {
    unav::Context ctx(runtime_options(domain, path == Path::kRuntimeSecured));
    unav::Node node("bench_sub", {&ctx});
    std::vector<int64_t> lat;
    size_t bytes = 0;
    const unav::QoS q =
        path == Path::kRuntimeDataSharing ? unav::QoS::reliable(10).with_data_sharing() : unav::QoS::reliable(10);
    auto sub = node.create_subscription<sensor_msgs::msg::Image>("/bench", q, [&](const sensor_msgs::msg::Image& m) {
      lat.push_back(latency_of(m));
      bytes += m.data().size();
    });
    ctx.spin_until([&] { return lat.size() >= n; },
                   std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::duration<double>(seconds + 15.0)));
    s = summarize(lat, bytes, seconds);
  }
  (void)!write(fd, &s, sizeof(s));
}

// Parent: publish `n` samples every `period_s` once matched (both modes use raw writers'
// matched status through the runtime or raw API).
void run_pub(Path path, int domain, bool big, size_t n, double period_s) {
  auto msg = make_sample(big);
  auto pace = [&](auto&& publish, auto&& matched) {
    const auto until = std::chrono::steady_clock::now() + 15s;
    while (!matched() && std::chrono::steady_clock::now() < until) std::this_thread::sleep_for(10ms);
    std::this_thread::sleep_for(300ms);
    auto next = std::chrono::steady_clock::now();
    for (size_t i = 0; i < n + 20; ++i) {  // a few extra in case the first ones race discovery
      stamp(msg, static_cast<int64_t>(i));
      publish();
      next += std::chrono::duration_cast<std::chrono::steady_clock::duration>(std::chrono::duration<double>(period_s));
      std::this_thread::sleep_until(next);
    }
  };
  if (is_raw(path)) {
    auto* p = raw_participant(domain);
    fdds::TypeSupport ts = raw_type(uses_data_sharing(path));
    ts.register_type(p);
    auto* t = p->create_topic("rt/bench", ts.get_type_name(), fdds::TOPIC_QOS_DEFAULT);
    auto* pub = p->create_publisher(fdds::PUBLISHER_QOS_DEFAULT);
    fdds::DataWriterQos wq = pub->get_default_datawriter_qos();
    raw_qos(wq, uses_data_sharing(path), true);
    auto* w = pub->create_datawriter(t, wq);
    pace([&] { w->write(&msg); },
         [&] {
           fdds::PublicationMatchedStatus st;
           w->get_publication_matched_status(st);
           return st.current_count > 0;
         });
    p->delete_contained_entities();
    fdds::DomainParticipantFactory::get_instance()->delete_participant(p);
  } else {
    unav::Context ctx(runtime_options(domain, path == Path::kRuntimeSecured));
    unav::Node node("bench_pub", {&ctx});
    // The bound is the largest sample of the run (the image), as a camera node sets it.
    const unav::QoS q = path == Path::kRuntimeDataSharing
                            ? unav::QoS::reliable(10).with_data_sharing(unav::serialized_bytes(make_sample(true)))
                            : unav::QoS::reliable(10);
    auto pub = node.create_publisher<sensor_msgs::msg::Image>("/bench", q);
    pace([&] { pub->publish(msg); }, [&] { return pub->subscription_count() > 0; });
  }
}

Stats measure(Path path, bool big, size_t n, double period_s, int domain) {
  int fds[2];
  if (pipe(fds) != 0) std::abort();
  const pid_t child = fork();
  if (child == 0) {
    close(fds[0]);
    run_sub(path, domain, n, period_s, fds[1]);
    _exit(0);
  }
  // The publisher runs in a child too: Fast DDS must never be initialised in a process that
  // forks afterwards (its threads and locks do not survive fork).
  const pid_t pub = fork();
  if (pub == 0) {
    close(fds[0]);
    close(fds[1]);
    run_pub(path, domain, big, n, period_s);
    _exit(0);
  }
  close(fds[1]);
  Stats s{};
  (void)!read(fds[0], &s, sizeof(s));
  close(fds[0]);
  waitpid(child, nullptr, 0);
  waitpid(pub, nullptr, 0);
  return s;
}

}  // namespace

int main(int argc, char** argv) {
  const size_t n_small = argc > 1 ? std::strtoul(argv[1], nullptr, 10) : 2000;
  const size_t n_image = argc > 2 ? std::strtoul(argv[2], nullptr, 10) : 300;
  const int domain = 200 + static_cast<int>(getpid() % 30);
  std::printf("transports: %s\n\n", unav::shm_transport_from_environment()
                                        ? "UDPv4 + shared memory (UNAV_TRANSPORT=shm)"
                                        : "UDPv4 (the default; UNAV_TRANSPORT=shm adds shared memory)");
  std::printf("| message | path | samples | rate | p50 [ms] | p99 [ms] | received MB/s |\n");
  std::printf("|---|---|---|---|---|---|---|\n");
  struct Case {
    const char* name;
    const char* id;  // BENCH id: p50 and p99 latency, or received MB/s for the throughput case
    bool big;
    size_t n;
    double period;
  };
  const Case cases[] = {{"100 B Image", "latency_small", false, n_small, 0.002},
                        {"640x480 rgb8 (921,600 B)", "latency_image", true, n_image, 1.0 / 30.0},
                        {"640x480 rgb8, throughput", "throughput_image", true, n_image, 1.0 / 500.0}};
  struct Figure {
    std::string id;
    double value;
    const char* unit;
  };
  std::vector<Figure> figures;  // BENCH lines, printed after the table
  g_keystore = "/tmp/unav_bench_keystore_" + std::to_string(getpid());
  std::filesystem::remove_all(g_keystore);
  unav::security::create_keystore(g_keystore);
  unav::security::create_enclave(g_keystore, "/bench");
  const Path paths[] = {Path::kRaw, Path::kRawDataSharing, Path::kRuntime, Path::kRuntimeDataSharing,
                        Path::kRuntimeSecured};
  for (const auto& c : cases) {
    for (const Path path : paths) {
      const Stats s = measure(path, c.big, c.n, c.period, domain);
      std::printf("| %s | %s | %zu | %.0f Hz | %.3f | %.3f | %.1f |\n", c.name, path_name(path), s.n, 1.0 / c.period,
                  s.p50_ms, s.p99_ms, s.mbps);
      std::fflush(stdout);
      if (s.n == 0) continue;  // nothing received: no figure
      const std::string id = std::string("runtime/") + c.id + "_" + kPathIds[static_cast<int>(path)];
      if (std::string(c.id).rfind("throughput", 0) == 0) {
        figures.push_back({id + "_mb_per_s", s.mbps, "MB_per_s"});
      } else {
        figures.push_back({id + "_p50_ms", s.p50_ms, "ms"});
        figures.push_back({id + "_p99_ms", s.p99_ms, "ms"});
      }
    }
  }
  std::printf("\n");
  for (const auto& f : figures) unav::common::print_bench(f.id, f.value, f.unit);
  std::filesystem::remove_all(g_keystore);
  return 0;
}
