#include "unav_runtime/context.hpp"

#include <pthread.h>
#include <signal.h>
#include <unistd.h>

#include <cstdlib>
#include <cstring>
#include <typeinfo>
#include <utility>

#include <fastdds/rtps/transport/UDPv4TransportDescriptor.h>
#include <fastdds/rtps/transport/shared_mem/SharedMemTransportDescriptor.h>
#include <fastrtps/utils/IPLocator.h>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/log/Log.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/DataReaderListener.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/topic/Topic.hpp>
#include <fastdds/dds/topic/TypeSupport.hpp>

#include "rmw_dds_common/msg/gid.hpp"
#include "rmw_dds_common/msg/participant_entities_info.hpp"
#include "rosgraph_msgs/msg/clock.hpp"
#include "unav_runtime/discovery.hpp"
#include "unav_runtime/errors.hpp"
#include "unav_runtime/logging.hpp"
#include "unav_runtime/node.hpp"
#include "unav_runtime/publisher.hpp"
#include "unav_runtime/shm_cleanup.hpp"

namespace fdds = eprosima::fastdds::dds;

namespace unav {
namespace {

int domain_from_env() {
  const char* env = std::getenv("ROS_DOMAIN_ID");
  if (!env || !*env) return 0;
  char* end = nullptr;
  const long id = std::strtol(env, &end, 10);
  if (*end != '\0' || id < 0 || id > 232)
    throw ConfigError(std::string("environment ROS_DOMAIN_ID='") + env + "': expected an integer in [0, 232]");
  return static_cast<int>(id);
}

sigset_t handled_signals() {
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, SIGINT);
  sigaddset(&set, SIGTERM);
  sigaddset(&set, SIGUSR2);  // internal: wakes the signal thread at exit
  return set;
}

void fill_gid(const eprosima::fastrtps::rtps::GUID_t& guid, rmw_dds_common::msg::Gid& gid) {
  std::array<char, 24> data{};
  std::memcpy(data.data(), guid.guidPrefix.value, 12);
  std::memcpy(data.data() + 12, guid.entityId.value, 4);
  gid.data(data);
}

void apply_qos(const QoS& q, fdds::ReliabilityQosPolicy& rel, fdds::DurabilityQosPolicy& dur,
               fdds::HistoryQosPolicy& hist) {
  rel.kind =
      q.reliability == QoS::Reliability::kReliable ? fdds::RELIABLE_RELIABILITY_QOS : fdds::BEST_EFFORT_RELIABILITY_QOS;
  dur.kind = q.durability == QoS::Durability::kTransientLocal ? fdds::TRANSIENT_LOCAL_DURABILITY_QOS
                                                              : fdds::VOLATILE_DURABILITY_QOS;
  hist.kind = fdds::KEEP_LAST_HISTORY_QOS;
  hist.depth = q.depth;
}

}  // namespace

constexpr uint32_t kUdpBufferBytes = 4u * 1024u * 1024u;

namespace {

eprosima::fastrtps::rtps::Locator_t udp_locator(const std::string& address, uint32_t port) {
  eprosima::fastrtps::rtps::Locator_t l;
  l.kind = LOCATOR_KIND_UDPv4;
  eprosima::fastrtps::rtps::IPLocator::setIPv4(l, address);
  l.port = port;  // 0: Fast DDS fills in the participant's well-known port (initial peers: the first N)
  return l;
}

// Discovery as the plan says (unav_runtime/discovery.hpp). SUBNET keeps Fast DDS' multicast
// defaults; LOCALHOST and OFF announce by unicast only, so no multicast socket is opened and every
// announcement arrives on the one metatraffic unicast thread.
void apply_discovery_plan(const DiscoveryPlan& plan, int domain, fdds::DomainParticipantQos& pqos,
                          eprosima::fastdds::rtps::UDPv4TransportDescriptor& udp, const std::string& who) {
  auto& builtin = pqos.wire_protocol().builtin;
  const bool peers = !plan.static_peers.empty();
  if (plan.range == DiscoveryRange::kSubnet) {
    if (peers) {  // an explicit initial peers list replaces the multicast default: keep it in
      const auto port =
          static_cast<uint32_t>(pqos.wire_protocol().port.getMulticastPort(static_cast<uint32_t>(domain)));
      builtin.initialPeersList.push_back(udp_locator("239.255.0.1", port));
      for (const auto& p : plan.static_peers) builtin.initialPeersList.push_back(udp_locator(p, 0));
    }
  } else {
    // Reachable from other hosts only when there are static peers.
    builtin.metatrafficUnicastLocatorList.push_back(udp_locator(peers ? "0.0.0.0" : "127.0.0.1", 0));
    if (plan.range == DiscoveryRange::kLocalhost) builtin.initialPeersList.push_back(udp_locator("127.0.0.1", 0));
    for (const auto& p : plan.static_peers) builtin.initialPeersList.push_back(udp_locator(p, 0));
    udp.maxInitialPeersRange = plan.localhost_participants;
    if (!peers) udp.interfaceWhiteList.emplace_back("127.0.0.1");
  }
  if (!plan.warning.empty()) make_logger(who)->warn("{}", plan.warning);
  if (!plan.reason.empty()) make_logger(who)->debug("discovery {}: {}", to_string(plan.range), plan.reason);
}

}  // namespace

