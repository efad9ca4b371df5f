// planner: a thin node around DockingPlanner. Brings each FUSED target estimate into odom with tf2 at
// the estimate's stamp, feeds it and the odometry to the core on a ros::Timer (sim-time friendly),
// and publishes cmd_vel, DockingState, the planned path and diagnostics. Docking runs on command: the
// action server docking/dock (docking_msgs/Dock) starts it; until then, and after every end, the
// planner is IDLE with zero velocity. Settings: declared in settings/planner.yaml, overridden by
// config/planner.yaml (README.md's table); an invalid one parks the node, naming it.
#include <cmath>
#include <csignal>
#include <deque>
#include <map>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>

#include <actionlib/server/simple_action_server.h>
#include <actionlib_msgs/GoalID.h>
#include <diagnostic_msgs/DiagnosticArray.h>
#include <diagnostic_updater/diagnostic_updater.h>
#include <docking_msgs/DockAction.h>
#include <docking_msgs/DockingState.h>
#include <docking_msgs/PlannerGeometry.h>
#include <docking_msgs/TargetEstimate.h>
#include <docking_msgs/estimate_check_msg.h>
#include <docking_msgs/latency_window.h>
#include <docking_msgs/names.h>
#include <geometry_msgs/Twist.h>
#include <nav_msgs/Odometry.h>
#include <nav_msgs/Path.h>
#include <ros/ros.h>
#include <std_srvs/Empty.h>
#include <docking_settings/param_reader.h>
#include <docking_settings/ros_loader.h>
#include <docking_settings/run_node.h>
#include <tf2/utils.h>
#include <tf2_eigen/tf2_eigen.h>
#include <tf2_geometry_msgs/tf2_geometry_msgs.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>

#include "docking_planner/docking_planner.h"
#include "docking_planner/odometry_history.h"

namespace docking_planner {
namespace {

// The probe tip and the base frame are robot data: config/robot.yaml, loaded under ~robot by
// guidance.launch (one home).
constexpr char kRobotNamespace[] = "robot";
constexpr char kProbeTipKey[] = "robot/chaser/docking_probe_x_m";
constexpr char kBaseFrameKey[] = "robot/chaser/base_frame";
// The docking action's feedback (the current DockingState) rate, Hz.
constexpr double kFeedbackRateHz = 5.0;
// Constants of the node:
// An estimate up to this much newer than the newest odometry is placed by advancing that odometry along
// its twist, s: a little over two periods of the 50 Hz base, so an image never waits for the next one.
constexpr double kMaxOdomExtrapolationS = 0.05;
// An estimate the odometry history cannot place waits at most this long for tf at its stamp, s: 4
// cycles at 20 Hz, below input_timeout_s (0.3 s), after which the chaser stops anyway.
constexpr double kTfWaitS = 0.2;

/// The node's settings: the declared defaults with the parameter server's values (config/planner.yaml).
PlannerNodeSettings loadSettings(const ros::NodeHandle& pnh) {
  PlannerNodeSettings settings;
  docking_settings::loadSettings(pnh, settings);
  docking_settings::warnUnknownKeys(pnh, settings, {kRobotNamespace});
  docking_settings::ParamReader(pnh).validated([&] { validate(settings.core); });
  return settings;
}

/// The probe tip (robot data), checked against the law's geometry (inside the safe circle).
double loadProbeTip(const ros::NodeHandle& pnh, const ApproachConfig& law) {
  const docking_settings::ParamReader reader(pnh);
  const double probe_x_m = reader.require<double>(kProbeTipKey);
  reader.validated([&] { SafeCircleApproach(law, probe_x_m); });
  return probe_x_m;
}

/// The estimate's covariance rotated into odom, as the track's sigmas.
void takeMeasurementNoise(const docking_msgs::TargetEstimate& msg, const Eigen::Matrix3d& rot, TargetObservation* o) {
  // Rotate the camera-frame covariance into odom; the planner's filter takes one sigma for x and y
  // (the larger of the two, to stay on the safe side) and one for yaw. Variances of 1e6 and more
  // mean "not estimated" (TargetEstimate): the track's default is used then (sigma 0).
  Eigen::Matrix3d position_cov, rotation_cov;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) {
      position_cov(r, c) = msg.pose.covariance[static_cast<std::size_t>(r * 6 + c)];
      rotation_cov(r, c) = msg.pose.covariance[static_cast<std::size_t>((r + 3) * 6 + c + 3)];
    }
  }
  const Eigen::Matrix3d position_odom = rot * position_cov * rot.transpose();
  const Eigen::Matrix3d rotation_odom = rot * rotation_cov * rot.transpose();
  const double xy_var = std::max(position_odom(0, 0), position_odom(1, 1));
  const double yaw_var = rotation_odom(2, 2);
  if (std::isfinite(xy_var) && xy_var > 0.0 && xy_var < 1e5) o->position_sigma_m = std::sqrt(xy_var);
  if (std::isfinite(yaw_var) && yaw_var > 0.0 && yaw_var < 1e5) o->yaw_sigma_rad = std::sqrt(yaw_var);
}

