// image_transport publisher plugin `compressed`: sensor_msgs/Image -> sensor_msgs/CompressedImage on
// <base topic>/compressed (JPEG or PNG, the standard compressed transport's format strings).
// Parameters, read per frame (cached) so that `rosparam set` takes effect live, in the transport topic's
// namespace <base topic>/compressed/: format (jpeg|png), jpeg_quality (1..100), png_level (0..9).
#pragma once

#include <image_transport/simple_publisher_plugin.h>
#include <sensor_msgs/CompressedImage.h>

#include <string>

#include "docking_image_transport/codec.h"

namespace docking_image_transport {

// The default JPEG quality: chosen from the measurement in docs/PERFORMANCE.md ("Images across a
// network link").
constexpr int kDefaultJpegQuality = 95;
constexpr int kDefaultPngLevel = 3;

class CompressedPublisher : public image_transport::SimplePublisherPlugin<sensor_msgs::CompressedImage> {
 public:
  std::string getTransportName() const override { return "compressed"; }

 protected:
  void publish(const sensor_msgs::Image& message, const PublishFn& publish_fn) const override;

 private:
  // The settings from the parameter server; false (with the reasons, parameters named) if invalid.
  bool readSettings(EncodeSettings* settings, std::string* error) const;
};

}  // namespace docking_image_transport
