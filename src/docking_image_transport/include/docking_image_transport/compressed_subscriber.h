// image_transport subscriber plugin `compressed`: sensor_msgs/CompressedImage on <base topic>/compressed
// -> sensor_msgs/Image. Corrupt, truncated or empty messages are dropped with a throttled error naming
// the topic; nothing here throws into the subscriber's spinner.
#pragma once

#include <image_transport/simple_subscriber_plugin.h>
#include <sensor_msgs/CompressedImage.h>

#include <string>

namespace docking_image_transport {

class CompressedSubscriber : public image_transport::SimpleSubscriberPlugin<sensor_msgs::CompressedImage> {
 public:
  std::string getTransportName() const override { return "compressed"; }

 protected:
  void internalCallback(const sensor_msgs::CompressedImageConstPtr& message, const Callback& user_cb) override;
};

}  // namespace docking_image_transport