volatile std::sig_atomic_t g_stop_requested = 0;
void onSigint(int) { g_stop_requested = 1; }

using DockServer = actionlib::SimpleActionServer<docking_msgs::DockAction>;

/// The docking action's goal and cancel topics as the action server subscribes them: the planner's
/// relay (PlannerNode::onGoalMessage, onCancelMessage) republishes each message there after checking
/// its goal id stamp. actionlib orders goals and cancels by that stamp, so one message stamped in the
/// future would make SimpleActionServer recall every later goal, or cancel every later goal on arrival
/// (issue 12). Feedback, status and result stay on the action's own topics.
constexpr const char kCheckedSuffix[] = "_checked";
ros::NodeHandle actionServerHandle(const ros::NodeHandle& nh) {
  const std::string action = std::string(docking_msgs::topics::kDockAction);
  const ros::M_string relayed = {
      {nh.resolveName(action + "/goal"), nh.resolveName(action + "/goal" + kCheckedSuffix)},
      {nh.resolveName(action + "/cancel"), nh.resolveName(action + "/cancel" + kCheckedSuffix)},
  };
  return ros::NodeHandle(nh, "", relayed);
}

using DockResultMsg = docking_msgs::DockResult;
static_assert(static_cast<int>(DockingOutcome::kDocked) == DockResultMsg::DOCKED &&
                  static_cast<int>(DockingOutcome::kCancelled) == DockResultMsg::CANCELLED &&
                  static_cast<int>(DockingOutcome::kTimeBudget) == DockResultMsg::TIME_BUDGET &&
                  static_cast<int>(DockingOutcome::kTargetLost) == DockResultMsg::TARGET_LOST &&
                  static_cast<int>(DockingOutcome::kClientGone) == DockResultMsg::CLIENT_GONE &&
                  static_cast<int>(DockingOutcome::kRejected) == DockResultMsg::REJECTED &&
                  static_cast<int>(DockingOutcome::kShutdown) == DockResultMsg::SHUTDOWN &&
                  static_cast<int>(DockingOutcome::kPerceptionLost) == DockResultMsg::PERCEPTION_LOST,
              "DockingOutcome is numbered as docking_msgs/DockResult");
static_assert(static_cast<int>(DockingPhase::kIdle) == docking_msgs::DockingState::IDLE,
              "DockingPhase is numbered as docking_msgs/DockingState");

class PlannerNode {
 public:
  PlannerNode(ros::NodeHandle& nh, ros::NodeHandle& pnh, const PlannerNodeSettings& settings)
      : planner_(settings.core, loadProbeTip(pnh, settings.core.law)),
        tf_listener_(tf_buffer_),
        diagnostics_(nh, pnh),
        dock_server_(actionServerHandle(nh), docking_msgs::topics::kDockAction, false) {
    takeNodeSettings(settings, pnh);
    advertiseOutputs(nh);
    subscribeInputs(nh);
    reset_service_ = pnh.advertiseService("reset", &PlannerNode::onReset, this);
    startDockServer(nh);
    diagnostics_.setHardwareID("none");
    diagnostics_.add("docking planner", this, &PlannerNode::diagnose);
    timer_ = nh.createTimer(ros::Duration(1.0 / settings.rate_hz), &PlannerNode::onTimer, this);
  }

  /// Zero velocity on the way out (the base would also stop on its own after its cmd_vel timeout), and
  /// the running goal, if any, ended.
  void shutdown() {
    endGoal(DockingOutcome::kShutdown, "the planner is shutting down");
    cmd_pub_.publish(geometry_msgs::Twist());
  }

 private:
  void takeNodeSettings(const PlannerNodeSettings& s, const ros::NodeHandle& pnh) {
    odom_frame_ = s.odom_frame;
    base_frame_ = docking_settings::ParamReader(pnh).require<std::string>(kBaseFrameKey);
    feedback_period_s_ = 1.0 / kFeedbackRateHz;
    client_loss_timeout_s_ = s.client_loss_timeout_s;
  }

  void advertiseOutputs(ros::NodeHandle& nh) {
    cmd_pub_ = nh.advertise<geometry_msgs::Twist>(docking_msgs::topics::kCmdVel, 1);
    state_pub_ = nh.advertise<docking_msgs::DockingState>(docking_msgs::topics::kDockingState, 10);
    path_pub_ = nh.advertise<nav_msgs::Path>(docking_msgs::topics::kDockingPath, 1, true);
    // For display only (docking_viz): filled and sent only while someone subscribes.
    geometry_pub_ = nh.advertise<docking_msgs::PlannerGeometry>(docking_msgs::topics::kDockingGeometry, 1);
  }

  void subscribeInputs(ros::NodeHandle& nh) {
    // TCP_NODELAY: small messages on the way to cmd_vel, not held back by Nagle's algorithm.
    estimate_sub_ = nh.subscribe(docking_msgs::topics::kTargetEstimate, 10, &PlannerNode::onEstimateEvent, this,
                                 ros::TransportHints().tcpNoDelay());
    odom_sub_ = nh.subscribe(docking_msgs::topics::kOdom, 10, &PlannerNode::onOdometryEvent, this,
                             ros::TransportHints().tcpNoDelay());
    // The cameras' own word on their sources, cited when perception is gone (diagnostic_updater publishes
    // on the absolute /diagnostics).
    diagnostics_sub_ = nh.subscribe("/diagnostics", 20, &PlannerNode::onDiagnostics, this);
  }

