#include "docking_viz/state_label.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <vector>

#include "docking_viz/palette.h"

namespace docking_viz {

namespace {

constexpr double kRadToDeg = 180.0 / M_PI;
constexpr const char kEllipsis[] = "...";

/// `value` printed with printf `format`, or kUnknownValue when it is not finite.
std::string number(const char* format, double value) {
  if (!std::isfinite(value)) return kUnknownValue;
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), format, value);
  return buffer;
}

std::vector<std::string> words(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream stream(text);
  for (std::string word; stream >> word;) out.push_back(word);
  return out;
}

}  // namespace

std::string wrapText(const std::string& text, std::size_t width, std::size_t max_lines) {
  if (width == 0 || max_lines == 0) return "";
  std::vector<std::string> lines;
  std::string line;
  bool cut = false;
  for (std::string word : words(text)) {
    if (word.size() > width) word = word.substr(0, width);  // a path or an id: cut, not overflowing
    if (!line.empty() && line.size() + 1 + word.size() > width) {
      lines.push_back(line);
      line.clear();
    }
    if (lines.size() == max_lines) {
      cut = true;
      break;
    }
    line += (line.empty() ? "" : " ") + word;
  }
  if (!line.empty() && lines.size() < max_lines) lines.push_back(line);
  if (cut) {
    std::string& last = lines.back();
    const std::size_t keep = std::min(last.size(), width - std::min(width, sizeof(kEllipsis) - 1));
    last = last.substr(0, keep) + kEllipsis;
  }
  std::string out;
  for (std::size_t i = 0; i < lines.size(); ++i) out += (i > 0 ? "\n" : "") + lines[i];
  return out;
}

const std::string& EndedStateMemory::update(bool idle, const std::string& state_name) {
  if (!idle) {
    ended_in_.clear();
  } else if (!previous_idle_) {
    ended_in_ = previous_name_;
  }
  previous_idle_ = idle;
  previous_name_ = state_name;
  return ended_in_;
}

std::string formatStateLabel(const StateSummary& s) {
  const std::string source = s.target_visible ? sourceStyle(s.estimate_source).name : std::string("target not seen");
  std::string state = s.state_name.empty() ? std::string("?") : s.state_name;
  if (!s.ended_in.empty()) state += " (ended in " + s.ended_in + ")";
  // Short lines: a narrow label stays inside the default view wherever the chaser is.
  std::vector<std::string> lines;
  lines.push_back(state + "  " + number("%.1f", s.time_in_state_s) + " s");
  lines.push_back(source + "  range " + number("%.2f", s.range_m) + " m");
  lines.push_back("goal " + number("%.2f", s.goal_distance_m) + " m  lat " + number("%+.3f", s.lateral_error_m) + " m");
  lines.push_back("axial " + number("%.2f", s.axial_distance_m) + " m  yaw " +
                  number("%+.1f", s.yaw_error_rad * kRadToDeg) + " deg");
  if (s.command) {
    lines.push_back("cmd " + number("%+.2f", s.command->vx_mps) + " " + number("%+.2f", s.command->vy_mps) + " m/s " +
                    number("%+.2f", s.command->wz_radps) + " rad/s");
  }
  const std::string reason = wrapText(s.reason, kLabelLineWidth, kMaxReasonLines);
  if (!reason.empty()) lines.push_back(reason);
  std::string label;
  for (std::size_t i = 0; i < lines.size(); ++i) label += (i > 0 ? "\n" : "") + lines[i];
  return label;
}

}  // namespace docking_viz
