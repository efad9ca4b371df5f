// A debug image's caption: what its estimator concluded, in words, big enough to read where rviz shows the
// image (config/docking.rviz's panels show a 640x480 frame at about a third of its size, where a 0.5
// Hershey font is a few pixels high). The font scales with the image's width; the text wraps at spaces to
// at most kMaxCaptionLines lines (a longer one ends in "...") on a darkened band at the top. Header-only
// (OpenCV): the visible and IR poses' drawing and the disparity detector's share it.
#pragma once

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>
#include <vector>

namespace docking_perception {

constexpr int kMaxCaptionLines = 3;
/// Hershey simplex scale per 640 px of image width: capitals ~40 px high, ~12 px in docking.rviz's panels.
constexpr double kCaptionScalePer640Px = 1.8;

/// The caption's lines: `text` broken at spaces to fit `width_px` at `scale`, at most kMaxCaptionLines.
inline std::vector<std::string> captionLines(const std::string& text, double scale, int thickness, int width_px) {
  std::vector<std::string> lines;
  std::istringstream words(text);
  std::string word, line;
  const auto fits = [&](const std::string& s) {
    int baseline = 0;
    return cv::getTextSize(s, cv::FONT_HERSHEY_SIMPLEX, scale, thickness, &baseline).width <= width_px;
  };
  while (words >> word) {
    const std::string longer = line.empty() ? word : line + " " + word;
    if (line.empty() || fits(longer)) {
      line = longer;
      continue;
    }
    lines.push_back(line);
    line = word;
  }
  if (!line.empty()) lines.push_back(line);
  if (static_cast<int>(lines.size()) > kMaxCaptionLines) {
    lines.resize(kMaxCaptionLines);
    lines.back() += " ...";
  }
  return lines;
}

/// Draws `text` across the top of `image` (8-bit, 3 channels) in `colour` on a darkened band.
inline void drawCaption(cv::Mat& image, const std::string& text, const cv::Scalar& colour) {
  if (image.empty() || image.type() != CV_8UC3 || text.empty()) return;
  const double scale = kCaptionScalePer640Px * image.cols / 640.0;
  const int thickness = std::max(1, static_cast<int>(std::lround(2.0 * scale)));
  const int margin = std::max(2, image.cols / 80);
  const std::vector<std::string> lines = captionLines(text, scale, thickness, image.cols - 2 * margin);
  int baseline = 0;
  const int line_height =
      cv::getTextSize("Hg", cv::FONT_HERSHEY_SIMPLEX, scale, thickness, &baseline).height + baseline + margin;
  const int band = std::min(image.rows, margin + line_height * static_cast<int>(lines.size()));
  cv::Mat top = image(cv::Rect(0, 0, image.cols, band));
  top.convertTo(top, -1, 0.3);  // darkened, not hidden: the image stays readable under the text
  for (std::size_t i = 0; i < lines.size(); ++i) {
    const cv::Point origin(margin, margin + line_height * static_cast<int>(i + 1) - baseline);
    cv::putText(image, lines[i], origin, cv::FONT_HERSHEY_SIMPLEX, scale, colour, thickness, cv::LINE_AA);
  }
}

}  // namespace docking_perception