  void startDockServer(ros::NodeHandle& nh) {
    // The client's liveness: an action client subscribes to the server's feedback topic. roscpp shares
    // one publication per topic within a node, so this publisher's connect/disconnect callbacks see the
    // server's feedback subscribers by node name; a publisher notices a subscriber's connection closing
    // at once (a killed client included). The goal's sender comes from the goal topic's message events.
    feedback_watch_ = nh.advertise<docking_msgs::DockActionFeedback>(
        std::string(docking_msgs::topics::kDockAction) + "/feedback", 1,
        boost::bind(&PlannerNode::onFeedbackSubscriber, this, boost::placeholders::_1, +1),
        boost::bind(&PlannerNode::onFeedbackSubscriber, this, boost::placeholders::_1, -1));
    const std::string action = docking_msgs::topics::kDockAction;
    goal_relay_ = nh.advertise<docking_msgs::DockActionGoal>(action + "/goal" + kCheckedSuffix, 10);
    cancel_relay_ = nh.advertise<actionlib_msgs::GoalID>(action + "/cancel" + kCheckedSuffix, 10);
    goal_watch_ = nh.subscribe(action + "/goal", 10, &PlannerNode::onGoalMessage, this);
    cancel_watch_ = nh.subscribe(action + "/cancel", 10, &PlannerNode::onCancelMessage, this);
    dock_server_.registerGoalCallback(boost::bind(&PlannerNode::onGoal, this));
    dock_server_.registerPreemptCallback(boost::bind(&PlannerNode::onPreempt, this));
    dock_server_.start();
  }

  // IDLE with no target; a running docking ends as cancelled.
  bool onReset(std_srvs::Empty::Request&, std_srvs::Empty::Response&) {
    endGoal(DockingOutcome::kCancelled, "the planner was reset (~reset service)");
    pending_.clear();
    odometry_history_.clear();
    planner_.reset(ros::Time::now().toSec());
    ROS_INFO("planner: reset to IDLE, target forgotten");
    return true;
  }

  // ---- The docking action ----

  // A new goal; one running is preempted first (SimpleActionServer ends it as preempted on accept).
  void onGoal() {
    const double now = ros::Time::now().toSec();
    // Ended here, with our result: SimpleActionServer would otherwise end it with an empty one.
    if (dock_server_.isActive()) endGoal(DockingOutcome::kCancelled, "preempted by a new docking goal");
    const docking_msgs::DockGoalConstPtr goal = dock_server_.acceptNewGoal();
    if (!goal) return;  // cancelled before it could start
    DockingLimits limits;
    limits.time_budget_s = goal->time_budget_s;
    limits.search_timeout_s = goal->search_timeout_s;
    limits.max_speed_mps = goal->max_speed_mps;
    std::string why_not;
    if (!planner_.start(now, limits, &why_not)) {
      ROS_WARN("planner: docking goal rejected: %s", why_not.c_str());
      dock_server_.setAborted(makeResult(DockingOutcome::kRejected, why_not, now), why_not);
      return;
    }
    goal_started_s_ = now;
    last_feedback_s_ = -1e300;
    client_seen_s_ = now;
    // goal_watch_ subscribed before the server: roscpp queues one message's callbacks in subscription
    // order, so onGoalMessage has already seen this goal.
    goal_owner_ = last_goal_sender_;
    ROS_INFO("planner: docking started (time budget %.0f s, search timeout %.0f s, speed cap %.2f m/s; 0 = default)",
             limits.time_budget_s, limits.search_timeout_s, limits.max_speed_mps);
    runCycle();  // IDLE -> SEARCH published at once
  }

  void onFeedbackSubscriber(const ros::SingleSubscriberPublisher& link, int change) {
    const int count = (feedback_subscribers_[link.getSubscriberName()] += change);
    if (count <= 0) feedback_subscribers_.erase(link.getSubscriberName());
  }

  // The relay in front of the action server (actionServerHandle): a goal id stamped in the future is
  // restamped 0 ("received now", as actionlib reads 0), with a warning; everything else passes as it is.
  void onGoalMessage(const ros::MessageEvent<docking_msgs::DockActionGoal const>& event) {
    last_goal_sender_ = event.getPublisherName();
    docking_msgs::DockActionGoal goal = *event.getConstMessage();
    restampIfFuture(&goal.goal_id, "docking goal", event.getPublisherName());
    goal_relay_.publish(goal);
  }

  void onCancelMessage(const ros::MessageEvent<actionlib_msgs::GoalID const>& event) {
    actionlib_msgs::GoalID cancel = *event.getConstMessage();
    restampIfFuture(&cancel, "docking cancel", event.getPublisherName());
    cancel_relay_.publish(cancel);
  }