bool shm_transport_from_environment() {
  const char* env = std::getenv("UNAV_TRANSPORT");
  const std::string v = env ? env : "";
  if (v.empty() || v == "udp") return false;
  if (v == "shm") return true;
  throw ConfigError("environment UNAV_TRANSPORT='" + v + "': expected udp (the default) or shm");
}

QoS QoS::from_name(const std::string& name) {
  if (name == "sensor_data") return sensor_data();
  if (name == "default" || name == "reliable") return reliable();
  if (name == "static" || name == "latched") return static_latched();
  throw ConfigError("QoS profile '" + name + "' is unknown (known: sensor_data, default, static)");
}

Context::Context(int argc, const char* const* argv, const ContextOptions& options) {
  if (argc > 0) args_ = parse_ros_args(argc, argv);
  if (!args_.log_level.empty()) set_log_level(args_.log_level);
  domain_id_ = options.domain_id >= 0 ? options.domain_id : domain_from_env();

  // DDS Security (SROS2 keystore, ROS_SECURITY_* switches): Fast DDS's built-in plugins.
  // Resolved before any thread starts, so a refusal (Enforce without keys) is a plain exception.
  const security::Environment sec = options.security ? *options.security : security::Environment::from_env();
  const std::string enclave = !sec.enclave_override.empty() ? sec.enclave_override
                              : !args_.enclave.empty()      ? args_.enclave
                              : !options.enclave.empty()    ? options.enclave
                                                            : "/";
  std::string security_warning;
  const auto security_properties = security::participant_properties(sec, enclave, &security_warning);
  if (security_properties) secured_enclave_ = enclave;

  // UNAV_FASTDDS_LOG=warning|info shows Fast DDS' own warnings (discovery, security handshakes).
  if (const char* level = std::getenv("UNAV_FASTDDS_LOG")) {
    const std::string l = level;
    if (l == "warning") eprosima::fastdds::dds::Log::SetVerbosity(eprosima::fastdds::dds::Log::Warning);
    if (l == "info") eprosima::fastdds::dds::Log::SetVerbosity(eprosima::fastdds::dds::Log::Info);
  }

  data_sharing_ = options.data_sharing;
  if (const char* ds = std::getenv("UNAV_DATA_SHARING")) {
    const std::string v = ds;
    if (v == "off" || v == "0" || v == "false") {
      data_sharing_ = false;
    } else if (v != "on" && v != "1" && v != "true" && !v.empty()) {
      throw ConfigError("environment UNAV_DATA_SHARING='" + v + "': expected on or off");
    }
  }

  handle_signals_ = options.handle_signals;
  if (handle_signals_) {
    // A process started in the background by a non-interactive shell inherits SIGINT ignored,
    // and an ignored signal is discarded even while blocked, so sigwait() would never see it:
    // take the default disposition back (the mask below keeps it from killing us).
    ::signal(SIGINT, SIG_DFL);
    ::signal(SIGTERM, SIG_DFL);
    // Block before DDS starts its threads so they inherit the mask and only our thread sees them.
    sigset_t set = handled_signals();
    pthread_sigmask(SIG_BLOCK, &set, nullptr);
    signal_thread_ = std::thread([this] { signal_loop(); });
  }

  try {
    create_participant(argc, argv, options, enclave, security_properties, security_warning, sec.keystore);
  } catch (...) {
    // The destructor will not run: stop what the constructor started, then report.
    if (participant_) {
      participant_->delete_contained_entities();
      fdds::DomainParticipantFactory::get_instance()->delete_participant(participant_);
      participant_ = nullptr;
    }
    stop_signal_thread();
    throw;
  }
}

