// talker: publishes std_msgs/String "Hello World: N" on `chatter` (the ros2 demos talker).
//
// Ports:   pub  chatter  std_msgs/msg/String  reliable, keep last 10
// Params:  rate (double, Hz, (0, 1000]): publish rate
//          message (string): text before the counter
#include "std_msgs/msg/string.hpp"
#include "unav_common/config.hpp"
#include "unav_runtime/runtime.hpp"

namespace unav_examples {

struct TalkerParams {
  double rate = 2.0;
  std::string message = "Hello World";
  template <class Archive>
  void Serialize(Archive* a) {
    a->Visit(unav::common::Field("rate", &rate).Range(1e-3, 1000.0).Unit("Hz").Doc("publish rate"));
    a->Visit(unav::common::Field("message", &message).Doc("text before the counter"));
  }
};

class Talker : public unav::Node {
 public:
  explicit Talker(const unav::NodeOptions& options) : Node("talker", options) {
    TalkerParams prm;
    declare_params(&prm);
    const double rate = prm.rate;
    prefix_ = prm.message;
    pub_ = create_publisher<std_msgs::msg::String>("chatter", unav::QoS::reliable());
    timer_ = create_wall_timer(std::chrono::nanoseconds(static_cast<int64_t>(1e9 / rate)), [this] { tick(); });
  }

 private:
  void tick() {
    std_msgs::msg::String msg;
    msg.data(prefix_ + ": " + std::to_string(++count_));
    logger()->info("Publishing: '{}'", msg.data());
    pub_->publish(msg);
  }

  std::string prefix_;
  uint64_t count_ = 0;
  std::shared_ptr<unav::Publisher<std_msgs::msg::String>> pub_;
  std::shared_ptr<unav::Timer> timer_;
};

}  // namespace unav_examples

int main(int argc, char** argv) { return unav::run_node<unav_examples::Talker>(argc, argv); }