  void restampIfFuture(actionlib_msgs::GoalID* id, const char* what, const std::string& publisher) {
    const double ahead_s = id->stamp.toSec() - ros::Time::now().toSec();
    if (id->stamp.isZero() || ahead_s <= docking_msgs::checks::kStampLimits.max_future_s) return;
    ++restamped_ids_;
    last_restamped_ = std::string(what) + " '" + id->id + "' from " + publisher + ", stamped " +
                      std::to_string(ahead_s) + " s ahead";
    ROS_WARN_THROTTLE(2.0, "planner: %s '%s' from %s stamped %.3f s in the future: taken as received now", what,
                      id->id.c_str(), publisher.c_str(), ahead_s);
    id->stamp = ros::Time(0);
  }

  // Cancel from the client (a new goal is handled in onGoal).
  void onPreempt() {
    if (dock_server_.isNewGoalAvailable()) return;
    endGoal(DockingOutcome::kCancelled, "cancelled by the client");
  }

  docking_msgs::DockResult makeResult(DockingOutcome outcome, const std::string& reason, double now) const {
    docking_msgs::DockResult result;
    result.outcome = static_cast<std::uint8_t>(outcome);
    result.reason = reason;
    result.duration_s = now - goal_started_s_;
    result.final_state = last_state_msg_;
    return result;
  }

  // Ends the running goal (if any) with `outcome`; the planner goes IDLE and zero velocity goes out now.
  void endGoal(DockingOutcome outcome, const std::string& reason) {
    const double now = ros::Time::now().toSec();
    const bool was_active = planner_.active();
    planner_.cancel(now, reason);
    if (was_active) cmd_pub_.publish(geometry_msgs::Twist());
    if (!dock_server_.isActive()) return;
    const docking_msgs::DockResult result = makeResult(outcome, reason, now);
    if (outcome == DockingOutcome::kCancelled) {
      dock_server_.setPreempted(result, reason);
    } else {
      dock_server_.setAborted(result, reason);
    }
    ROS_INFO("planner: docking ended, %s: %s", outcomeName(outcome), reason.c_str());
  }

  // Reports the running goal: its end when the core ended the docking this cycle, otherwise feedback
  // at kFeedbackRateHz; and ends it when no client listens any more.
  void serveGoal(double now) {
    if (!dock_server_.isActive()) return;
    if (last_.outcome) {
      const docking_msgs::DockResult result = makeResult(*last_.outcome, last_.reason, now);
      if (*last_.outcome == DockingOutcome::kDocked) {
        dock_server_.setSucceeded(result, last_.reason);
      } else {
        dock_server_.setAborted(result, last_.reason);
      }
      ROS_INFO("planner: docking ended, %s: %s", outcomeName(*last_.outcome), last_.reason.c_str());
      return;
    }
    if (feedback_subscribers_.count(goal_owner_) > 0) client_seen_s_ = now;
    if (client_loss_timeout_s_ > 0.0 && now - client_seen_s_ > client_loss_timeout_s_) {
      endGoal(DockingOutcome::kClientGone, "the goal's client (" + goal_owner_ + ") is gone");
      return;
    }
    if (now - last_feedback_s_ >= feedback_period_s_) {
      docking_msgs::DockFeedback feedback;
      feedback.state = last_state_msg_;
      feedback.elapsed_s = now - goal_started_s_;
      dock_server_.publishFeedback(feedback);
      last_feedback_s_ = now;
    }
  }

  /// Keeps the camera statuses that are not OK (docking_msgs/names.h kCameraCapture); an OK one clears its
  /// camera's.
  void onDiagnostics(const diagnostic_msgs::DiagnosticArrayConstPtr& msg) {
    const std::string suffix = std::string(": ") + docking_msgs::diagnostics::kCameraCapture;
    for (const auto& status : msg->status) {
      const auto& name = status.name;
      if (name.size() < suffix.size() || name.compare(name.size() - suffix.size(), suffix.size(), suffix) != 0) continue;
      if (status.level == diagnostic_msgs::DiagnosticStatus::OK) {
        camera_faults_.erase(name);
      } else {
        camera_faults_[name] = CameraFault{"camera " + name.substr(0, name.size() - suffix.size()) + ": " +
                                               status.message,
                                           ros::Time::now().toSec()};
      }
    }
  }

  /// The camera faults reported within the last few seconds, joined (empty: none). A camera that stopped
  /// reporting is not cited: its process is gone or restarting (the respawned one reports afresh).
  std::string cameraFaults(double now_s) const {
    constexpr double kFreshS = 5.0;  // diagnostic_updater reports every second
    std::string text;
    for (const auto& [name, fault] : camera_faults_) {
      if (std::abs(now_s - fault.received_s) > kFreshS) continue;
      text += (text.empty() ? "" : "; ") + fault.text;
    }
    return text;
  }

  // Nothing a message contains may end the node: what the algorithm code throws drops that message,
  // with a diagnostic, and the node goes on.
  void onOdometryEvent(const ros::MessageEvent<nav_msgs::Odometry const>& event) {
    try {
      onOdometry(event.getConstMessage(), event.getPublisherName());
    } catch (const std::exception& e) {
      recordDrop("odometry", event.getPublisherName(), "exception", e.what());
    }
  }

