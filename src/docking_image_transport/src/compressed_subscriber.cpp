#include "docking_image_transport/compressed_subscriber.h"

#include <ros/console.h>
#include <sensor_msgs/Image.h>

#include <boost/make_shared.hpp>
#include <exception>

#include "docking_image_transport/codec.h"

namespace docking_image_transport {

void CompressedSubscriber::internalCallback(const sensor_msgs::CompressedImageConstPtr& message,
                                            const Callback& user_cb) {
  DecodeResult decoded;
  try {
    decoded = decode(message->format, message->data.data(), message->data.size());
  } catch (const std::exception& e) {  // decode() reports what it knows; anything else (bad_alloc, OpenCV) too
    ROS_ERROR_THROTTLE(5.0, "%s: dropped a frame of %zu bytes, format '%s': %s", getTopic().c_str(),
                       message->data.size(), message->format.c_str(), e.what());
    return;
  }
  if (!decoded.ok()) {
    ROS_ERROR_THROTTLE(5.0, "%s: dropped a frame of %zu bytes, format '%s': %s (%s)", getTopic().c_str(),
                       message->data.size(), message->format.c_str(), decoded.reason.c_str(),
                       errorName(decoded.error));
    return;
  }
  auto image = boost::make_shared<sensor_msgs::Image>();
  image->header = message->header;
  image->width = static_cast<std::uint32_t>(decoded.image.width);
  image->height = static_cast<std::uint32_t>(decoded.image.height);
  image->encoding = decoded.image.encoding;
  image->is_bigendian = 0;
  image->step = static_cast<std::uint32_t>(decoded.image.step);
  image->data = std::move(decoded.image.data);
  user_cb(image);
}

}  // namespace docking_image_transport
