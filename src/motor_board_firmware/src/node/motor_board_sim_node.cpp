// motor_board_sim: the motor board's firmware in the loop. Runs the firmware's .hex on a simulated
// ATmega328P (libsimavr, 16 MHz) behind a pseudo-terminal that omni_base_node opens as its serial
// device (~link), and closes the loop through one of two plants (~plant):
//   model      the bench: each wheel a DC motor with lag and friction (config/omni_base.yaml motor/*, this
//              package's config/board_sim.yaml), quadrature edges from its angle; this node owns time and
//              publishes /clock (simulated board time) at ~real_time_factor of the wall clock.
//   simulator  docking_sim moves the chaser: the duties on the board's pins go out as wheels/command
//              (the speed each duty settles to), and wheels/encoders come back as quadrature edges on
//              the encoder pins; the board follows the simulator's /clock.
// ~probe (motor_board_firmware/BoardProbe, 100 Hz of simulated time): what the board's pins and wheels
// do. ~reset (std_msgs/Empty): the board's reset button.
#include <docking_msgs/WheelCommand.h>
#include <docking_msgs/WheelEncoders.h>
#include <docking_msgs/names.h>
#include <motor_board_firmware/BoardProbe.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Clock.h>
#include <std_msgs/Empty.h>

#include <cmath>
#include <memory>

#include "motor_board_firmware/board_bench.h"
#include <docking_settings/param_reader.h>
#include <docking_settings/ros_loader.h>
#include <docking_settings/run_node.h>

#include "omni_base/base_settings.h"
#include "omni_base/serial_port.h"

namespace motor_board_firmware {
namespace {

constexpr double kSliceS = 0.002;        // simulated time between looks at the pseudo-terminal
constexpr double kProbePeriodS = 0.01;
constexpr double kClockPeriodS = 0.005;  // /clock in model mode
constexpr double kClockOffsetS = 1.0;    // sim time 0 reads as "no time yet" to ROS nodes
constexpr double kTargetSlackS = 1e-6;
constexpr double kCommandRefreshS = 0.05;

class MotorBoardSimNode {
 public:
  explicit MotorBoardSimNode(ros::NodeHandle& nh, ros::NodeHandle& pnh) : nh_(nh) {
    const docking_settings::ParamReader p(pnh);
    omni_base::OmniBaseSettings base;  // the base it drives: config/omni_base.yaml, as omni_base_node reads it
    docking_settings::loadSettings(pnh, base);
    p.validated([&] { omni_base::validate(base); });
    plant_ = p.optional<std::string>("plant", "model");
    if (plant_ != "model" && plant_ != "simulator") p.invalid("plant", "must be 'model' or 'simulator', got '" + plant_ + "'");
    if (base.wheels.names.size() != kWheels) p.invalid("wheels/names", "the motor board drives exactly 3 wheels");
    BoardBenchConfig config;
    config.hex_path = p.optional<std::string>("hex", firmwareHexPath());
    config.motor.volts_per_rad_s = base.motor.volts_per_rad_s;
    config.motor.supply_volts = base.motor.supply_volts;
    config.motor.time_constant_s = base.motor.time_constant_s;
    config.motor.friction_volts = p.require<double>("friction_volts");
    config.model_step_s = p.require<double>("model_step_s");
    if (!(config.motor.friction_volts >= 0.0 && config.motor.friction_volts < config.motor.supply_volts) ||
        !(config.model_step_s >= 1e-5 && config.model_step_s <= 1e-3)) {
      p.invalid("friction_volts", "friction_volts must be in [0, supply) and model_step_s in [1e-5, 1e-3]");
    }
    config.counts_per_rev = base.wheels.encoder_counts_per_rev;
    config.internal_plant = plant_ == "model";
    real_time_factor_ = p.optional<double>("real_time_factor", 1.0);
    if (!(real_time_factor_ > 0.0 && real_time_factor_ <= 10.0)) p.invalid("real_time_factor", "must be in (0, 10]");
    bench_ = std::make_unique<BoardBench>(config);
    link_path_ = p.optional<std::string>("link", "/tmp/motor_board_sim");
    if (!pty_.open(link_path_)) throw std::runtime_error("cannot open the pseudo-terminal: " + pty_.lastError());
    probe_pub_ = pnh.advertise<BoardProbe>("probe", 20);
    reset_sub_ = pnh.subscribe("reset", 1, &MotorBoardSimNode::onReset, this);
    if (plant_ == "model") {
      clock_pub_ = nh.advertise<rosgraph_msgs::Clock>("/clock", 10);
    } else {
      command_pub_ = nh.advertise<docking_msgs::WheelCommand>(docking_msgs::topics::kWheelCommand, 10);
      encoder_sub_ = nh.subscribe(docking_msgs::topics::kWheelEncoders, 10, &MotorBoardSimNode::onEncoders, this,
                                  ros::TransportHints().tcpNoDelay());
    }
    ROS_INFO("motor_board_sim: firmware %s on a simulated ATmega328P, serial link %s (-> %s), plant: %s",
             config.hex_path.c_str(), link_path_.c_str(), pty_.slavePath().c_str(), plant_.c_str());
  }