  void onEstimateEvent(const ros::MessageEvent<docking_msgs::TargetEstimate const>& event) {
    try {
      onEstimate(event.getConstMessage(), event.getPublisherName());
    } catch (const std::exception& e) {
      recordDrop("estimate", event.getPublisherName(), "exception", e.what());
    }
  }

  /// Counts a dropped message by its code, keeps who sent it and why for the diagnostics, and warns
  /// (throttled). No other state changes.
  void recordDrop(const char* what, const std::string& publisher, const std::string& code, const std::string& why) {
    ++drops_by_code_[std::string(what) + ": " + code];
    last_drop_ = std::string(what) + " from " + publisher + ": " + code + " (" + why + ")";
    ROS_WARN_THROTTLE(2.0, "planner: dropped %s from %s: %s: %s", what, publisher.c_str(), code.c_str(), why.c_str());
  }

  /// A stamp outside [now - 5 s, now + 0.5 s] (kStampLimits; or not finite): the message is
  /// recorded as dropped and true is returned.
  bool stampRefused(const char* what, const std::string& publisher, double stamp_s, double now_s) {
    const auto stamp = docking_msgs::checks::checkStamp(stamp_s, now_s, docking_msgs::checks::kStampLimits);
    if (stamp == docking_msgs::checks::StampProblem::kNone) return false;
    recordDrop(what, publisher, docking_msgs::checks::stampProblemName(stamp),
               "stamp " + std::to_string(stamp_s - now_s) + " s from now");
    return true;
  }

  /// Sim time reset or a bag loop: the held stamps (target track, odometry history, waiting estimates)
  /// belong to the old timeline and would refuse every new message.
  void followClock(double now_s) {
    if (!clock_.jumpedBack(now_s)) return;
    ++clock_jumps_back_;
    pending_.clear();
    odometry_history_.clear();
    odometry_.reset();
    planner_.forgetTarget(now_s);
    ROS_WARN("planner: the clock jumped back to %.3f s: target, odometry history and waiting estimates forgotten",
             now_s);
  }

  void onOdometry(const nav_msgs::OdometryConstPtr& msg, const std::string& publisher) {
    const double now_s = ros::Time::now().toSec();
    followClock(now_s);
    // Before the history: one sample stamped in the future would make it refuse every true sample
    // after it, and huge numbers would place the target at absurd ranges (issue 12).
    const auto problem = docking_msgs::checks::checkOdometry(*msg);
    if (problem != docking_msgs::checks::OdometryProblem::kNone) {
      recordDrop("odometry", publisher, docking_msgs::checks::odometryProblemName(problem), "numbers refused");
      return;
    }
    if (stampRefused("odometry", publisher, msg->header.stamp.toSec(), now_s)) return;
    if (!msg->header.frame_id.empty() && msg->header.frame_id != odom_frame_) {
      ROS_WARN_THROTTLE(5.0, "planner: odometry in frame '%s', expected '%s'", msg->header.frame_id.c_str(),
                        odom_frame_.c_str());
    }
    ChaserOdometry o;
    o.stamp_s = msg->header.stamp.toSec();
    o.pose.x = msg->pose.pose.position.x;
    o.pose.y = msg->pose.pose.position.y;
    o.pose.yaw = tf2::getYaw(msg->pose.pose.orientation);
    o.twist.vx = msg->twist.twist.linear.x;  // nav_msgs/Odometry: twist in child_frame_id (base_link)
    o.twist.vy = msg->twist.twist.linear.y;
    o.twist.wz = msg->twist.twist.angular.z;
    odometry_ = o;
    if (!odometry_history_.add(OdometrySample{o.stamp_s, o.pose, o.twist})) {
      ROS_WARN_THROTTLE(5.0, "planner: odometry sample not kept (not finite, or stamp not after the last one)");
    }
    // An estimate that waited for odometry at its stamp can be placed now.
    if (!pending_.empty() && processPending()) runCycle(last_placed_stamp_);
  }

  void onEstimate(const docking_msgs::TargetEstimateConstPtr& msg, const std::string& publisher) {
    const double now_s = ros::Time::now().toSec();
    followClock(now_s);
    // Before the queue: a future stamp would wait there for tf forever and hold every later estimate
    // behind it (issue 12: SEARCH while 26 valid estimates arrived); a zero quaternion would steer.
    const auto problem = docking_msgs::checks::checkEstimate(*msg);
    if (problem != docking_msgs::checks::EstimateProblem::kNone) {
      recordDrop("estimate", publisher, docking_msgs::checks::estimateProblemName(problem), "numbers refused");
      return;
    }
    if (stampRefused("estimate", publisher, msg->header.stamp.toSec(), now_s)) return;
    // A well-formed message shows that the arbiter is alive; it also says whether the estimators are.
    planner_.notePerception(now_s, !msg->valid && msg->reject_reason == docking_msgs::TargetEstimate::REJECT_SOURCES_SILENT);
    if (msg->source != docking_msgs::TargetEstimate::SOURCE_FUSED) {
      ROS_WARN_ONCE("planner: estimates on %s are not SOURCE_FUSED; using them anyway",
                    docking_msgs::topics::kTargetEstimate);
    }
    pending_.push_back(msg);
    // A fresh estimate is acted on at once rather than at the next timer tick: that tick would add up
    // to one period to the image-to-cmd_vel latency.
    if (processPending()) runCycle(last_placed_stamp_);
  }

