// markers: a thin node that draws what the docking stack believes, for rviz. It keeps the latest
// estimate of each source, the fused one, the planner's state, geometry and command, and publishes them
// as one visualization_msgs/MarkerArray at a fixed rate, but only while the marker topic has a
// subscriber: with none, it subscribes to nothing and does no work. The shapes come from the ROS-free
// core (docking_viz_core); geometry that is not finite is never published (skipped and counted).
// Settings: settings/markers.yaml, overridden by config/markers.yaml (~); the radii are the planner's
// settings, read from its namespace. README.md lists both.
#include <cmath>
#include <cstdint>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "docking_settings/param_reader.h"
#include "docking_settings/ros_loader.h"
#include "docking_planner/planner_settings.h"
#include "docking_settings/run_node.h"
#include <docking_msgs/DockingState.h>
#include <docking_msgs/PlannerGeometry.h>
#include <docking_msgs/TargetEstimate.h>
#include <docking_msgs/estimate_check_msg.h>
#include <docking_msgs/names.h>
#include <geometry_msgs/Twist.h>
#include <ros/ros.h>
#include <visualization_msgs/MarkerArray.h>

#include "docking_viz/covariance_ellipsoid.h"
#include "docking_viz/marker_config.h"
#include "docking_viz/palette.h"
#include "docking_viz/planner_drawing.h"
#include "docking_viz/state_label.h"
#include "docking_viz/target_mockup.h"