  void run() {
    const ros::WallTime wall_start = ros::WallTime::now();
    while (ros::ok()) {
      ros::spinOnce();
      const double target = plant_ == "model" ? (ros::WallTime::now() - wall_start).toSec() * real_time_factor_
                                              : simulatorTime();
      // Within a few cycles of the target is there (the CPU stops at instruction boundaries).
      while (bench_->seconds() < target - kTargetSlackS && ros::ok()) advanceSlice(target);
      reportProblems();
      ros::WallDuration(0.0005).sleep();
    }
  }

 private:
  /// The simulator's clock relative to its first tick (the board powers up then), or 0 before it.
  double simulatorTime() {
    const ros::Time now = ros::Time::now();
    if (now.isZero()) return 0.0;
    if (sim_start_.isZero()) sim_start_ = now;
    return (now - sim_start_).toSec();
  }

  void advanceSlice(double target) {
    rx_.clear();
    if (pty_.readAvailable(rx_) && !rx_.empty()) bench_->send(rx_);
    bench_->runUntil(std::min(target, bench_->seconds() + kSliceS));
    const auto out = bench_->receiveBytes();
    if (!out.empty()) pty_.write(out);
    const double now = bench_->seconds();
    if (plant_ == "model" && now - last_clock_s_ >= kClockPeriodS - 1e-9) {
      rosgraph_msgs::Clock clock;
      clock.clock = ros::Time(now + kClockOffsetS);
      clock_pub_.publish(clock);
      last_clock_s_ = now;
    }
    if (plant_ == "simulator") publishWheelCommand();
    if (now - last_probe_s_ >= kProbePeriodS - 1e-9) {
      publishProbe();
      last_probe_s_ = now;
    }
  }

  ros::Time stamp() const {
    return plant_ == "model" ? ros::Time(bench_->seconds() + kClockOffsetS) : sim_start_ + ros::Duration(bench_->seconds());
  }

  /// On every change of the drive, and every kCommandRefreshS (docking_sim stops wheels whose command is
  /// 0.25 s old, as the board's own watchdog would).
  void publishWheelCommand() {
    const auto& outputs = bench_->outputs();
    const bool changed = outputs.bridges_enabled != last_command_.bridges_enabled || outputs.duty != last_command_.duty;
    if (!changed && bench_->seconds() - last_command_s_ < kCommandRefreshS) return;
    last_command_ = outputs;
    last_command_s_ = bench_->seconds();
    docking_msgs::WheelCommand command;
    command.header.stamp = stamp();
    command.header.frame_id = docking_msgs::frames::kBaseLink;
    command.enable = outputs.bridges_enabled;
    for (std::size_t i = 0; i < kWheels; ++i) {
      command.velocity.push_back(outputs.bridges_enabled ? bench_->motor(i).steadySpeed(outputs.duty[i]) : 0.0);
    }
    command_pub_.publish(command);
  }