  // Estimates wait here until the camera can be placed in odom at their stamp (placeCamera), for at
  // most kTfWaitS. Returns true when a valid estimate was placed and given to the planner.
  bool processPending() {
    bool placed = false;
    while (!pending_.empty()) {
      const auto& msg = pending_.front();
      if (!msg->valid) {
        TargetObservation o;
        o.stamp_s = msg->header.stamp.toSec();
        o.valid = false;
        o.status = msg->status;
        planner_.addObservation(o);
        pending_.pop_front();
        continue;
      }
      Eigen::Isometry3d odom_from_camera;
      const Placement placement = placeCamera(*msg, &odom_from_camera);
      if (placement == Placement::kWait) return placed;  // retry with the next odometry or tick
      if (placement == Placement::kFailed) {
        ++tf_failures_;
        ROS_WARN_THROTTLE(2.0, "planner: dropped an estimate: cannot place %s in %s at its stamp: %s",
                          msg->header.frame_id.c_str(), odom_frame_.c_str(), last_tf_error_.c_str());
        pending_.pop_front();
        continue;
      }
      const TrackUpdate result = planner_.addObservation(toObservation(*msg, odom_from_camera));
      if (!result.accepted) ROS_DEBUG("planner: estimate not used: %s", result.reason.c_str());
      placed = true;  // acted on at once even when not used (an outlier, near contact): the planner has decided
      last_placed_stamp_ = msg->header.stamp;
      pending_.pop_front();
    }
    return placed;
  }

  enum class Placement { kPlaced, kWait, kFailed };

