// The planner's state as a compact multi-line text for the 3D view: state, source, errors, command,
// reason. Fixed precision (a number does not change width as it changes value), "--" for an unknown
// one, the reason wrapped so that the label stays narrow. ROS-free.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>

namespace docking_viz {

/// Characters per line of the reason: about as wide as the numbers' lines.
constexpr std::size_t kLabelLineWidth = 36;
/// The reason's lines at most; a longer reason ends in "...".
constexpr std::size_t kMaxReasonLines = 3;
/// Printed for a number that is not known (NaN: the planner holds no target).
constexpr const char kUnknownValue[] = "--";

struct CommandedVelocity {
  double vx_mps{0.0};
  double vy_mps{0.0};
  double wz_radps{0.0};
};

/// docking_msgs/DockingState's fields that the label shows, plus the last commanded velocity.
struct StateSummary {
  std::string state_name;
  std::string ended_in;  ///< while IDLE: the state the last docking ended in (see EndedStateMemory), or ""
  std::string reason;
  double time_in_state_s{0.0};
  std::uint8_t estimate_source{0};  ///< TargetEstimate.SOURCE_*
  bool target_visible{false};
  double range_m{0.0};
  double goal_distance_m{0.0};
  double lateral_error_m{0.0};
  double axial_distance_m{0.0};
  double yaw_error_rad{0.0};
  std::optional<CommandedVelocity> command;  ///< absent: none received
};

/// The planner shows an end state (DOCKED, ABORT, ...) for one cycle only, then IDLE with the end's
/// reason: this remembers which state that was, so that the label can say how the docking ended.
class EndedStateMemory {
 public:
  /// Feed every state in order (`idle`: the state is DockingState.IDLE, by its code). Returns, while
  /// idle, the name of the state before IDLE ("" at start-up, before any docking); otherwise "".
  const std::string& update(bool idle, const std::string& state_name);
  /// What the last update returned.
  const std::string& endedIn() const { return ended_in_; }

 private:
  bool previous_idle_{true};  // the planner starts in IDLE
  std::string previous_name_;
  std::string ended_in_;
};

/// Lines: "STATE  t s" ("IDLE (ended in DOCKED)  t s" after a docking), "source  range .. m",
/// "goal .. m  lat .. m", "axial .. m  yaw .. deg", "cmd vx vy m/s wz rad/s" (when known), then the
/// reason wrapped at kLabelLineWidth.
std::string formatStateLabel(const StateSummary& summary);

/// `text` broken at spaces into lines of at most `width` characters (a longer word gets a line of its
/// own, cut), at most `max_lines`; a cut text ends in "...".
std::string wrapText(const std::string& text, std::size_t width, std::size_t max_lines);

}  // namespace docking_viz