  void onEncoders(const docking_msgs::WheelEncoders::ConstPtr& msg) {
    if (msg->counts.size() != kWheels) return;
    // The simulator's counters are 32-bit; the edges put on the pins follow their differences.
    if (last_counts_.empty()) {
      last_counts_.assign(msg->counts.begin(), msg->counts.end());
      unwrapped_.assign(kWheels, 0);
    }
    for (std::size_t i = 0; i < kWheels; ++i) {
      unwrapped_[i] += static_cast<int32_t>(static_cast<uint32_t>(msg->counts[i]) - static_cast<uint32_t>(last_counts_[i]));
      last_counts_[i] = msg->counts[i];
    }
    const double period = last_encoder_stamp_.isZero() ? 0.01 : (msg->header.stamp - last_encoder_stamp_).toSec();
    last_encoder_stamp_ = msg->header.stamp;
    bench_->setEncoderTargets(unwrapped_, std::clamp(period, 0.001, 0.05));
  }

  void publishProbe() {
    BoardProbe probe;
    probe.header.stamp = stamp();
    const auto& outputs = bench_->outputs();
    probe.bridges_enabled = outputs.bridges_enabled;
    for (std::size_t i = 0; i < kWheels; ++i) {
      probe.duty.push_back(outputs.duty[i]);
      probe.wheel_angle.push_back(plant_ == "model" ? bench_->wheelAngle(i) : 0.0);
      probe.wheel_speed.push_back(plant_ == "model" ? bench_->wheelSpeed(i) : 0.0);
      probe.encoder_edges.push_back(bench_->encoderEdges(i));
    }
    probe.last_valid_command_s = bench_->lastValidCommandAt().value_or(-1.0);
    probe.last_drive_stop_s = bench_->lastDriveStopAt().value_or(-1.0);
    probe.unexpected_resets = bench_->board().unexpectedResets();
    probe.requested_resets = bench_->board().requestedResets();
    probe.worst_loop_cycles = bench_->board().worstBusyCycles();
    probe.pwm_pin_high_events = bench_->pwmPinHighEvents();
    probe.firmware_encoder_glitches = bench_->firmwareEncoderGlitches();
    probe_pub_.publish(probe);
  }

  void onReset(const std_msgs::Empty::ConstPtr&) {
    ROS_WARN("motor_board_sim: reset button pressed at %.3f s (simulated)", bench_->seconds());
    bench_->board().pressReset();
  }

  void reportProblems() {
    for (const auto& line : bench_->board().takeLog()) ROS_WARN_THROTTLE(5.0, "motor_board_sim: simavr: %s", line.c_str());
    if (bench_->board().unexpectedResets() != reported_resets_) {
      reported_resets_ = bench_->board().unexpectedResets();
      ROS_ERROR("motor_board_sim: the firmware reset itself (%llu so far): hardware watchdog or crash",
                static_cast<unsigned long long>(reported_resets_));
    }
  }

  ros::NodeHandle nh_;
  std::string plant_;
  double real_time_factor_{1.0};
  std::unique_ptr<BoardBench> bench_;
  omni_base::PseudoTerminal pty_;
  std::string link_path_;
  std::vector<uint8_t> rx_;
  ros::Publisher probe_pub_, clock_pub_, command_pub_;
  ros::Subscriber reset_sub_, encoder_sub_;
  ros::Time sim_start_;
  ros::Time last_encoder_stamp_;
  std::vector<int32_t> last_counts_;
  std::vector<int64_t> unwrapped_;
  double last_clock_s_{-1.0};
  MotorOutputs last_command_;
  double last_command_s_{-1.0};
  double last_probe_s_{-1.0};
  uint64_t reported_resets_{0};
};

}  // namespace
}  // namespace motor_board_firmware

int main(int argc, char** argv) {
  ros::init(argc, argv, "motor_board_sim");
  return docking_settings::runNode([] {
    ros::NodeHandle nh;
    ros::NodeHandle pnh("~");
    motor_board_firmware::MotorBoardSimNode node(nh, pnh);
    node.run();
  });
}