Context::~Context() {
  for (auto it = shutdown_hooks_.rbegin(); it != shutdown_hooks_.rend(); ++it) (*it)();
  executor_.shutdown();
  clock_subscription_.reset();
  if (participant_) {
    participant_->delete_contained_entities();
    fdds::DomainParticipantFactory::get_instance()->delete_participant(participant_);
  }
  stop_signal_thread();
}

void Context::create_participant(
    int argc, const char* const* argv, const ContextOptions& options, const std::string& enclave,
    const std::optional<std::vector<std::pair<std::string, std::string>>>& security_properties,
    const std::string& security_warning, const std::string& keystore) {
  fdds::DomainParticipantQos pqos;
  std::string pname = options.participant_name;
  if (pname.empty() && argc > 0 && argv && argv[0]) {
    pname = argv[0];
    pname = pname.substr(pname.find_last_of('/') + 1);
  }
  pqos.name(pname.empty() ? "unav" : pname);
  if (security_properties) {
    for (const auto& [name, value] : *security_properties) pqos.properties().properties().emplace_back(name, value);
  } else if (!security_warning.empty()) {
    make_logger(pqos.name().to_string())->warn("{}", security_warning);
  }
  // ROS 2 participants announce their security enclave in USER_DATA.
  const std::string user_data = "enclave=" + enclave + ";";
  pqos.user_data().data_vec(std::vector<eprosima::fastrtps::rtps::octet>(user_data.begin(), user_data.end()));
  pqos.transport().use_builtin_transports = false;
  // UDPv4 (loopback between the processes of one host), plus data-sharing for the endpoints that
  // ask for it (images): no transport port in shared memory. Fast DDS 2.9's shared-memory
  // transport is opt-in (UNAV_TRANSPORT=shm) because it cannot survive a SIGKILLed peer: the next
  // participant on the host takes the dead one's port number, finds the port "zombie" and
  // recreates its segment, while the processes that had talked to the dead one keep writing into
  // the old, unlinked segment and never reach the newcomer (fixed upstream after 2.9:
  // eProsima/Fast-DDS PR #4728). Seen here as a respawned renderer that never rejoined lockstep
  // and a `unav topic pub` that one running node never heard, in 2 of 4 fault-injection runs.
  if (shm_transport_from_environment()) {
    auto shm = std::make_shared<eprosima::fastdds::rtps::SharedMemTransportDescriptor>();
    shm->segment_size(options.shm_segment_bytes);
    pqos.transport().user_transports.push_back(shm);
  }
  auto udp = std::make_shared<eprosima::fastdds::rtps::UDPv4TransportDescriptor>();
  // Socket buffers for a whole image burst (a 640x480 rgb8 image is 15 datagrams of 64 KB): with
  // the kernel's default 208 KiB, fragments overflow the receive buffer and each image waits for a
  // NACK round (~12 ms p50 instead of ~1 ms). Linux caps the request at net.core.rmem_max /
  // wmem_max (Debian 12: 208 KiB unless raised, e.g. sysctl -w net.core.rmem_max=4194304).
  udp->receiveBufferSize = kUdpBufferBytes;
  udp->sendBufferSize = kUdpBufferBytes;
  apply_discovery_plan(discovery_plan_from_env(security_properties.has_value()), domain_id_, pqos, *udp,
                       pqos.name().to_string());
  pqos.transport().user_transports.push_back(udp);

  participant_ = fdds::DomainParticipantFactory::get_instance()->create_participant(
      domain_id_, pqos, options.participant_listener,
      options.participant_listener ? fdds::StatusMask::none() : fdds::StatusMask::all());
  if (!participant_) {
    throw MiddlewareError("Fast DDS could not create a participant on domain " + std::to_string(domain_id_) +
                          (secured_enclave_.empty()
                               ? std::string()
                               : " with security enclave '" + secured_enclave_ + "' (keystore " + keystore +
                                     "): its certificate, key or signed documents were refused"));
  }
  if (data_sharing_) clean_dead_data_sharing();
  publisher_ = participant_->create_publisher(fdds::PUBLISHER_QOS_DEFAULT);
  subscriber_ = participant_->create_subscriber(fdds::SUBSCRIBER_QOS_DEFAULT);
  if (!publisher_ || !subscriber_) throw MiddlewareError("Fast DDS could not create a publisher/subscriber");

  // ros_discovery_info is not prefixed with rt/: it is the rmw's own topic.
  auto* graph_topic = topic("ros_discovery_info", new rmw_dds_common::msg::dds_::ParticipantEntitiesInfo_PubSubType());
  graph_writer_ = create_writer(graph_topic, QoS::static_latched());
}