namespace docking_viz {
namespace {

using docking_msgs::TargetEstimate;
using visualization_msgs::Marker;

static_assert(static_cast<std::uint8_t>(EstimateSource::kDisparity) == TargetEstimate::SOURCE_DISPARITY &&
                  static_cast<std::uint8_t>(EstimateSource::kMonoVisible) == TargetEstimate::SOURCE_MONO_VISIBLE &&
                  static_cast<std::uint8_t>(EstimateSource::kMonoIr) == TargetEstimate::SOURCE_MONO_IR &&
                  static_cast<std::uint8_t>(EstimateSource::kFused) == TargetEstimate::SOURCE_FUSED,
              "EstimateSource must be numbered as TargetEstimate's SOURCE_* constants");

// Estimates: the source the arbiter uses now stands out; the fused estimate overlaps it, so it is faint.
constexpr double kInUseAlpha = 0.75;
constexpr double kNotInUseAlpha = 0.25;
constexpr double kFusedEllipsoidAlpha = 0.15;
constexpr double kEstimateDotDiameterM = 0.03;
constexpr double kArrowShaftDiameterM = 0.015;
constexpr double kArrowHeadDiameterM = 0.03;
constexpr double kArrowHeadLengthM = 0.04;
constexpr double kLineWidthM = 0.01;
constexpr double kGoalArrowLengthM = 0.2;
// The planner's shapes lie in its odom plane; lifted a little so that the grid does not hide them.
constexpr double kPlannerDrawingZM = 0.01;
// Below this speed the command arrow has no direction worth drawing.
constexpr double kMinDrawnSpeedMps = 1e-3;

// Marker ids within a namespace.
enum EstimateMarkerId { kEstimateDot = 0, kEstimateEllipsoid = 1, kEstimateAxis = 2 };
enum PlannerMarkerId { kSafeCircle = 0, kSearchOrbit = 1, kPortAxis = 2, kGoal = 3 };
constexpr char kPlannerNamespace[] = "planner";
constexpr char kMockupNamespace[] = "target_mockup";
// The target's URDF, as launch/description.launch loads it (docking_description's make_urdf.py target).
constexpr char kTargetDescriptionParam[] = "target_description";
constexpr char kCommandNamespace[] = "cmd_vel";
constexpr char kStateNamespace[] = "state";
std::string estimateNamespace(std::uint8_t source) { return std::string("estimate/") + sourceStyle(source).key; }

/// The node's settings: the declared defaults with the parameter server's values (config/markers.yaml).
MarkerConfig loadConfig(const ros::NodeHandle& pnh) {
  MarkerConfig c;
  docking_settings::loadSettings(pnh, c);
  docking_settings::warnUnknownKeys(pnh, c);
  docking_settings::ParamReader(pnh).validated([&] { validate(c); });
  return c;
}

/// The planner's own radii, read with the planner's declaration from its namespace (its defaults and
/// config/planner.yaml's overrides, as the planner loads them): no copy.
PlannerRadii loadPlannerRadii(const ros::NodeHandle& planner_nh) {
  docking_planner::PlannerNodeSettings planner;
  docking_settings::loadSettings(planner_nh, planner);
  PlannerRadii radii;
  radii.safe_radius_m = planner.core.law.safe_radius_m;
  radii.search_orbit_radius_m = planner.core.search_orbit_radius_m;
  docking_settings::ParamReader(planner_nh).validated([&] { validate(radii); });
  return radii;
}

std_msgs::ColorRGBA toColour(const Rgba& rgba, double alpha) {
  std_msgs::ColorRGBA c;
  c.r = rgba.r;
  c.g = rgba.g;
  c.b = rgba.b;
  c.a = static_cast<float>(alpha);
  return c;
}

geometry_msgs::Point toPoint(double x, double y, double z) {
  geometry_msgs::Point p;
  p.x = x;
  p.y = y;
  p.z = z;
  return p;
}

geometry_msgs::Quaternion yawQuaternion(double yaw) {
  geometry_msgs::Quaternion q;
  q.z = std::sin(yaw / 2.0);
  q.w = std::cos(yaw / 2.0);
  return q;
}

/// A latest message and when it arrived (ROS time: it ages on the simulated or replayed clock).
template <typename Msg>
struct Latest {
  std::optional<Msg> message;
  ros::Time received;
  /// Received within timeout_s; not after a jump of the clock back (sim time reset, bag loop).
  bool fresh(const ros::Time& now, double timeout_s) const {
    const double age_s = (now - received).toSec();
    return message && age_s >= 0.0 && age_s <= timeout_s;
  }
};

class MarkersNode {
 public:
  MarkersNode(ros::NodeHandle nh, ros::NodeHandle pnh)
      : nh_(nh),
        config_(loadConfig(pnh)),
        radii_(loadPlannerRadii(ros::NodeHandle(nh, config_.planner_namespace))),
        mockup_(loadMockup(nh)) {
    const ros::SubscriberStatusCallback on_change = [this](const ros::SingleSubscriberPublisher&) {
      updateSubscriptions();
    };
    markers_pub_ = nh_.advertise<visualization_msgs::MarkerArray>(docking_msgs::topics::kDockingMarkers, 1,
                                                                   on_change, on_change);
    timer_ = nh_.createTimer(ros::Duration(1.0 / config_.publish_rate_hz), &MarkersNode::onTimer, this,
                             false, /*autostart=*/false);
    ROS_INFO("markers: safe circle %.2f m and search orbit %.2f m from '%s'; publishing %s while subscribed",
             radii_.safe_radius_m, radii_.search_orbit_radius_m,
             ros::NodeHandle(nh, config_.planner_namespace).getNamespace().c_str(),
             nh_.resolveName(docking_msgs::topics::kDockingMarkers).c_str());
  }

 private:
  /// Lazy: inputs and the timer run only while the marker topic has a subscriber.
  void updateSubscriptions() {
    const bool wanted = markers_pub_.getNumSubscribers() > 0;
    if (wanted == !subscribers_.empty()) return;
    if (!wanted) {
      subscribers_.clear();  // each ros::Subscriber unsubscribes when destroyed
      timer_.stop();
      estimates_.clear();
      state_ = {};
      ended_state_memory_ = {};
      geometry_ = {};
      command_ = {};
      return;
    }
    namespace topics = docking_msgs::topics;
    for (const char* topic : {topics::kDisparityEstimate, topics::kMonoVisibleEstimate, topics::kMonoIrEstimate,
                              topics::kTargetEstimate}) {
      subscribers_.push_back(nh_.subscribe(topic, 1, &MarkersNode::onEstimate, this));
    }
    subscribers_.push_back(nh_.subscribe(topics::kDockingState, 1, &MarkersNode::onState, this));
    subscribers_.push_back(nh_.subscribe(topics::kDockingGeometry, 1, &MarkersNode::onGeometry, this));
    subscribers_.push_back(nh_.subscribe(topics::kCmdVel, 1, &MarkersNode::onCommand, this));
    timer_.start();
  }

