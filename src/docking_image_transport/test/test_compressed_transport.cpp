// The `compressed` transport end to end (test/compressed_transport.test): images published here through
// image_transport come back from image_transport's republish nodes, which subscribed with the
// `compressed` transport, as raw images with the same size, encoding and stamp (PNG: bit-exact).
#include <gtest/gtest.h>
#include <image_transport/image_transport.h>
#include <ros/ros.h>
#include <sensor_msgs/CompressedImage.h>
#include <sensor_msgs/Image.h>

#include <opencv2/core.hpp>

#include <map>
#include <mutex>
#include <string>
#include <vector>

#include "docking_image_transport/codec.h"

namespace {

struct Received {
  std::mutex mutex;
  std::map<double, sensor_msgs::ImageConstPtr> by_stamp;

  void add(const sensor_msgs::ImageConstPtr& image) {
    std::lock_guard<std::mutex> lock(mutex);
    by_stamp[image->header.stamp.toSec()] = image;
  }
  std::size_t size() {
    std::lock_guard<std::mutex> lock(mutex);
    return by_stamp.size();
  }
  sensor_msgs::ImageConstPtr at(double stamp) {
    std::lock_guard<std::mutex> lock(mutex);
    auto it = by_stamp.find(stamp);
    return it == by_stamp.end() ? nullptr : it->second;
  }
};

// A 64x48 image with a pattern that depends on `seed`, so that a mixed-up frame would not match.
sensor_msgs::ImagePtr makeImage(const std::string& encoding, int seed, double stamp) {
  const int channels = encoding == "mono8" ? 1 : 3;
  auto image = boost::make_shared<sensor_msgs::Image>();
  image->header.stamp = ros::Time(stamp);
  image->header.frame_id = "test_optical_frame";
  image->width = 64;
  image->height = 48;
  image->encoding = encoding;
  image->step = 64 * channels;
  image->data.resize(image->step * image->height);
  cv::RNG rng(static_cast<std::uint64_t>(seed));
  for (std::uint32_t r = 0; r < image->height; ++r)
    for (std::uint32_t c = 0; c < image->step; ++c)
      image->data[r * image->step + c] = static_cast<std::uint8_t>(2 * r + c / channels + seed * 17 + rng.uniform(0, 6));
  return image;
}

double meanAbsDifference(const std::vector<std::uint8_t>& a, const std::vector<std::uint8_t>& b) {
  double sum = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) sum += std::abs(static_cast<int>(a[i]) - static_cast<int>(b[i]));
  return sum / static_cast<double>(a.size());
}

bool waitFor(const std::function<bool()>& done, double timeout_s) {
  const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(timeout_s);
  while (ros::ok() && ros::WallTime::now() < deadline) {
    if (done()) return true;
    ros::WallDuration(0.02).sleep();
  }
  return done();
}

class CompressedTransport : public ::testing::Test {
 protected:
  CompressedTransport() : it_(nh_) {}

  // Publishes one image per encoding through `base` and checks what comes back on `base`_out.
  void roundTrip(const std::string& base, double first_stamp, bool lossless) {
    Received received;
    image_transport::Publisher pub = it_.advertise(base + "/image", 10);
    image_transport::Subscriber sub =
        it_.subscribe(base + "/image_out", 10, &Received::add, &received, image_transport::TransportHints("raw"));
    // The republish node subscribes to our /compressed topic, and we to its output.
    ASSERT_TRUE(waitFor([&] { return pub.getNumSubscribers() > 0 && sub.getNumPublishers() > 0; }, 20.0))
        << base << ": republish did not connect";
    std::vector<sensor_msgs::ImagePtr> sent;
    const std::vector<std::string> encodings = {"mono8", "bgr8", "rgb8"};
    for (std::size_t i = 0; i < encodings.size(); ++i) {
      sent.push_back(makeImage(encodings[i], static_cast<int>(i) + 1, first_stamp + static_cast<double>(i)));
      pub.publish(sent.back());
      ros::WallDuration(0.05).sleep();
    }
    ASSERT_TRUE(waitFor([&] { return received.size() >= sent.size(); }, 10.0))
        << base << ": " << received.size() << " of " << sent.size() << " images came back";
    for (const auto& in : sent) {
      const sensor_msgs::ImageConstPtr out = received.at(in->header.stamp.toSec());
      ASSERT_TRUE(out) << base << ": no image with stamp " << in->header.stamp;
      EXPECT_EQ(out->encoding, in->encoding);
      EXPECT_EQ(out->width, in->width);
      EXPECT_EQ(out->height, in->height);
      EXPECT_EQ(out->header.frame_id, in->header.frame_id);
      ASSERT_EQ(out->data.size(), in->data.size()) << in->encoding;
      if (lossless) {
        EXPECT_TRUE(out->data == in->data) << base << " " << in->encoding << " not bit-exact";
      } else {
        const double error = meanAbsDifference(out->data, in->data);
        EXPECT_GT(error, 0.0) << "JPEG should be lossy; was it PNG?";
        EXPECT_LT(error, 4.0) << in->encoding;
      }
    }
  }

