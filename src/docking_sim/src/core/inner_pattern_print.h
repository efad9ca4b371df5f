// The print of target.yaml's inner pattern (an AprilTag near the port), as the simulator draws it.
#pragma once

#include <opencv2/core.hpp>

#include "docking_sim/configs.h"

namespace docking_sim {

/// Edge of the whole print (the tag with its one-cell white ring) over the tag's size_m: tag36h11 has
/// 8 black-bordered cells inside a 10-cell print.
constexpr double kInnerPrintOverTagSize = 10.0 / 8.0;

/// The print as a BGR image, `px_per_cell` pixels per cell (nearest, so the cell edges stay sharp up to
/// the renderer's bilinear filtering), rows along -z and columns along +y of frame `target` as the face
/// texture. Cells from libapriltag (apriltag_to_image): black 25, white 240 as the face's paper.
cv::Mat innerPatternPrint(const InnerPatternConfig& pattern, int px_per_cell);

}  // namespace docking_sim