  // The camera in odom at the estimate's stamp: base_link from the odometry history (interpolated, or
  // advanced along the newest twist by at most kMaxOdomExtrapolationS: no wait for the next odometry
  // message) times the camera's mount on base_link (static, from tf). Falls back to tf at the stamp
  // for stamps older than the history. kWait while the stamp is too new for both, up to kTfWaitS.
  Placement placeCamera(const docking_msgs::TargetEstimate& msg, Eigen::Isometry3d* odom_from_camera) {
    const double stamp = msg.header.stamp.toSec();
    const std::optional<Pose2D> base = odometry_history_.poseAt(stamp, kMaxOdomExtrapolationS);
    if (base) {
      std::string error;
      const std::optional<Eigen::Isometry3d> mount = cameraMount(msg.header.frame_id, &error);
      if (mount) {
        Eigen::Isometry3d odom_from_base = Eigen::Isometry3d::Identity();
        odom_from_base.translation() << base->x, base->y, 0.0;
        odom_from_base.linear() = Eigen::AngleAxisd(base->yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
        *odom_from_camera = odom_from_base * *mount;
        ++placed_from_odometry_;
        return Placement::kPlaced;
      }
      last_tf_error_ = error;
    }
    std::string error;
    if (tf_buffer_.canTransform(odom_frame_, msg.header.frame_id, msg.header.stamp, &error)) {
      try {
        *odom_from_camera =
            tf2::transformToEigen(tf_buffer_.lookupTransform(odom_frame_, msg.header.frame_id, msg.header.stamp));
        return Placement::kPlaced;
      } catch (const tf2::TransformException& e) {
        last_tf_error_ = e.what();
        return Placement::kFailed;
      }
    }
    if ((ros::Time::now() - msg.header.stamp).toSec() <= kTfWaitS) return Placement::kWait;
    last_tf_error_ = error;
    return Placement::kFailed;
  }

  // base_link <- camera: a fixed mount (robot.yaml's static transforms), looked up once per frame.
  std::optional<Eigen::Isometry3d> cameraMount(const std::string& camera_frame, std::string* error) {
    const auto known = camera_mounts_.find(camera_frame);
    if (known != camera_mounts_.end()) return known->second;
    try {
      const Eigen::Isometry3d mount =
          tf2::transformToEigen(tf_buffer_.lookupTransform(base_frame_, camera_frame, ros::Time(0)));
      camera_mounts_.emplace(camera_frame, mount);
      return mount;
    } catch (const tf2::TransformException& e) {
      *error = e.what();
      return std::nullopt;
    }
  }

  TargetObservation toObservation(const docking_msgs::TargetEstimate& msg, const Eigen::Isometry3d& odom_from_camera) {
    TargetObservation o;
    o.stamp_s = msg.header.stamp.toSec();
    o.valid = msg.valid && msg.position_valid;
    o.status = msg.position_valid ? msg.status : "no position";
    o.source = msg.selected_source;
    const auto& p = msg.pose.pose.position;
    o.range_m = Eigen::Vector3d(p.x, p.y, p.z).norm();
    const Eigen::Vector3d position = odom_from_camera * Eigen::Vector3d(p.x, p.y, p.z);
    o.pose.x = position.x();
    o.pose.y = position.y();
    o.orientation_valid = msg.orientation_valid;
    if (msg.orientation_valid) {
      const auto& q = msg.pose.pose.orientation;
      // The port axis is target x; its direction in the odom plane is the port's yaw.
      const Eigen::Vector3d axis =
          odom_from_camera.rotation() * (Eigen::Quaterniond(q.w, q.x, q.y, q.z).normalized() * Eigen::Vector3d::UnitX());
      o.pose.yaw = std::atan2(axis.y(), axis.x());
    }
    takeMeasurementNoise(msg, odom_from_camera.rotation(), &o);
    return o;
  }

  void onTimer(const ros::TimerEvent&) {
    try {
      followClock(ros::Time::now().toSec());
      const bool placed = processPending();
      runCycle(placed ? last_placed_stamp_ : ros::Time());
    } catch (const std::exception& e) {
      ROS_ERROR_THROTTLE(5.0, "planner: cycle failed: %s; zero velocity", e.what());
      cmd_pub_.publish(geometry_msgs::Twist());
    }
  }

  // One planning step and its cmd_vel. `image_stamp`: the stamp of the estimate this step acts on (its
  // image's), for the image -> cmd_vel latency; zero for a step of the timer alone.
  void runCycle(const ros::Time& image_stamp = ros::Time()) {
    const ros::Time now = ros::Time::now();
    planner_.setInputProblem(cameraFaults(now.toSec()));
    last_ = planner_.update(now.toSec(), odometry_);

    geometry_msgs::Twist cmd;
    cmd.linear.x = last_.command.vx;
    cmd.linear.y = last_.command.vy;
    cmd.angular.z = last_.command.wz;
    cmd_pub_.publish(cmd);
    if (!image_stamp.isZero()) latency_.add((ros::Time::now() - image_stamp).toSec());

    docking_msgs::DockingState state;
    state.header.stamp = now;
    state.header.frame_id = base_frame_;
    state.state = static_cast<std::uint8_t>(last_.state);
    state.state_name = stateName(last_.state);
    state.reason = last_.reason;
    state.time_in_state_s = last_.time_in_state_s;
    state.estimate_source = last_.estimate_source;
    state.target_visible = last_.target_visible;
    const double unknown = std::numeric_limits<double>::quiet_NaN();  // no target pose held
    state.range_m = last_.has_target ? last_.geometry.range_m : unknown;
    state.goal_distance_m = last_.has_target ? last_.goal_distance_m : unknown;
    // Against the port axis: unknown while only the port's position is held (the law then takes the line
    // of sight as the axis, and these would read as a perfect zero).
    const bool axis_known = last_.has_target && last_.port_orientation_known;
    state.lateral_error_m = axis_known ? last_.geometry.lateral_m : unknown;
    state.axial_distance_m = axis_known ? last_.geometry.axial_m : unknown;
    state.yaw_error_rad = axis_known ? last_.geometry.yaw_error_rad : unknown;
    state.bearing_rad = last_.has_target ? last_.geometry.bearing_rad : unknown;
    state_pub_.publish(state);
    last_state_msg_ = state;
    serveGoal(now.toSec());

    if (last_.state != last_state_) {
      ROS_INFO("planner: %s -> %s: %s", stateName(last_state_), stateName(last_.state), last_.reason.c_str());
      last_state_ = last_.state;
    }

    nav_msgs::Path path;
    path.header.stamp = now;
    path.header.frame_id = odom_frame_;
    for (const Pose2D& p : last_.path) {
      geometry_msgs::PoseStamped ps;
      ps.header = path.header;
      ps.pose.position.x = p.x;
      ps.pose.position.y = p.y;
      ps.pose.orientation.z = std::sin(p.yaw / 2.0);
      ps.pose.orientation.w = std::cos(p.yaw / 2.0);
      path.poses.push_back(ps);
    }
    path_pub_.publish(path);
    if (geometry_pub_.getNumSubscribers() > 0) publishGeometry(now);
    diagnostics_.update();
  }

  /// The held port and the current goal in odom (docking_msgs/PlannerGeometry), for display.
  void publishGeometry(const ros::Time& now) {
    docking_msgs::PlannerGeometry geometry;
    geometry.header.stamp = now;
    geometry.header.frame_id = odom_frame_;
    geometry.has_port = last_.port.has_value();
    if (last_.port) {
      geometry.port.x = last_.port->pose.x;
      geometry.port.y = last_.port->pose.y;
      geometry.port.theta = last_.port->pose.yaw;
      geometry.port_orientation_known = last_.port_orientation_known;
    }
    geometry.has_goal = last_.goal.has_value();
    if (last_.goal) {
      geometry.goal.x = last_.goal->x;
      geometry.goal.y = last_.goal->y;
      geometry.goal.theta = last_.goal->yaw;
    }
    geometry_pub_.publish(geometry);
  }

  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& stat) {
    using diagnostic_msgs::DiagnosticStatus;
    const bool failing = last_.state == DockingPhase::kHold || last_.state == DockingPhase::kAbort;
    const std::string perception_problem = planner_.perceptionProblem(ros::Time::now().toSec());
    stat.add("docking goal active", dock_server_.isActive());
    if (!perception_problem.empty() && dock_server_.isActive()) {
      stat.summaryf(DiagnosticStatus::ERROR, "%s: %s", stateName(last_.state), perception_problem.c_str());
    } else {
      stat.summaryf(failing ? DiagnosticStatus::WARN : DiagnosticStatus::OK, "%s: %s", stateName(last_.state),
                    last_.reason.c_str());
    }
    stat.add("perception", perception_problem.empty() ? std::string("alive") : perception_problem);
    stat.add("state", stateName(last_.state));
    stat.add("time in state (s)", last_.time_in_state_s);
    stat.add("target visible", last_.target_visible);
    stat.add("on odometry", last_.on_odometry);
    if (last_.has_target) {
      stat.add("range (m)", last_.geometry.range_m);
      stat.add("lateral error (m)", last_.geometry.lateral_m);
      stat.add("yaw error (rad)", last_.geometry.yaw_error_rad);
      stat.add("probe tip error (m)", last_.geometry.tip_error_m);
    }
    stat.add("estimates dropped (no tf)", tf_failures_);
    stat.add("estimates placed from the odometry history", placed_from_odometry_);
    if (tf_failures_ > 0) stat.add("last tf error", last_tf_error_);
    stat.add("clock jumps back (target forgotten)", clock_jumps_back_);
    for (const auto& [code, count] : drops_by_code_) stat.add("dropped: " + code, count);
    if (!last_drop_.empty()) stat.add("last dropped", last_drop_);
    stat.add("goal ids stamped in the future (taken as received now)", restamped_ids_);
    if (!last_restamped_.empty()) stat.add("last restamped goal id", last_restamped_);
    docking_msgs::addLatency(stat, "image->cmd_vel", latency_);
  }