// Data-sharing pools left in /dev/shm by writers of this host that died without closing (SIGKILL,
// a crash): removed before this participant makes its own (unav_runtime/shm_cleanup.hpp).
// UNAV_SHM_CLEAN=off keeps them.
void Context::clean_dead_data_sharing() {
  if (const char* v = std::getenv("UNAV_SHM_CLEAN"); v && (std::string(v) == "off" || std::string(v) == "0")) return;
  const auto& prefix = participant_->guid().guidPrefix.value;
  const shm::CleanReport r =
      shm::clean_data_sharing("/dev/shm", false, std::array<std::uint8_t, 2>{prefix[2], prefix[3]});
  if (r.removed > 0)
    make_logger("unav_runtime")
        ->info("removed {} data-sharing segments ({:.1f} MB) left in /dev/shm by processes that died", r.removed,
               static_cast<double>(r.removed_bytes) / 1e6);
  for (const auto& e : r.errors) make_logger("unav_runtime")->warn("/dev/shm/{} not removed", e);
}

void Context::stop_signal_thread() {
  if (!handle_signals_ || !signal_thread_.joinable()) return;
  exiting_ = true;
  pthread_kill(signal_thread_.native_handle(), SIGUSR2);
  signal_thread_.join();
}

void Context::signal_loop() {
  const sigset_t set = handled_signals();
  std::chrono::steady_clock::time_point first{};
  bool shutting_down = false;
  while (!exiting_) {
    int sig = 0;
    if (sigwait(&set, &sig) != 0) continue;
    if (sig == SIGUSR2) continue;  // exit request: loop condition decides
    if (!shutting_down) {
      shutting_down = true;
      first = std::chrono::steady_clock::now();
      executor_.shutdown();
    } else if (std::chrono::steady_clock::now() - first < std::chrono::seconds(2)) {
      // `timeout` and terminals often deliver the same Ctrl-C twice (to the process and its
      // group): a repeat within 2 s is the same request, not an insistence.
    } else {
      const char msg[] = "second signal: exiting without cleanup\n";
      (void)!write(STDERR_FILENO, msg, sizeof(msg) - 1);
      _exit(130);
    }
  }
}

fdds::Topic* Context::topic(const std::string& dds_topic, fdds::TopicDataType* type) {
  std::unique_ptr<fdds::TopicDataType> owned(type);
  std::lock_guard<std::mutex> lock(mutex_);
  const std::string type_name = owned->getName();
  auto it = topics_.find(dds_topic);
  if (it != topics_.end()) {
    if (it->second->get_type_name() != type_name)
      throw ConfigError("topic '" + dds_topic + "' is already used in this process with type '" +
                        it->second->get_type_name() + "', not '" + type_name + "'");
    return it->second;
  }
  if (const fdds::TypeSupport existing = participant_->find_type(type_name); !existing.empty()) {
    // Already registered: the new instance is not needed, if it is the same kind of type support.
    // A raw (any-type, bytes) one and a generated one cannot share a name in a participant: each
    // would hand the other's samples to its own (de)serializer (memory garbage, not an error).
    if (typeid(*existing.get()) != typeid(*owned))
      throw ConfigError("topic '" + dds_topic + "': type '" + type_name +
                        "' is already registered in this process by another type support (a generated type and "
                        "raw bytes cannot share a type name in one participant)");
  } else {
    fdds::TypeSupport ts(owned.release());
    if (ts.register_type(participant_) != ReturnCode_t::RETCODE_OK)
      throw MiddlewareError("Fast DDS refused to register type '" + type_name + "'");
  }
  fdds::Topic* t = participant_->create_topic(dds_topic, type_name, fdds::TOPIC_QOS_DEFAULT);
  if (!t) throw MiddlewareError("Fast DDS could not create topic '" + dds_topic + "' of type '" + type_name + "'");
  topics_[dds_topic] = t;
  return t;
}