  // Keyed by the message's own source, so one callback serves the four estimate topics.
  void onEstimate(const docking_msgs::TargetEstimateConstPtr& msg) {
    Latest<TargetEstimate>& latest = estimates_[msg->source];
    latest.message = *msg;
    latest.received = ros::Time::now();
  }
  void onState(const docking_msgs::DockingStateConstPtr& msg) {
    store(&state_, *msg);
    ended_state_memory_.update(msg->state == docking_msgs::DockingState::IDLE, msg->state_name);
  }
  void onGeometry(const docking_msgs::PlannerGeometryConstPtr& msg) { store(&geometry_, *msg); }
  void onCommand(const geometry_msgs::TwistConstPtr& msg) { store(&command_, *msg); }
  template <typename Msg>
  static void store(Latest<Msg>* latest, const Msg& msg) {
    latest->message = msg;
    latest->received = ros::Time::now();
  }

  void onTimer(const ros::TimerEvent&) {
    const ros::Time now = ros::Time::now();
    visualization_msgs::MarkerArray array;
    addEstimates(now, &array);
    addMockup(now, &array);
    addPlanner(now, &array);
    addCommand(now, &array);
    addLabel(now, &array);
    markers_pub_.publish(array);
    if (skipped_total_ != reported_skipped_) {
      ROS_WARN_THROTTLE(10.0, "markers: invalid geometry not drawn (count of marker arrays): %s", skippedSummary().c_str());
      reported_skipped_ = skipped_total_;
    }
  }

  std::string skippedSummary() const {
    std::string summary;
    for (const auto& [what, count] : skipped_by_reason_) {
      summary += (summary.empty() ? "" : "; ") + what + " x" + std::to_string(count);
    }
    return summary;
  }

  // --- Markers: every slot is either drawn (ADD) or removed (DELETE) in every array, so nothing stale stays.

  Marker slot(const std::string& ns, int id, const std::string& frame_id, const ros::Time& stamp) const {
    Marker m;
    m.header.frame_id = frame_id;
    m.header.stamp = stamp;
    m.ns = ns;
    m.id = id;
    m.action = Marker::ADD;
    m.lifetime = ros::Duration(config_.marker_lifetime_s);
    m.pose.orientation.w = 1.0;
    return m;
  }
  static Marker deletion(const std::string& ns, int id) {
    Marker m;
    m.ns = ns;
    m.id = id;
    m.action = Marker::DELETE;
    return m;
  }
  void skip(const std::string& what) {
    ++skipped_total_;
    ++skipped_by_reason_[what];
  }

  void addEstimates(const ros::Time& now, visualization_msgs::MarkerArray* array) {
    std::optional<std::uint8_t> in_use;
    const auto fused = estimates_.find(TargetEstimate::SOURCE_FUSED);
    if (fused != estimates_.end() && fused->second.fresh(now, config_.input_timeout_s) && fused->second.message->valid) {
      in_use = fused->second.message->selected_source;
    }
    for (std::uint8_t source = 0; source < kSourceCount; ++source) {
      const auto it = estimates_.find(source);
      const TargetEstimate* estimate = nullptr;
      if (it != estimates_.end() && it->second.fresh(now, config_.input_timeout_s)) estimate = &*it->second.message;
      double ellipsoid_alpha = in_use && *in_use == source ? kInUseAlpha : kNotInUseAlpha;
      if (source == TargetEstimate::SOURCE_FUSED) ellipsoid_alpha = kFusedEllipsoidAlpha;
      addEstimate(estimate, source, ellipsoid_alpha, array);
    }
  }

