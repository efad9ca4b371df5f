#include <docking_perception/camera/source_spec.h>

#include <cctype>
#include <climits>
#include <stdexcept>

namespace docking_perception {
namespace camera {
namespace {

std::string trim(const std::string& text) {
  const auto first = text.find_first_not_of(" \t\r\n");
  if (first == std::string::npos) return "";
  const auto last = text.find_last_not_of(" \t\r\n");
  return text.substr(first, last - first + 1);
}

bool allDigits(const std::string& text) {
  if (text.empty()) return false;
  for (char c : text) {
    if (!std::isdigit(static_cast<unsigned char>(c))) return false;
  }
  return true;
}

// Counts printf integer conversions ("%d", "%04d"); returns -1 if a '%' starts anything else.
int countIntegerConversions(const std::string& text) {
  int conversions = 0;
  for (size_t i = 0; i < text.size(); ++i) {
    if (text[i] != '%') continue;
    size_t j = i + 1;
    while (j < text.size() && std::isdigit(static_cast<unsigned char>(text[j]))) ++j;
    if (j >= text.size() || text[j] != 'd') return -1;
    ++conversions;
    i = j;
  }
  return conversions;
}

}  // namespace

const char* toString(SourceKind kind) {
  switch (kind) {
    case SourceKind::kDeviceIndex: return "V4L2 device index";
    case SourceKind::kDevicePath: return "V4L2 device";
    case SourceKind::kVideoFile: return "video file";
    case SourceKind::kImageSequence: return "image sequence";
  }
  return "unknown source";
}

std::string SourceSpec::describe() const {
  if (kind == SourceKind::kDeviceIndex) return "V4L2 device " + text + " (/dev/video" + text + ")";
  return std::string(toString(kind)) + " " + text;
}

SourceSpec parseSourceSpec(const std::string& raw) {
  SourceSpec spec;
  spec.text = trim(raw);
  if (spec.text.empty()) throw std::invalid_argument("capture source is empty");

  if (allDigits(spec.text)) {
    if (spec.text.size() > 4) throw std::invalid_argument("device index '" + spec.text + "' is out of range");
    spec.kind = SourceKind::kDeviceIndex;
    spec.device_index = std::stoi(spec.text);
    return spec;
  }
  if (spec.text[0] == '-' && allDigits(spec.text.substr(1))) {
    throw std::invalid_argument("device index '" + spec.text + "' is negative");
  }
  if (spec.text.rfind("/dev/", 0) == 0) {
    spec.kind = SourceKind::kDevicePath;
    return spec;
  }
  const int conversions = countIntegerConversions(spec.text);
  if (conversions < 0) {
    throw std::invalid_argument("source '" + spec.text +
                                "' has a '%' that is not an integer pattern such as %d or %04d");
  }
  if (conversions > 1) {
    throw std::invalid_argument("image-sequence pattern '" + spec.text + "' has more than one %d");
  }
  spec.kind = conversions == 1 ? SourceKind::kImageSequence : SourceKind::kVideoFile;
  return spec;
}

}  // namespace camera
}  // namespace docking_perception