std::string Context::access_hint(const char* way) const {
  if (secured_enclave_.empty()) return "";
  return std::string(": access control denies it? enclave '") + secured_enclave_ + "' must be allowed to " + way +
         " it (its permissions.xml in the keystore)";
}

BoundSwitch* Context::data_sharing_type(fdds::Topic* t, const QoS& q, bool writer) {
  if (!q.data_sharing || !data_sharing_ || !secured_enclave_.empty()) return nullptr;  // Fast DDS: not with security
  if (writer && q.max_sample_bytes == 0)
    throw ConfigError("topic '" + t->get_name() +
                      "': a data-sharing writer needs QoS max_sample_bytes, the largest serialized sample "
                      "(unav::serialized_bytes of the biggest message it will publish)");
  if (writer && q.max_sample_bytes > (1u << 30))
    throw ConfigError("topic '" + t->get_name() + "': QoS max_sample_bytes = " + std::to_string(q.max_sample_bytes) +
                      " is over the 1 GiB a data-sharing sample may have");
  auto* bs = dynamic_cast<BoundSwitch*>(participant_->find_type(t->get_type_name()).get());
  if (!bs)
    make_logger("unav_runtime")
        ->warn(
            "topic '{}': its type '{}' was registered without a bound switch, "
            "so it goes through the transports instead of data-sharing",
            t->get_name(), t->get_type_name());
  return bs;
}

fdds::DataWriter* Context::create_writer(fdds::Topic* t, const QoS& q) {
  fdds::DataWriterQos wqos = publisher_->get_default_datawriter_qos();
  apply_qos(q, wqos.reliability(), wqos.durability(), wqos.history());
  wqos.endpoint().history_memory_policy = eprosima::fastrtps::rtps::PREALLOCATED_WITH_REALLOC_MEMORY_MODE;
  // Unbounded ROS types cannot use data-sharing; shared memory transport carries them instead.
  wqos.data_sharing().off();
  if (q.durability == QoS::Durability::kTransientLocal) {
    // Late joiners of latched topics (camera_info, ros_discovery_info) get the sample within a
    // heartbeat: 200 ms instead of Fast DDS' 3 s default.
    wqos.reliable_writer_qos().times.heartbeatPeriod = eprosima::fastrtps::Duration_t(0, 200000000);
  }
  fdds::DataWriter* w = nullptr;
  if (BoundSwitch* bounded = data_sharing_type(t, q, true)) {
    // A pool of depth + 1 payloads of the bound in shared memory, written in place; readers on
    // this host with data-sharing read from it, all others get the same bytes by transport.
    fdds::DataWriterQos ds = wqos;
    ds.data_sharing().automatic();
    ds.endpoint().history_memory_policy = eprosima::fastrtps::rtps::PREALLOCATED_MEMORY_MODE;
    std::lock_guard<std::mutex> lock(endpoint_mutex_);
    bounded->set_bound(q.max_sample_bytes);
    w = publisher_->create_datawriter(t, ds);
    bounded->set_bound(0);
    if (!w)
      make_logger("unav_runtime")
          ->warn(
              "topic '{}': no data-sharing writer ({} bytes a sample; /dev/shm full?): "
              "falling back to the transports",
              t->get_name(), q.max_sample_bytes);
  }
  if (!w) w = publisher_->create_datawriter(t, wqos);
  if (!w)
    throw MiddlewareError("Fast DDS could not create a writer on '" + t->get_name() + "'" + access_hint("publish"));
  return w;
}

