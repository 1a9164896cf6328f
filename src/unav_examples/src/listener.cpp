// listener: logs every std_msgs/String received on `chatter` (the ros2 demos listener).
//
// Ports:   sub  chatter  std_msgs/msg/String  reliable, keep last 10
// Params:  exit_after (int, >= 0): exit after this many messages; 0 = run until Ctrl-C
#include "std_msgs/msg/string.hpp"
#include "unav_common/config.hpp"
#include "unav_runtime/runtime.hpp"

namespace unav_examples {

struct ListenerParams {
  int64_t exit_after = 0;
  template <class Archive>
  void Serialize(Archive* a) {
    a->Visit(unav::common::Field("exit_after", &exit_after).Min(0.0).Doc("exit after N messages, 0 = never"));
  }
};

class Listener : public unav::Node {
 public:
  explicit Listener(const unav::NodeOptions& options) : Node("listener", options) {
    ListenerParams prm;
    declare_params(&prm);
    exit_after_ = prm.exit_after;
    sub_ = create_subscription<std_msgs::msg::String>("chatter", unav::QoS::reliable(),
                                                      [this](const std_msgs::msg::String& m) { on_message(m); });
  }

 private:
  void on_message(const std_msgs::msg::String& m) {
    logger()->info("I heard: '{}'", m.data());
    if (exit_after_ > 0 && ++count_ >= exit_after_) context().shutdown();
  }

  int64_t exit_after_ = 0;
  int64_t count_ = 0;
  std::shared_ptr<unav::Subscription<std_msgs::msg::String>> sub_;
};

}  // namespace unav_examples

int main(int argc, char** argv) { return unav::run_node<unav_examples::Listener>(argc, argv); }
