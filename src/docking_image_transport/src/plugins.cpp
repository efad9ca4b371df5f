// The two classes plugins.xml names, for pluginlib.
#include <pluginlib/class_list_macros.hpp>

#include "docking_image_transport/compressed_publisher.h"
#include "docking_image_transport/compressed_subscriber.h"

PLUGINLIB_EXPORT_CLASS(docking_image_transport::CompressedPublisher, image_transport::PublisherPlugin)
PLUGINLIB_EXPORT_CLASS(docking_image_transport::CompressedSubscriber, image_transport::SubscriberPlugin)