  /// One source's dot, ellipsoid and port axis, or their deletions when it has nothing drawable.
  void addEstimate(const TargetEstimate* estimate, std::uint8_t source, double ellipsoid_alpha,
                   visualization_msgs::MarkerArray* array) {
    const std::string ns = estimateNamespace(source);
    const bool drawable = estimate && estimate->valid && estimate->position_valid && usable(*estimate, ns);
    if (!drawable) {
      for (int id : {kEstimateDot, kEstimateEllipsoid, kEstimateAxis}) array->markers.push_back(deletion(ns, id));
      return;
    }
    const Rgba& colour = sourceStyle(source).colour;
    Marker dot = slot(ns, kEstimateDot, estimate->header.frame_id, estimate->header.stamp);
    dot.type = Marker::SPHERE;
    dot.pose.position = estimate->pose.pose.position;
    dot.scale.x = dot.scale.y = dot.scale.z = kEstimateDotDiameterM;
    dot.color = toColour(colour, 1.0);
    array->markers.push_back(dot);
    array->markers.push_back(ellipsoidMarker(*estimate, ns, ellipsoid_alpha));
    if (estimate->orientation_valid) {
      Marker axis = slot(ns, kEstimateAxis, estimate->header.frame_id, estimate->header.stamp);
      axis.type = Marker::ARROW;  // along the pose's x: the port axis, out of the face
      axis.pose = estimate->pose.pose;
      axis.scale.x = config_.axis_arrow_length_m;
      axis.scale.y = axis.scale.z = kArrowShaftDiameterM;
      axis.color = toColour(colour, 1.0);
      array->markers.push_back(axis);
    } else {
      array->markers.push_back(deletion(ns, kEstimateAxis));
    }
  }

  /// The checks the arbiter and the planner run (docking_msgs/estimate_check.h); a refused one is counted.
  bool usable(const TargetEstimate& estimate, const std::string& ns) {
    const auto problem = docking_msgs::checks::checkEstimate(estimate);
    if (problem == docking_msgs::checks::EstimateProblem::kNone) return true;
    skip(ns + ": " + docking_msgs::checks::estimateProblemName(problem));
    return false;
  }

  Marker ellipsoidMarker(const TargetEstimate& estimate, const std::string& ns, double alpha) {
    const EllipsoidResult result =
        covarianceEllipsoid(positionCovariance(estimate.pose.covariance.data()), config_.sigma_scale);
    if (!result.valid()) {
      skip(ns + " ellipsoid: " + ellipsoidProblemName(result.problem));
      return deletion(ns, kEstimateEllipsoid);
    }
    Marker m = slot(ns, kEstimateEllipsoid, estimate.header.frame_id, estimate.header.stamp);
    m.type = Marker::SPHERE;  // scaled per axis: an ellipsoid
    m.pose.position = estimate.pose.pose.position;
    const Eigen::Quaterniond& q = result.ellipsoid.orientation;
    m.pose.orientation.x = q.x();
    m.pose.orientation.y = q.y();
    m.pose.orientation.z = q.z();
    m.pose.orientation.w = q.w();
    m.scale.x = 2.0 * result.ellipsoid.semi_axes_m.x();  // a sphere's scale is its diameter
    m.scale.y = 2.0 * result.ellipsoid.semi_axes_m.y();
    m.scale.z = 2.0 * result.ellipsoid.semi_axes_m.z();
    m.color = toColour(sourceStyle(estimate.source).colour, alpha);
    return m;
  }

  /// The target mockup at the fused estimate, only while that estimate claims an orientation: before, the
  /// stack knows the position alone (the ellipsoid shows it), and nothing is drawn where it believes nothing.
  void addMockup(const ros::Time& now, visualization_msgs::MarkerArray* array) {
    const auto fused = estimates_.find(TargetEstimate::SOURCE_FUSED);
    const TargetEstimate* estimate = nullptr;
    if (fused != estimates_.end() && fused->second.fresh(now, config_.input_timeout_s)) estimate = &*fused->second.message;
    const bool drawn = estimate && estimate->valid && estimate->position_valid && estimate->orientation_valid &&
                       usable(*estimate, kMockupNamespace);
    for (std::size_t i = 0; i < mockup_.size(); ++i) {
      if (!drawn) {
        array->markers.push_back(deletion(kMockupNamespace, static_cast<int>(i)));
        continue;
      }
      const MockupPart& part = mockup_[i];
      const auto& p = estimate->pose.pose.position;
      const auto& q = estimate->pose.pose.orientation;
      const Eigen::Isometry3d camera_T_part =
          Eigen::Translation3d(p.x, p.y, p.z) * Eigen::Quaterniond(q.w, q.x, q.y, q.z).normalized() * part.root_T_part;
      Marker m = slot(kMockupNamespace, static_cast<int>(i), estimate->header.frame_id, estimate->header.stamp);
      m.type = part.shape == MockupPart::Shape::kBox ? Marker::CUBE
               : part.shape == MockupPart::Shape::kCylinder ? Marker::CYLINDER : Marker::SPHERE;
      m.pose.position = toPoint(camera_T_part.translation().x(), camera_T_part.translation().y(),
                                camera_T_part.translation().z());
      const Eigen::Quaterniond r(camera_T_part.linear());
      m.pose.orientation.x = r.x();
      m.pose.orientation.y = r.y();
      m.pose.orientation.z = r.z();
      m.pose.orientation.w = r.w();
      m.scale.x = part.scale.x();
      m.scale.y = part.scale.y();
      m.scale.z = part.scale.z();
      m.color = toColour(part.colour, part.colour.a);
      array->markers.push_back(m);
    }
  }

