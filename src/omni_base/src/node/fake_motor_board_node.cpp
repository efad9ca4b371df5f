// fake_motor_board: a pseudo-terminal that behaves like the motor board, for bench tests without
// hardware. omni_base opens the link path (~link) as if it were /dev/ttyUSB0.
//
// Misbehaviour on request, on ~fault (std_msgs/String):
//   "none"            behave
//   "stall"           wheels blocked, fault reported
//   "drop P"          drop each reply with probability P (0..1)
//   "garbage"         random bytes and false start sequences between replies
//   "disconnect S"    close the pty (an unplugged cable) for S seconds, then come back
//   "reboot"          counters, set-points and the board clock back to zero, motors disabled
//   "forge T C0 C1 .." one extra STATE frame now, with board time T ms and counts C0 C1 .., and the
//                     board's own frame right behind it in the same write (a glitching firmware, a second
//                     writer on the port, a replayed log); the board itself carries on
// The true wheel speeds and angles (never reset, not even by a reboot) are published on ~wheels
// (sensor_msgs/JointState) at 200 Hz.
#include <docking_settings/param_reader.h>
#include <docking_settings/ros_loader.h>
#include <docking_settings/run_node.h>
#include <poll.h>
#include <ros/ros.h>
#include <sensor_msgs/JointState.h>
#include <std_msgs/String.h>

#include <chrono>
#include <sstream>

#include "omni_base/fake_motor_board.h"
#include "omni_base/serial_port.h"
#include "omni_base/base_settings.h"

namespace {

double steadySeconds() {
  static const auto start = std::chrono::steady_clock::now();
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

class FakeMotorBoardNode {
 public:
  FakeMotorBoardNode(ros::NodeHandle& pnh) : pnh_(pnh), base_(loadBase(pnh)), board_(boardConfig(pnh, base_)) {
    // Launch wiring, not a setting: where the pseudo-terminal is linked.
    link_path_ = docking_settings::ParamReader(pnh).optional<std::string>("link", "/tmp/omni_base_fake_board");
    wheel_names_ = base_.wheels.names;
    fault_sub_ = pnh.subscribe("fault", 10, &FakeMotorBoardNode::onFault, this);
    wheels_pub_ = pnh.advertise<sensor_msgs::JointState>("wheels", 10);
    connect();
  }

  void run() {
    double last_publish = 0.0;
    std::vector<uint8_t> rx;
    while (ros::ok()) {
      const double now = steadySeconds();
      if (!pty_.isOpen() && now >= reconnect_at_) connect();
      if (pty_.isOpen()) {
        pollfd pfd{pty_.masterFd(), POLLIN, 0};
        ::poll(&pfd, 1, 1);
        rx.clear();
        pty_.readAvailable(rx);
        board_.advanceTo(steadySeconds());
        if (!rx.empty()) {
          const auto reply = board_.receive(rx.data(), rx.size(), steadySeconds());
          if (!reply.empty()) pty_.write(reply);
        }
      } else {
        board_.advanceTo(now);
        ros::Duration(0.001).sleep();
      }
      if (now - last_publish >= 0.005) {
        publishWheels();
        last_publish = now;
      }
      ros::spinOnce();
    }
  }

 private:
  /// The base it stands in for: config/omni_base.yaml, as omni_base_node reads it.
  static omni_base::OmniBaseSettings loadBase(const ros::NodeHandle& pnh) {
    omni_base::OmniBaseSettings base;
    docking_settings::loadSettings(pnh, base);
    docking_settings::ParamReader(pnh).validated([&] { omni_base::validate(base); });
    return base;
  }

  static omni_base::FakeMotorBoardConfig boardConfig(const ros::NodeHandle& pnh, const omni_base::OmniBaseSettings& base) {
    omni_base::FakeMotorBoardConfig c;
    c.wheel_count = base.wheels.names.size();
    c.drive = omni_base::driveModel(base.motor);
    c.motor_time_constant_s = base.motor.time_constant_s;
    c.counts_per_rev = base.wheels.encoder_counts_per_rev;
    // A test's choice of misbehaviour sequence, not a setting of the base.
    c.random_seed = static_cast<uint32_t>(docking_settings::ParamReader(pnh).optional<int>("random_seed", 42));
    return c;
  }

  void connect() {
    if (pty_.open(link_path_)) {
      ROS_INFO("fake_motor_board: listening on %s (-> %s)", link_path_.c_str(), pty_.slavePath().c_str());
    } else {
      ROS_ERROR("fake_motor_board: %s; retrying in 1 s", pty_.lastError().c_str());
      reconnect_at_ = steadySeconds() + 1.0;
    }
  }

  void onFault(const std_msgs::String::ConstPtr& msg) {
    std::istringstream in(msg->data);
    std::string kind;
    double value = 0.0;
    in >> kind >> value;
    if (kind == "none") {
      board_.setStalled(false);
      board_.setReplyDropProbability(0.0);
      board_.setGarbageBetweenFrames(false);
    } else if (kind == "stall") {
      board_.setStalled(true);
    } else if (kind == "drop") {
      board_.setReplyDropProbability(value);
    } else if (kind == "garbage") {
      board_.setGarbageBetweenFrames(true);
    } else if (kind == "disconnect") {
      pty_.close();
      reconnect_at_ = steadySeconds() + (value > 0.0 ? value : 1.0);
    } else if (kind == "reboot") {
      board_.resetCounters();
    } else if (kind == "forge") {
      if (!forge(msg->data)) return;
    } else {
      ROS_ERROR("fake_motor_board: unknown fault '%s' (none|stall|drop P|garbage|disconnect S|reboot|forge T C..)",
                msg->data.c_str());
      return;
    }
    ROS_WARN("fake_motor_board: fault mode '%s'", msg->data.c_str());
  }

  /// "forge T C0 C1 ...": writes one STATE frame with that board time and those counts.
  bool forge(const std::string& command) {
    std::istringstream in(command);
    std::string kind;
    int64_t board_time_ms = 0;
    in >> kind >> board_time_ms;
    std::vector<int32_t> counts;
    for (int64_t c = 0; in >> c;) counts.push_back(static_cast<int32_t>(c));
    if (board_time_ms < 0 || counts.empty() || !pty_.isOpen()) {
      ROS_ERROR("fake_motor_board: cannot forge '%s' (forge T C0 C1 ..., with the link up)", command.c_str());
      return false;
    }
    // The board's own frame in the same write: the host reads both at once, as it would a burst.
    auto frames = board_.forgedState(static_cast<uint32_t>(board_time_ms), counts);
    const auto own = board_.currentState();
    frames.insert(frames.end(), own.begin(), own.end());
    pty_.write(frames);
    return true;
  }

  void publishWheels() {
    sensor_msgs::JointState js;
    js.header.stamp = ros::Time::now();
    js.name = wheel_names_;
    js.position = board_.wheelAngles();
    js.velocity = board_.wheelSpeeds();
    wheels_pub_.publish(js);
  }

  ros::NodeHandle pnh_;
  omni_base::OmniBaseSettings base_;
  omni_base::FakeMotorBoard board_;
  omni_base::PseudoTerminal pty_;
  std::string link_path_;
  std::vector<std::string> wheel_names_;
  double reconnect_at_{0.0};
  ros::Subscriber fault_sub_;
  ros::Publisher wheels_pub_;
};

int main(int argc, char** argv) {
  ros::init(argc, argv, "fake_motor_board");
  return docking_settings::runNode([] {
    ros::NodeHandle pnh("~");
    FakeMotorBoardNode node(pnh);
    node.run();
  });
}
