// dock_abort: `rosrun docking_planner dock abort` runs this (the Python client execs it first thing): it
// cancels every docking goal and waits until the planner reports no goal running and IDLE (zero velocity).
// In C++ because an abort must be quick to start: a Python client spent most of its seconds on a busy
// machine importing rospy and registering before the cancel left.
//
//   dock_abort [--server-timeout S] [--confirm-timeout S]
// Exit status 0 confirmed; 2 no /clock under use_sim_time; 3 not sent or not confirmed (loudly: use the
// e-stop). Every wait is on the wall clock (under simulated time ROS time is 0 before /clock).
#include <actionlib_msgs/GoalID.h>
#include <actionlib_msgs/GoalStatusArray.h>
#include <docking_msgs/DockingState.h>
#include <docking_msgs/names.h>
#include <ros/ros.h>

#include <cstdio>
#include <cstdlib>
#include <mutex>
#include <set>
#include <string>
#include <thread>

namespace {

constexpr char kEStopHint[] = "stop the robot with the e-stop: rostopic pub -1 /e_stop std_msgs/Bool true";
constexpr double kResendPeriodS = 0.5;  // a cancel on a connection just made can be lost: sent again until confirmed

struct Options {
  double server_timeout_s = 10.0;  // 0: wait for ever
  double confirm_timeout_s = 5.0;
};

Options parseOptions(int argc, char** argv) {
  Options o;
  for (int i = 1; i + 1 < argc; ++i) {
    const std::string name = argv[i];
    if (name == "--server-timeout") o.server_timeout_s = std::atof(argv[++i]);
    else if (name == "--confirm-timeout") o.confirm_timeout_s = std::atof(argv[++i]);
  }
  return o;
}

double wallNow() { return ros::WallTime::now().toSec(); }

/// The planner's goal statuses and state as they arrive, and who listens to the cancel.
class PlannerWatch {
 public:
  void onStatus(const ros::MessageEvent<actionlib_msgs::GoalStatusArray const>& event) {
    std::lock_guard<std::mutex> lock(mutex_);
    server_ = event.getPublisherName();
    running_.clear();
    for (const auto& s : event.getMessage()->status_list) {
      if (s.status == s.PENDING || s.status == s.ACTIVE || s.status == s.PREEMPTING || s.status == s.RECALLING) {
        running_.insert(s.goal_id.id);
      }
    }
    status_wall_ = wallNow();
  }
  void onState(const docking_msgs::DockingState::ConstPtr& msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    idle_ = msg->state == docking_msgs::DockingState::IDLE;
    state_ = msg->state;
    state_wall_ = wallNow();
  }
  void onCancelSubscriber(const ros::SingleSubscriberPublisher& sub, bool connected) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (connected) cancel_subscribers_.insert(sub.getSubscriberName());
    else cancel_subscribers_.erase(sub.getSubscriberName());
  }
  /// The action server (the status's publisher) has connected to our cancel topic.
  bool connected() {
    std::lock_guard<std::mutex> lock(mutex_);
    return !server_.empty() && cancel_subscribers_.count(server_) > 0;
  }
  /// Both heard after `wall`: no goal running and the planner IDLE.
  bool idleSince(double wall) {
    std::lock_guard<std::mutex> lock(mutex_);
    return status_wall_ > wall && state_wall_ > wall && idle_ && running_.empty();
  }
  std::set<std::string> running() {
    std::lock_guard<std::mutex> lock(mutex_);
    return running_;
  }
  int state() {
    std::lock_guard<std::mutex> lock(mutex_);
    return state_;
  }

 private:
  std::mutex mutex_;
  std::string server_;
  std::set<std::string> cancel_subscribers_;
  std::set<std::string> running_;
  bool idle_ = false;
  int state_ = -1;
  double status_wall_ = 0.0;
  double state_wall_ = 0.0;
};

/// Waits (wall clock) until `condition` or `deadline_wall` (0: none); returns condition().
template <typename Condition>
bool waitUntil(Condition condition, double deadline_wall) {
  while (!condition()) {
    if (!ros::ok() || (deadline_wall > 0.0 && wallNow() >= deadline_wall)) return condition();
    ros::WallDuration(0.005).sleep();
  }
  return true;
}

std::string joined(const std::set<std::string>& ids) {
  std::string out;
  for (const auto& id : ids) out += (out.empty() ? "" : ", ") + id;
  return out.empty() ? "none" : out;
}