fdds::DataReader* Context::create_reader(fdds::Topic* t, const QoS& q, void* listener) {
  fdds::DataReaderQos rqos = subscriber_->get_default_datareader_qos();
  apply_qos(q, rqos.reliability(), rqos.durability(), rqos.history());
  rqos.endpoint().history_memory_policy = eprosima::fastrtps::rtps::PREALLOCATED_WITH_REALLOC_MEMORY_MODE;
  rqos.data_sharing().off();
  auto* l = static_cast<fdds::DataReaderListener*>(listener);
  fdds::DataReader* r = nullptr;
  if (BoundSwitch* bounded = data_sharing_type(t, q, false)) {
    // Fast DDS wants a bounded type for a data-sharing reader but never sizes anything by it
    // with dynamic memory: samples by transport (other vendors, other hosts, writers without
    // data-sharing) still arrive whatever their size.
    fdds::DataReaderQos ds = rqos;
    ds.data_sharing().automatic();
    ds.endpoint().history_memory_policy = eprosima::fastrtps::rtps::DYNAMIC_REUSABLE_MEMORY_MODE;
    std::lock_guard<std::mutex> lock(endpoint_mutex_);
    bounded->set_bound(BoundSwitch::kReaderBound);
    r = subscriber_->create_datareader(t, ds, l, fdds::StatusMask::data_available());
    bounded->set_bound(0);
  }
  if (!r) r = subscriber_->create_datareader(t, rqos, l, fdds::StatusMask::data_available());
  if (!r)
    throw MiddlewareError("Fast DDS could not create a reader on '" + t->get_name() + "'" + access_hint("subscribe"));
  return r;
}

void Context::delete_writer(fdds::DataWriter* w) {
  if (w && participant_) publisher_->delete_datawriter(w);
}

void Context::replace_writer(fdds::DataWriter*& slot, fdds::DataWriter* fresh) {
  fdds::DataWriter* old = nullptr;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    old = std::exchange(slot, fresh);
  }
  delete_writer(old);
}

void Context::delete_reader(fdds::DataReader* r) {
  if (r && participant_) subscriber_->delete_datareader(r);
}

void Context::add_node(Node* node) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    nodes_.push_back(node);
  }
  publish_graph();
}

void Context::remove_node(Node* node) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    nodes_.erase(std::remove(nodes_.begin(), nodes_.end(), node), nodes_.end());
  }
  publish_graph();
}

void Context::publish_graph() {
  rmw_dds_common::msg::ParticipantEntitiesInfo info;
  std::lock_guard<std::mutex> lock(mutex_);
  if (!graph_writer_) return;
  fill_gid(participant_->guid(), info.gid());
  for (const Node* n : nodes_) {
    rmw_dds_common::msg::dds_::NodeEntitiesInfo_ ne;
    ne.node_namespace(n->get_namespace());
    ne.node_name(n->name());
    for (const auto* p : n->publishers()) {
      rmw_dds_common::msg::Gid g;
      fill_gid(p->writer()->guid(), g);
      ne.writer_gid_seq().push_back(g);
    }
    for (const auto* s : n->subscriptions()) {
      rmw_dds_common::msg::Gid g;
      fill_gid(s->reader()->guid(), g);
      ne.reader_gid_seq().push_back(g);
    }
    info.node_entities_info_seq().push_back(ne);
  }
  graph_writer_->write(&info);
}

void Context::enable_sim_time() {
  if (clock_subscription_) return;
  clock_.set_sim_time_active(true);
  // ROS 2's ClockQoS: best effort, keep last 1 (matches reliable and best-effort publishers).
  auto sub = std::make_shared<Subscription<rosgraph_msgs::msg::Clock>>(
      *this, "rt/clock", QoS{QoS::Reliability::kBestEffort, QoS::Durability::kVolatile, 1},
      [this](const rosgraph_msgs::msg::Clock& c) {
        clock_.set_sim_time(Time::from_msg(c.clock().sec(), c.clock().nanosec()));
      });
  sub->start(QoS{QoS::Reliability::kBestEffort, QoS::Durability::kVolatile, 1});
  clock_subscription_ = sub;
}

}  // namespace unav
