#include "graph.hpp"

#include <cstdio>
#include <cstdlib>

#include <fastdds/rtps/reader/ReaderDiscoveryInfo.h>
#include <fastdds/rtps/writer/WriterDiscoveryInfo.h>
#include <fastdds/dds/domain/DomainParticipantListener.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>

#include "rmw_dds_common/msg/participant_entities_info.hpp"

namespace fdds = eprosima::fastdds::dds;
namespace rtps = eprosima::fastrtps::rtps;

namespace unav::cli {

struct Graph::Listener : fdds::DomainParticipantListener {
  mutable std::mutex mutex;
  std::map<rtps::GUID_t, EndpointInfo> endpoints;

  template <typename Data>
  void update(const Data& d, bool is_writer, bool removed) {
    std::lock_guard<std::mutex> lock(mutex);
    if (removed) {
      endpoints.erase(d.guid());
      return;
    }
    EndpointInfo e;
    e.dds_topic = d.topicName().to_string();
    e.dds_type = d.typeName().to_string();
    e.is_writer = is_writer;
    e.reliable = d.m_qos.m_reliability.kind == fdds::RELIABLE_RELIABILITY_QOS;
    e.transient_local = d.m_qos.m_durability.kind == fdds::TRANSIENT_LOCAL_DURABILITY_QOS;
    e.participant_key.assign(reinterpret_cast<const char*>(d.guid().guidPrefix.value), 12);
    endpoints[d.guid()] = e;
  }
  void on_publisher_discovery(fdds::DomainParticipant*, rtps::WriterDiscoveryInfo&& info) override {
    update(info.info, true, info.status == rtps::WriterDiscoveryInfo::REMOVED_WRITER);
  }
  void on_subscriber_discovery(fdds::DomainParticipant*, rtps::ReaderDiscoveryInfo&& info) override {
    update(info.info, false, info.status == rtps::ReaderDiscoveryInfo::REMOVED_READER);
  }
};

std::chrono::milliseconds default_spin_time() {
  if (const char* s = std::getenv("UNAV_SPIN_TIME"))
    return std::chrono::milliseconds(static_cast<int64_t>(std::atof(s) * 1000));
  return std::chrono::milliseconds(2000);
}

Graph::Graph() : listener_(std::make_unique<Listener>()) {
  unav::ContextOptions o;
  o.handle_signals = true;
  o.participant_name = "unav_cli";
  o.participant_listener = listener_.get();
  ctx_ = std::make_unique<unav::Context>(o);
}

Graph::~Graph() { ctx_.reset(); }

std::vector<EndpointInfo> Graph::endpoints() const {
  std::lock_guard<std::mutex> lock(listener_->mutex);
  std::vector<EndpointInfo> out;
  for (const auto& kv : listener_->endpoints) out.push_back(kv.second);
  return out;
}

std::map<std::string, std::set<std::string>> Graph::topics() const {
  std::map<std::string, std::set<std::string>> out;
  for (const auto& e : endpoints())
    if (e.dds_topic.rfind("rt/", 0) == 0) out[unav::from_dds_topic(e.dds_topic)].insert(e.dds_type);
  return out;
}

std::string Graph::writer_type(const std::string& ros_topic) const {
  const std::string dds_topic = unav::to_dds_topic(ros_topic);
  std::string type;
  for (const auto& e : endpoints())
    if (e.is_writer && e.dds_topic == dds_topic) type = e.dds_type;
  return type;
}

std::string Graph::wait_for_type(const std::string& ros_topic, std::chrono::milliseconds timeout) {
  std::string type;
  ctx_->spin_until(
      [&] {
        type = writer_type(ros_topic);
        return !type.empty();
      },
      timeout);
  return type;
}

unav::QoS Graph::matching_qos(const std::string& ros_topic) const {
  const std::string dds_topic = unav::to_dds_topic(ros_topic);
  bool any = false, all_reliable = true, all_transient = true;
  for (const auto& e : endpoints()) {
    if (!e.is_writer || e.dds_topic != dds_topic) continue;
    any = true;
    all_reliable = all_reliable && e.reliable;
    all_transient = all_transient && e.transient_local;
  }
  unav::QoS q = unav::QoS::reliable(10);
  if (!any) return q;
  if (!all_reliable) q.reliability = unav::QoS::Reliability::kBestEffort;
  if (all_transient) q.durability = unav::QoS::Durability::kTransientLocal;
  return q;
}

std::vector<std::string> Graph::nodes() {
  std::map<std::string, std::vector<std::string>> by_participant;
  unav::Node probe("_unav_cli_node_list", {ctx_.get()});
  // Raw typed reader of ros_discovery_info (not prefixed), transient local: every live
  // participant's latest graph arrives on subscription.
  auto* topic = ctx_->topic("ros_discovery_info", new rmw_dds_common::msg::dds_::ParticipantEntitiesInfo_PubSubType());
  // Depth 100, not 1: the topic is keyless, so with depth 1 a sample from one participant would
  // overwrite another's before it is taken.
  auto* reader = ctx_->create_reader(
      topic, unav::QoS{unav::QoS::Reliability::kReliable, unav::QoS::Durability::kTransientLocal, 100}, nullptr);
  // Listen for the spin time, then longer (up to twice) while a participant that writes
  // ros_discovery_info has not delivered its graph yet.
  const auto start = std::chrono::steady_clock::now();
  auto complete = [&] {
    for (const auto& e : endpoints())
      if (e.is_writer && e.dds_topic == "ros_discovery_info" &&
          !by_participant.count(e.participant_key + std::string(12, '\0')))
        return false;
    return true;
  };
  rmw_dds_common::msg::ParticipantEntitiesInfo info;
  fdds::SampleInfo si;
  while (ctx_->ok()) {
    const auto waited = std::chrono::steady_clock::now() - start;
    if (waited >= 2 * default_spin_time() || (waited >= default_spin_time() && complete())) break;
    while (reader->take_next_sample(&info, &si) == ReturnCode_t::RETCODE_OK) {
      if (!si.valid_data) continue;
      // Key: GUID prefix (12 bytes) + 12 zero bytes, comparable with participant_key.
      std::string key(info.gid().data().begin(), info.gid().data().begin() + 12);
      key += std::string(12, '\0');
      auto& names = by_participant[key];
      names.clear();
      for (const auto& n : info.node_entities_info_seq()) {
        if (n.node_name().to_string().rfind('_', 0) == 0) continue;  // hidden nodes (ours, ROS' _ros2cli)
        const std::string ns = n.node_namespace().to_string();
        names.push_back((ns == "/" ? "" : ns) + "/" + n.node_name().to_string());
      }
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  if (std::getenv("UNAV_DEBUG")) {
    fdds::SubscriptionMatchedStatus st;
    reader->get_subscription_matched_status(st);
    std::fprintf(stderr, "node list: %d matched graph writers, %zu participants reported\n", st.current_count,
                 by_participant.size());
  }
  ctx_->delete_reader(reader);
  std::set<std::string> all;
  for (const auto& kv : by_participant) all.insert(kv.second.begin(), kv.second.end());
  return {all.begin(), all.end()};
}

}  // namespace unav::cli