  /// The mockup's parts from the target's URDF; none (said once) when there is no such parameter or it is
  /// not a mockup of primitives: the rest of the view does not need it.
  static std::vector<MockupPart> loadMockup(const ros::NodeHandle& nh) {
    std::string urdf_xml;
    if (!nh.getParam(kTargetDescriptionParam, urdf_xml)) {
      ROS_WARN("markers: no parameter %s (launch/description.launch): the target mockup is not drawn",
               nh.resolveName(kTargetDescriptionParam).c_str());
      return {};
    }
    try {
      return mockupFromUrdf(urdf_xml);
    } catch (const std::invalid_argument& e) {
      ROS_ERROR("markers: %s: %s: the target mockup is not drawn", nh.resolveName(kTargetDescriptionParam).c_str(),
                e.what());
      return {};
    }
  }

  void addPlanner(const ros::Time& now, visualization_msgs::MarkerArray* array) {
    std::optional<PlannerDrawing> drawing;
    if (geometry_.fresh(now, config_.input_timeout_s) && geometry_.message->has_port) {
      drawing = drawPlanner(plannerView(*geometry_.message), radii_, config_.circle_segments);
      if (!drawing) skip("planner geometry: not finite");
    }
    if (!drawing) {
      for (int id : {kSafeCircle, kSearchOrbit, kPortAxis, kGoal}) array->markers.push_back(deletion(kPlannerNamespace, id));
      return;
    }
    const std_msgs::Header& header = geometry_.message->header;
    array->markers.push_back(polylineMarker(drawing->safe_circle, kSafeCircle, header, kSafeCircleColour));
    array->markers.push_back(polylineMarker(drawing->search_orbit, kSearchOrbit, header, kSearchOrbitColour));
    if (drawing->port_axis) {
      const std::vector<Vec2> axis{drawing->port_axis->from, drawing->port_axis->to};
      array->markers.push_back(polylineMarker(axis, kPortAxis, header, kPortAxisColour));
    } else {
      array->markers.push_back(deletion(kPlannerNamespace, kPortAxis));
    }
    if (drawing->goal) {
      Marker goal = slot(kPlannerNamespace, kGoal, header.frame_id, header.stamp);
      goal.type = Marker::ARROW;  // at the goal, pointing the heading the law steers to
      goal.pose.position = toPoint(drawing->goal->x, drawing->goal->y, kPlannerDrawingZM);
      goal.pose.orientation = yawQuaternion(drawing->goal->yaw);
      goal.scale.x = kGoalArrowLengthM;
      goal.scale.y = goal.scale.z = kArrowHeadDiameterM;
      goal.color = toColour(kGoalColour, kGoalColour.a);
      array->markers.push_back(goal);
    } else {
      array->markers.push_back(deletion(kPlannerNamespace, kGoal));
    }
  }

  static PlannerView plannerView(const docking_msgs::PlannerGeometry& msg) {
    PlannerView view;
    view.port = PlanarPose{msg.port.x, msg.port.y, msg.port.theta};
    view.port_orientation_known = msg.port_orientation_known;
    if (msg.has_goal) view.goal = PlanarPose{msg.goal.x, msg.goal.y, msg.goal.theta};
    return view;
  }

  Marker polylineMarker(const std::vector<Vec2>& points, int id, const std_msgs::Header& header, const Rgba& colour) const {
    Marker m = slot(kPlannerNamespace, id, header.frame_id, header.stamp);
    m.type = Marker::LINE_STRIP;
    m.scale.x = kLineWidthM;
    m.color = toColour(colour, colour.a);
    for (const Vec2& p : points) m.points.push_back(toPoint(p.x(), p.y(), kPlannerDrawingZM));
    return m;
  }

