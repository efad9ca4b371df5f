#include <docking_perception/camera/capture_rig.h>

#include <algorithm>
#include <filesystem>
#include <stdexcept>
#include <system_error>
#include <utility>

namespace docking_perception {
namespace camera {
namespace {

bool pathExists(const std::string& path) {
  std::error_code ignored;
  return std::filesystem::exists(path, ignored);
}

}  // namespace

const char* toString(CaptureStatus status) {
  switch (status) {
    case CaptureStatus::kFrames: return "frames";
    case CaptureStatus::kEmptyFrame: return "empty frame";
    case CaptureStatus::kWaiting: return "waiting to reopen";
    case CaptureStatus::kRestarted: return "restarted at end of file";
    case CaptureStatus::kEndOfStream: return "end of stream";
  }
  return "unknown";
}

void validateCaptureSettings(const CaptureSettings& settings) {
  if (settings.width <= 0 || settings.height <= 0) {
    throw std::invalid_argument("width and height must be positive, got " + std::to_string(settings.width) + "x" +
                                std::to_string(settings.height));
  }
  if (!(settings.fps > 0.0)) throw std::invalid_argument("fps must be positive, got " + std::to_string(settings.fps));
  if (!settings.fourcc.empty() && settings.fourcc.size() != 4) {
    throw std::invalid_argument("fourcc must have 4 characters (e.g. MJPG, YUYV) or be empty, got '" +
                                settings.fourcc + "'");
  }
  if (settings.max_consecutive_empty < 1) {
    throw std::invalid_argument("max_consecutive_empty must be at least 1, got " +
                                std::to_string(settings.max_consecutive_empty));
  }
}

CaptureRig::CaptureRig(std::vector<SourceSpec> sources, const CaptureSettings& settings,
                       const BackoffParams& backoff)
    : sources_(std::move(sources)), settings_(settings), backoff_(backoff), captures_(sources_.size()) {
  if (sources_.empty()) throw std::invalid_argument("a capture rig needs at least one source");
  validateCaptureSettings(settings_);
}

CaptureRig::~CaptureRig() { close(); }

void CaptureRig::close() {
  for (auto& capture : captures_) capture.release();
  open_ = false;
}

bool CaptureRig::allFiles() const {
  for (const auto& source : sources_) {
    if (source.isLiveDevice()) return false;
  }
  return true;
}

std::vector<cv::Size> CaptureRig::openedSizes() const {
  std::vector<cv::Size> sizes;
  for (const auto& capture : captures_) {
    sizes.emplace_back(static_cast<int>(capture.get(cv::CAP_PROP_FRAME_WIDTH)),
                       static_cast<int>(capture.get(cv::CAP_PROP_FRAME_HEIGHT)));
  }
  return sizes;
}

bool CaptureRig::openOne(size_t index, std::string* error) {
  const SourceSpec& source = sources_[index];
  cv::VideoCapture& capture = captures_[index];
  switch (source.kind) {
    case SourceKind::kDeviceIndex:
    case SourceKind::kDevicePath: {
      const std::string path =
          source.kind == SourceKind::kDevicePath ? source.text : "/dev/video" + std::to_string(source.device_index);
      if (!pathExists(path)) {
        *error = source.describe() + " does not exist (not plugged in?)";
        return false;
      }
      const bool opened = source.kind == SourceKind::kDevicePath ? capture.open(path, cv::CAP_V4L2)
                                                                 : capture.open(source.device_index, cv::CAP_V4L2);
      if (!opened || !capture.isOpened()) {
        *error = "cannot open " + source.describe() +
                 " (busy in another program, no permission (group video?), or not a capture device)";
        return false;
      }
      // The driver may refuse any of these; the frames' real size is checked against the calibration.
      if (!settings_.fourcc.empty()) {
        const auto& f = settings_.fourcc;
        capture.set(cv::CAP_PROP_FOURCC, cv::VideoWriter::fourcc(f[0], f[1], f[2], f[3]));
      }
      capture.set(cv::CAP_PROP_FRAME_WIDTH, settings_.width);
      capture.set(cv::CAP_PROP_FRAME_HEIGHT, settings_.height);
      capture.set(cv::CAP_PROP_FPS, settings_.fps);
      // A short driver queue keeps frames fresh when we read slower than the device delivers.
      capture.set(cv::CAP_PROP_BUFFERSIZE, 1);
      return true;
    }
    case SourceKind::kVideoFile:
      if (source.text.find("://") == std::string::npos && !pathExists(source.text)) {
        *error = source.describe() + " not found";
        return false;
      }
      if (!capture.open(source.text, cv::CAP_ANY) || !capture.isOpened()) {
        *error = "cannot read " + source.describe() + " (not a video OpenCV can decode?)";
        return false;
      }
      return true;
    case SourceKind::kImageSequence:
      if (!capture.open(source.text, cv::CAP_IMAGES) || !capture.isOpened()) {
        *error = "no readable image matches " + source.describe() + " (numbering must start at 0 to 4)";
        return false;
      }
      return true;
  }
  *error = "unknown source kind for " + source.text;
  return false;
}

bool CaptureRig::openAll(std::string* error) {
  frame_counts_.assign(sources_.size(), 0);
  for (size_t i = 0; i < sources_.size(); ++i) {
    if (!openOne(i, error)) {
      close();
      return false;
    }
    // Files and sequences know their length: ending there avoids a failed read of a file that is not
    // there (which OpenCV reports as a warning every time a sequence loops).
    if (!sources_[i].isLiveDevice()) {
      frame_counts_[i] = std::max(0L, static_cast<long>(captures_[i].get(cv::CAP_PROP_FRAME_COUNT)));
    }
  }
  return true;
}

bool CaptureRig::reachedKnownEnd() const {
  for (size_t i = 0; i < frame_counts_.size(); ++i) {
    if (frame_counts_[i] > 0 && frames_since_open_ >= frame_counts_[i]) return true;
  }
  return false;
}

CaptureOutcome CaptureRig::endOfFiles(double now_s, const std::string& end) {
  CaptureOutcome outcome;
  close();
  if (settings_.loop_files) {
    retry_at_s_ = now_s;  // reopen on the next call, without backoff
    outcome.status = CaptureStatus::kRestarted;
    outcome.message = end + ", starting again";
    return outcome;
  }
  ended_ = true;
  last_error_ = end;
  outcome.status = CaptureStatus::kEndOfStream;
  outcome.message = end;
  return outcome;
}

CaptureOutcome CaptureRig::scheduleRetry(double now_s, const std::string& what) {
  close();
  retry_at_s_ = now_s + backoff_.nextDelay();
  last_error_ = what;
  CaptureOutcome outcome;
  outcome.status = CaptureStatus::kWaiting;
  outcome.message = what;
  outcome.retry_at_s = retry_at_s_;
  outcome.new_failure = true;
  return outcome;
}

CaptureOutcome CaptureRig::capture(double now_s, const std::function<void()>& after_grab) {
  CaptureOutcome outcome;
  if (ended_) {
    outcome.status = CaptureStatus::kEndOfStream;
    outcome.message = last_error_;
    return outcome;
  }
  if (!open_) {
    if (now_s < retry_at_s_) {
      outcome.status = CaptureStatus::kWaiting;
      outcome.message = last_error_;
      outcome.retry_at_s = retry_at_s_;
      return outcome;
    }
    std::string error;
    if (!openAll(&error)) return scheduleRetry(now_s, error);
    open_ = true;
    frames_since_open_ = 0;
    consecutive_empty_ = 0;
  }

  // Grab every source first (cheap: it only latches the frame), decode afterwards, so that the pair is
  // as close in time as the devices allow.
  if (allFiles() && reachedKnownEnd()) return endOfFiles(now_s, "end of " + sources_.front().describe());
  for (size_t i = 0; i < captures_.size(); ++i) {
    if (captures_[i].grab()) continue;
    if (allFiles() && frames_since_open_ > 0) return endOfFiles(now_s, "end of " + sources_[i].describe());
    return scheduleRetry(now_s, frames_since_open_ > 0 ? "lost " + sources_[i].describe() + " (grab failed)"
                                                       : sources_[i].describe() + " opened but gives no frames");
  }
  if (after_grab) after_grab();

  outcome.frames.resize(captures_.size());
  for (size_t i = 0; i < captures_.size(); ++i) {
    if (captures_[i].retrieve(outcome.frames[i]) && !outcome.frames[i].empty()) continue;
    outcome.frames.clear();
    ++consecutive_empty_;
    if (consecutive_empty_ >= settings_.max_consecutive_empty) {
      return scheduleRetry(now_s, sources_[i].describe() + " gave " + std::to_string(consecutive_empty_) +
                                      " empty frames in a row");
    }
    outcome.status = CaptureStatus::kEmptyFrame;
    outcome.message = "empty frame from " + sources_[i].describe();
    return outcome;
  }
  consecutive_empty_ = 0;
  ++frames_since_open_;
  backoff_.reset();
  outcome.status = CaptureStatus::kFrames;
  return outcome;
}

}  // namespace camera
}  // namespace docking_perception