  DockingPlanner planner_;
  std::string odom_frame_, base_frame_;
  tf2_ros::Buffer tf_buffer_;
  tf2_ros::TransformListener tf_listener_;
  diagnostic_updater::Updater diagnostics_;
  ros::Publisher cmd_pub_, state_pub_, path_pub_, geometry_pub_;
  ros::Subscriber estimate_sub_, odom_sub_, diagnostics_sub_;
  struct CameraFault {
    std::string text;      ///< "<status name>: <message>"
    double received_s{0};  ///< ROS time of its last report
  };
  std::map<std::string, CameraFault> camera_faults_;  ///< by status name: cameras whose last word was not OK
  ros::ServiceServer reset_service_;
  ros::Timer timer_;
  DockServer dock_server_;
  ros::Publisher feedback_watch_;
  ros::Subscriber goal_watch_, cancel_watch_;
  ros::Publisher goal_relay_, cancel_relay_;
  std::map<std::string, int> feedback_subscribers_;  // node name -> connections to the feedback topic
  std::string last_goal_sender_, goal_owner_;
  double feedback_period_s_{0.2};
  double client_loss_timeout_s_{1.0};
  double goal_started_s_{0.0};
  double last_feedback_s_{-1e300};
  double client_seen_s_{0.0};
  docking_msgs::DockingState last_state_msg_;
  std::optional<ChaserOdometry> odometry_;
  OdometryHistory odometry_history_;
  std::map<std::string, Eigen::Isometry3d> camera_mounts_;
  std::uint64_t placed_from_odometry_{0};
  std::deque<docking_msgs::TargetEstimateConstPtr> pending_;
  ros::Time last_placed_stamp_;            ///< stamp of the newest estimate processPending() placed
  docking_msgs::LatencyWindow latency_;    ///< image stamp -> the cmd_vel acting on it
  PlannerOutput last_;
  DockingPhase last_state_{DockingPhase::kIdle};
  std::uint64_t tf_failures_{0};
  std::string last_tf_error_;
  docking_msgs::checks::ClockJumpDetector clock_;
  std::uint64_t clock_jumps_back_{0};
  std::map<std::string, std::uint64_t> drops_by_code_;  ///< dropped messages by problem code
  std::string last_drop_;                               ///< publisher, code and reason
  std::uint64_t restamped_ids_{0};                      ///< goal/cancel ids stamped in the future
  std::string last_restamped_;
};

}  // namespace
}  // namespace docking_planner

int main(int argc, char** argv) {
  // Own SIGINT handling, so that a last zero cmd_vel goes out before the node shuts down.
  ros::init(argc, argv, "planner", ros::init_options::NoSigintHandler);
  std::signal(SIGINT, docking_planner::onSigint);
  const int exit_code = docking_settings::runNode([] {
    ros::NodeHandle nh;
    ros::NodeHandle pnh("~");
    docking_planner::PlannerNode node(nh, pnh, docking_planner::loadSettings(pnh));
    while (ros::ok() && !docking_planner::g_stop_requested) {
      ros::spinOnce();
      ros::WallDuration(0.002).sleep();
    }
    node.shutdown();
    ros::WallDuration(0.1).sleep();  // let the zero command and the goal's end leave
  });
  ros::shutdown();
  return exit_code;
}