int abortDocking(const Options& o) {
  const double deadline = o.server_timeout_s > 0.0 ? wallNow() + o.server_timeout_s : 0.0;
  ros::NodeHandle nh;
  bool sim_time = false;
  nh.param("/use_sim_time", sim_time, false);
  if (sim_time && !waitUntil([] { return !ros::Time::now().isZero(); }, deadline)) {
    std::fprintf(stderr, "dock: no /clock within the wait (use_sim_time is set: is the simulator or the replay running?)\n");
    return 2;
  }
  PlannerWatch planner;
  const std::string action = docking_msgs::topics::kDockAction;
  ros::Publisher cancel = nh.advertise<actionlib_msgs::GoalID>(
      action + "/cancel", 10, [&](const ros::SingleSubscriberPublisher& s) { planner.onCancelSubscriber(s, true); },
      [&](const ros::SingleSubscriberPublisher& s) { planner.onCancelSubscriber(s, false); });
  ros::Subscriber status = nh.subscribe<actionlib_msgs::GoalStatusArray>(
      action + "/status", 10, boost::function<void(const ros::MessageEvent<actionlib_msgs::GoalStatusArray const>&)>(
                                  [&](const auto& event) { planner.onStatus(event); }));
  ros::Subscriber state = nh.subscribe<docking_msgs::DockingState>(
      docking_msgs::topics::kDockingState, 10, [&](const docking_msgs::DockingState::ConstPtr& m) { planner.onState(m); });
  if (!waitUntil([&] { return planner.connected(); }, deadline)) {
    std::fprintf(stderr, "dock: ABORT NOT SENT: no docking action server on %s within %.0f s of wall time; %s\n",
                 ros::names::resolve(action).c_str(), o.server_timeout_s, kEStopHint);
    return 3;
  }
  const std::set<std::string> running = planner.running();
  const double sent = wallNow();
  const double confirm_deadline = sent + o.confirm_timeout_s;
  bool confirmed = false;
  while (!confirmed && wallNow() < confirm_deadline && ros::ok()) {
    cancel.publish(actionlib_msgs::GoalID());  // an empty id, stamp 0: every goal
    confirmed = waitUntil([&] { return planner.idleSince(sent); }, std::min(wallNow() + kResendPeriodS, confirm_deadline));
  }
  if (!confirmed) {
    std::fprintf(stderr, "dock: ABORT NOT CONFIRMED: within %.0f s the planner did not report IDLE with no goal "
                 "running (last state: %d; goals running: %s); %s\n", o.confirm_timeout_s, planner.state(),
                 joined(planner.running()).c_str(), kEStopHint);
    return 3;
  }
  if (running.empty()) {
    std::printf("dock: ABORTED: no docking was running; the planner is IDLE (zero velocity)\n");
  } else {
    std::printf("dock: ABORTED: docking goal %s cancelled; the planner is IDLE (zero velocity), confirmed after "
                "%.2f s\n", joined(running).c_str(), wallNow() - sent);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  ros::init(argc, argv, "dock_abort", ros::init_options::AnonymousName | ros::init_options::NoRosout);
  const Options options = parseOptions(argc, argv);
  // An abort must end, and say so, whatever blocks below it (a master gone while it ran).
  const double limit_s = options.server_timeout_s > 0.0 ? options.server_timeout_s + options.confirm_timeout_s + 5.0 : 0.0;
  if (limit_s > 0.0) {
    std::thread([limit_s] {
      std::this_thread::sleep_for(std::chrono::duration<double>(limit_s));
      std::fprintf(stderr, "dock: ABORT NOT CONFIRMED: the client did not finish within %.0f s; %s\n", limit_s, kEStopHint);
      std::fflush(stderr);
      std::_Exit(3);
    }).detach();
  }
  if (!ros::master::check()) {
    const double deadline = options.server_timeout_s > 0.0 ? wallNow() + options.server_timeout_s : 0.0;
    while (!ros::master::check()) {
      if (deadline > 0.0 && wallNow() >= deadline) {
        std::fprintf(stderr, "dock: ABORT NOT SENT: no ROS master at %s within %.0f s of wall time\n",
                     ros::master::getURI().c_str(), options.server_timeout_s);
        return 3;
      }
      ros::WallDuration(0.1).sleep();
    }
  }
  ros::AsyncSpinner spinner(1);
  spinner.start();
  const int code = abortDocking(options);
  std::fflush(stdout);
  return code;
}
