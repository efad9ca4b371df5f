#include "docking_image_transport/compressed_publisher.h"

#include <ros/console.h>
#include <xmlrpcpp/XmlRpcValue.h>

namespace docking_image_transport {
namespace {

// One parameter: absent -> the default; present but not an int -> an error naming it.
bool readInt(const ros::NodeHandle& nh, const std::string& name, int fallback, int* value, std::string* error) {
  XmlRpc::XmlRpcValue v;
  if (!nh.getParamCached(name, v)) {
    *value = fallback;
    return true;
  }
  if (v.getType() != XmlRpc::XmlRpcValue::TypeInt) {
    *error = nh.resolveName(name) + " must be an integer";
    return false;
  }
  *value = static_cast<int>(v);
  return true;
}

}  // namespace

bool CompressedPublisher::readSettings(EncodeSettings* settings, std::string* error) const {
  std::string format = "jpeg";
  XmlRpc::XmlRpcValue v;
  if (nh().getParamCached("format", v)) {
    if (v.getType() != XmlRpc::XmlRpcValue::TypeString) {
      *error = nh().resolveName("format") + " must be the string jpeg or png";
      return false;
    }
    format = static_cast<std::string>(v);
  }
  if (!parseCodec(format, &settings->codec)) {
    *error = nh().resolveName("format") + " must be jpeg or png (got '" + format + "')";
    return false;
  }
  if (!readInt(nh(), "jpeg_quality", kDefaultJpegQuality, &settings->jpeg_quality, error) ||
      !readInt(nh(), "png_level", kDefaultPngLevel, &settings->png_level, error))
    return false;
  const std::vector<std::string> bad = validateSettings(*settings);
  if (!bad.empty()) {
    // The core names the field; prefix the parameter's namespace so the user knows where to fix it.
    *error = nh().getNamespace() + "/" + bad.front();
    return false;
  }
  return true;
}

void CompressedPublisher::publish(const sensor_msgs::Image& message, const PublishFn& publish_fn) const {
  EncodeSettings settings;
  std::string error;
  if (!readSettings(&settings, &error)) {
    ROS_ERROR_THROTTLE(5.0, "%s; not publishing on %s", error.c_str(), getTopic().c_str());
    return;
  }
  ImageView view;
  view.width = static_cast<int>(message.width);
  view.height = static_cast<int>(message.height);
  view.encoding = message.encoding;
  view.is_bigendian = message.is_bigendian != 0;
  view.step = message.step;
  view.data = message.data.data();
  view.size = message.data.size();
  EncodeResult encoded = encode(view, settings);
  if (!encoded.ok()) {
    ROS_ERROR_THROTTLE(5.0, "%s: frame dropped: %s (%s)", getTopic().c_str(), encoded.reason.c_str(),
                       errorName(encoded.error));
    return;
  }
  sensor_msgs::CompressedImage compressed;
  compressed.header = message.header;
  compressed.format = std::move(encoded.format);
  compressed.data = std::move(encoded.data);
  publish_fn(compressed);
}

}  // namespace docking_image_transport