  ros::NodeHandle nh_;
  image_transport::ImageTransport it_;
};

TEST_F(CompressedTransport, PngIsBitExact) { roundTrip("png", 100.0, true); }

TEST_F(CompressedTransport, JpegArrivesWithSizeEncodingAndStamp) { roundTrip("jpeg", 200.0, false); }

TEST_F(CompressedTransport, BadMessagesAreDroppedAndTheSubscriberCarriesOn) {
  Received received;
  ros::Publisher pub = nh_.advertise<sensor_msgs::CompressedImage>("corrupt/image/compressed", 10);
  image_transport::Subscriber sub = it_.subscribe("corrupt/image_out", 10, &Received::add, &received,
                                                  image_transport::TransportHints("raw"));
  ASSERT_TRUE(waitFor([&] { return pub.getNumSubscribers() > 0 && sub.getNumPublishers() > 0; }, 20.0));

  const sensor_msgs::ImagePtr good = makeImage("bgr8", 9, 305.0);
  docking_image_transport::ImageView view;
  view.width = static_cast<int>(good->width);
  view.height = static_cast<int>(good->height);
  view.encoding = good->encoding;
  view.step = good->step;
  view.data = good->data.data();
  view.size = good->data.size();
  docking_image_transport::EncodeSettings settings;
  settings.codec = docking_image_transport::Codec::kJpeg;
  const docking_image_transport::EncodeResult encoded = docking_image_transport::encode(view, settings);
  ASSERT_TRUE(encoded.ok()) << encoded.reason;

  std::vector<sensor_msgs::CompressedImage> messages(5);
  for (std::size_t i = 0; i < messages.size(); ++i) {
    messages[i].header.stamp = ros::Time(301.0 + static_cast<double>(i));
    messages[i].format = encoded.format;
    messages[i].data = encoded.data;
  }
  messages[0].data.clear();                                         // empty
  messages[1].data.resize(messages[1].data.size() / 2);             // truncated
  for (std::size_t k = 0; k < messages[2].data.size(); k += 3) messages[2].data[k] = 0x5A;  // garbage
  messages[3].format = "bgr8; gif compressed bgr8";                 // unknown format
  // messages[4] (stamp 305) is the good one, after the bad ones.
  for (const auto& m : messages) {
    pub.publish(m);
    ros::WallDuration(0.05).sleep();
  }
  ASSERT_TRUE(waitFor([&] { return received.size() >= 1; }, 10.0)) << "the good frame after the bad ones never came";
  ros::WallDuration(0.5).sleep();  // anything else that was (wrongly) decoded would be here by now
  EXPECT_EQ(received.size(), 1u);
  const sensor_msgs::ImageConstPtr out = received.at(305.0);
  ASSERT_TRUE(out);
  EXPECT_EQ(out->encoding, "bgr8");
  EXPECT_EQ(out->width, good->width);
}

TEST_F(CompressedTransport, InvalidQualityPublishesNothingUntilFixed) {
  Received received;
  image_transport::Publisher pub = it_.advertise("badparam/image", 10);
  image_transport::Subscriber sub = it_.subscribe("badparam/image_out", 10, &Received::add, &received,
                                                  image_transport::TransportHints("raw"));
  ASSERT_TRUE(waitFor([&] { return pub.getNumSubscribers() > 0 && sub.getNumPublishers() > 0; }, 20.0));
  for (int i = 0; i < 10; ++i) {
    pub.publish(makeImage("mono8", i, 400.0 + i));
    ros::WallDuration(0.05).sleep();
  }
  ros::WallDuration(1.0).sleep();
  EXPECT_EQ(received.size(), 0u) << "jpeg_quality 0 must not be replaced silently";

  // Parameters are read per frame: fixing it takes effect without restarting the publisher.
  ros::param::set("badparam/image/compressed/jpeg_quality", 75);
  ASSERT_TRUE(waitFor([&] {
    pub.publish(makeImage("mono8", 50, 500.0));
    return received.size() > 0;
  }, 10.0));
  EXPECT_EQ(received.at(500.0)->encoding, "mono8");
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_compressed_transport");
  ros::AsyncSpinner spinner(2);
  spinner.start();
  const int result = RUN_ALL_TESTS();
  spinner.stop();
  ros::shutdown();
  return result;
}
