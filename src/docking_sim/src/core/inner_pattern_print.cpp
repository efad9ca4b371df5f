#include "inner_pattern_print.h"

#include <apriltag/apriltag.h>
#include <apriltag/tag36h11.h>

#include <cstdlib>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

namespace docking_sim {

cv::Mat innerPatternPrint(const InnerPatternConfig& pattern, int px_per_cell) {
  if (pattern.family != "tag36h11") throw std::invalid_argument("inner pattern: only tag36h11 is supported");
  if (px_per_cell < 1) throw std::invalid_argument("inner pattern: px_per_cell must be >= 1");
  apriltag_family_t* family = tag36h11_create();
  image_u8_t* tag = apriltag_to_image(family, static_cast<uint32_t>(pattern.id));
  cv::Mat cells(tag->height, tag->width, CV_8UC1);
  for (int r = 0; r < tag->height; ++r) {
    for (int c = 0; c < tag->width; ++c) cells.at<uchar>(r, c) = tag->buf[r * tag->stride + c] < 128 ? 25 : 240;
  }
  // Debian's libapriltag does not export image_u8_destroy: the image is a calloc'ed struct and buffer.
  std::free(tag->buf);
  std::free(tag);
  tag36h11_destroy(family);
  cv::Mat big, bgr;
  cv::resize(cells, big, cv::Size(), px_per_cell, px_per_cell, cv::INTER_NEAREST);
  cv::cvtColor(big, bgr, cv::COLOR_GRAY2BGR);
  return bgr;
}

}  // namespace docking_sim
