#include "unav_runtime/publisher.hpp"

#include <fastdds/dds/core/status/PublicationMatchedStatus.hpp>
#include <fastdds/dds/core/status/SubscriptionMatchedStatus.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/DataReaderListener.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/topic/Topic.hpp>

#include "unav_runtime/logging.hpp"

namespace fdds = eprosima::fastdds::dds;

namespace unav {
namespace {

// Runs on a DDS thread: only hands the subscription to the executor.
class ReaderListener : public fdds::DataReaderListener {
 public:
  explicit ReaderListener(std::weak_ptr<SubscriptionBase> sub) : sub_(std::move(sub)) {}
  void on_data_available(fdds::DataReader*) override {
    if (auto s = sub_.lock()) s->on_data();
  }

 private:
  std::weak_ptr<SubscriptionBase> sub_;
};

}  // namespace

PublisherBase::PublisherBase(Context& ctx, const std::string& topic, fdds::TopicDataType* type, const QoS& qos)
    : ctx_(ctx), topic_(topic), max_sample_bytes_(qos.data_sharing ? qos.max_sample_bytes : 0), qos_(qos) {
  dds_topic_ = ctx_.topic(topic, type);
  writer_ = ctx_.create_writer(dds_topic_, qos);
}

PublisherBase::~PublisherBase() { ctx_.delete_writer(writer_); }

int PublisherBase::subscription_count() const {
  fdds::PublicationMatchedStatus status;
  writer_->get_publication_matched_status(status);
  return status.current_count;
}

namespace {
const char* return_code_name(const ReturnCode_t& rc) {
  switch (rc()) {
    case ReturnCode_t::RETCODE_TIMEOUT:
      return "timeout: the writer stayed busy for max_blocking_time";
    case ReturnCode_t::RETCODE_OUT_OF_RESOURCES:
      return "out of resources: history or payload pool full";
    case ReturnCode_t::RETCODE_BAD_PARAMETER:
      return "bad parameter";
    case ReturnCode_t::RETCODE_PRECONDITION_NOT_MET:
      return "precondition not met";
    case ReturnCode_t::RETCODE_NOT_ENABLED:
      return "writer not enabled";
    default:
      return "error";
  }
}
}  // namespace

bool PublisherBase::write(const void* sample) {
  // A sample taken after refusals ends their run (logged once).
  const auto accepted = [this] {
    if (failures_since_ok_ != 0) {
      make_logger("unav_runtime")
          ->warn("topic '{}': the middleware accepts samples again after {} refused", topic_, failures_since_ok_);
      failures_since_ok_ = 0;
    }
    return true;
  };
  const ReturnCode_t rc = refuse_for_test_ > 0 ? (--refuse_for_test_, ReturnCode_t::RETCODE_OUT_OF_RESOURCES)
                                               : writer_->write(const_cast<void*>(sample), fdds::HANDLE_NIL);
  if (rc == ReturnCode_t::RETCODE_OK) return accepted();
  ++write_failures_;
  const auto now = std::chrono::steady_clock::now();
  if (failures_since_ok_++ == 0) first_refusal_ = now;
  // Out of resources twice in a row over at least 0.5 s (a lockstep frame is sent again each
  // second; a camera at 10+ Hz refuses several times in that span), at most once every 10 s (a
  // sample over the bound is refused by any pool: no churn).
  using std::chrono::milliseconds;
  // (A writer that fell back to the transports, data-sharing off, keeps its history: not this case.)
  if (rc == ReturnCode_t::RETCODE_OUT_OF_RESOURCES && failures_since_ok_ >= 2 &&
      writer_->get_qos().data_sharing().kind() != fdds::DataSharingKind::OFF &&
      now - first_refusal_ >= milliseconds(500) &&
      (recreations_ == 0 || now - last_recreation_ >= milliseconds(10000))) {
    make_logger("unav_runtime")
        ->warn(
            "topic '{}': the data-sharing writer refused {} samples in a row over {:.1f} s (out of resources: its "
            "payload pool stays full); creating it again (readers match the new one)",
            topic_, failures_since_ok_, std::chrono::duration<double>(now - first_refusal_).count());
    // The new writer first, swapped in under the graph's lock, then the old one goes:
    // Context::publish_graph() reads writer() from other threads under that lock.
    ctx_.replace_writer(writer_, ctx_.create_writer(dds_topic_, qos_));
    ++recreations_;
    last_recreation_ = now;
    ctx_.publish_graph();  // the node's writer has a new GUID (ros_discovery_info)
    if (writer_->write(const_cast<void*>(sample), fdds::HANDLE_NIL) == ReturnCode_t::RETCODE_OK) return accepted();
  }
  if ((write_failures_ & (write_failures_ - 1)) == 0) {  // 1st, 2nd, 4th, 8th ...
    make_logger("unav_runtime")
        ->error(
            "topic '{}': the middleware refused a sample ({}{}); {} refused so far", topic_, return_code_name(rc),
            max_sample_bytes_ != 0
                ? "; larger than the data-sharing bound max_sample_bytes = " + std::to_string(max_sample_bytes_) + "?"
                : std::string(),
            write_failures_);
  }
  return false;
}

SubscriptionBase::SubscriptionBase(Context& ctx, const std::string& topic, fdds::TopicDataType* type, const QoS&)
    : ctx_(ctx), topic_(topic) {
  dds_topic_ = ctx_.topic(topic, type);
}

void SubscriptionBase::start(const QoS& qos) {
  auto* listener = new ReaderListener(weak_from_this());
  listener_ = std::unique_ptr<void, void (*)(void*)>(listener, [](void* p) { delete static_cast<ReaderListener*>(p); });
  reader_.store(ctx_.create_reader(dds_topic_, qos, static_cast<fdds::DataReaderListener*>(listener)),
                std::memory_order_release);
  // Samples that arrived before the listener was attached (transient local) are picked up here.
  ctx_.executor().notify(shared_from_this());
}

SubscriptionBase::~SubscriptionBase() {
  if (fdds::DataReader* r = reader_.load()) {
    r->set_listener(nullptr);
    ctx_.delete_reader(r);
  }
}

int SubscriptionBase::publisher_count() const {
  fdds::SubscriptionMatchedStatus status;
  reader()->get_subscription_matched_status(status);
  return status.current_count;
}

void SubscriptionBase::on_data() {
  auto self = shared_from_this();
  ctx_.executor().notify(self);
  // The executor may have taken everything before the prefetch: then nothing was prefetched. If
  // it took a sample, the executor may have gone back to sleep meanwhile: wake it for that one.
  if (prefetch()) ctx_.executor().notify(self);
}

bool SubscriptionBase::take(void* sample) {
  // The listener can call this (prefetch) while create_reader() is still running in start(): a
  // transient-local sample arriving then found reader_ still null and crashed the process (seen
  // twice in late-joiner /tf_static tests); the executor takes it after start() instead.
  fdds::DataReader* r = reader();
  if (r == nullptr) return false;
  fdds::SampleInfo info;
  while (r->take_next_sample(sample, &info) == ReturnCode_t::RETCODE_OK) {
    if (info.valid_data) return true;
  }
  return false;
}

}  // namespace unav