  /// The commanded linear velocity as an arrow from base_link (the planner's base frame: DockingState's).
  void addCommand(const ros::Time& now, visualization_msgs::MarkerArray* array) {
    const bool known = command_.fresh(now, config_.input_timeout_s) && state_.fresh(now, config_.input_timeout_s);
    const double vx = known ? command_.message->linear.x : 0.0;
    const double vy = known ? command_.message->linear.y : 0.0;
    if (known && !(std::isfinite(vx) && std::isfinite(vy))) skip("cmd_vel: not finite");
    if (!known || !std::isfinite(vx) || !std::isfinite(vy) || std::hypot(vx, vy) < kMinDrawnSpeedMps) {
      array->markers.push_back(deletion(kCommandNamespace, 0));
      return;
    }
    // Stamp 0: the latest tf, as the command is meant now.
    Marker arrow = slot(kCommandNamespace, 0, state_.message->header.frame_id, ros::Time());
    arrow.type = Marker::ARROW;
    arrow.points.push_back(toPoint(0.0, 0.0, kPlannerDrawingZM));
    arrow.points.push_back(toPoint(vx * config_.velocity_arrow_s, vy * config_.velocity_arrow_s, kPlannerDrawingZM));
    arrow.scale.x = kArrowShaftDiameterM;
    arrow.scale.y = kArrowHeadDiameterM;
    arrow.scale.z = kArrowHeadLengthM;
    arrow.color = toColour(kCommandColour, kCommandColour.a);
    array->markers.push_back(arrow);
  }

  /// The state label above base_link.
  void addLabel(const ros::Time& now, visualization_msgs::MarkerArray* array) {
    if (!state_.fresh(now, config_.input_timeout_s)) {
      array->markers.push_back(deletion(kStateNamespace, 0));
      return;
    }
    const docking_msgs::DockingState& s = *state_.message;
    StateSummary summary;
    summary.state_name = s.state_name;
    summary.ended_in = ended_state_memory_.endedIn();
    summary.reason = s.reason;
    summary.time_in_state_s = s.time_in_state_s;
    summary.estimate_source = s.estimate_source;
    summary.target_visible = s.target_visible;
    summary.range_m = s.range_m;
    summary.goal_distance_m = s.goal_distance_m;
    summary.lateral_error_m = s.lateral_error_m;
    summary.axial_distance_m = s.axial_distance_m;
    summary.yaw_error_rad = s.yaw_error_rad;
    if (command_.fresh(now, config_.input_timeout_s)) {
      const geometry_msgs::Twist& t = *command_.message;
      summary.command = CommandedVelocity{t.linear.x, t.linear.y, t.angular.z};
    }
    Marker text = slot(kStateNamespace, 0, s.header.frame_id, ros::Time());
    text.type = Marker::TEXT_VIEW_FACING;
    text.pose.position = toPoint(0.0, 0.0, config_.text_offset_z_m);
    text.scale.z = config_.text_height_m;
    text.color = toColour(kLabelColour, kLabelColour.a);
    text.text = formatStateLabel(summary);  // non-finite numbers print as "--": nothing invalid in a label
    array->markers.push_back(text);
  }

  ros::NodeHandle nh_;
  MarkerConfig config_;
  PlannerRadii radii_;
  std::vector<MockupPart> mockup_;  // the target's parts in its port frame (empty: not drawn)
  ros::Publisher markers_pub_;
  ros::Timer timer_;
  std::vector<ros::Subscriber> subscribers_;  // empty while nobody subscribes to the markers
  std::map<std::uint8_t, Latest<TargetEstimate>> estimates_;  // by TargetEstimate source
  Latest<docking_msgs::DockingState> state_;
  EndedStateMemory ended_state_memory_;  // while IDLE: how the last docking ended
  Latest<docking_msgs::PlannerGeometry> geometry_;
  Latest<geometry_msgs::Twist> command_;
  std::uint64_t skipped_total_{0};
  std::uint64_t reported_skipped_{0};
  std::map<std::string, std::uint64_t> skipped_by_reason_;  // "<namespace>: <problem>" -> count
};

}  // namespace
}  // namespace docking_viz

int main(int argc, char** argv) {
  ros::init(argc, argv, "markers");
  return docking_settings::runNode([] {
    docking_viz::MarkersNode node(ros::NodeHandle(), ros::NodeHandle("~"));
    ros::spin();
  });
}
