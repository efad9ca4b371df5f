#!/usr/bin/env python3
"""rostest: docking_sim publishes the three cameras at the configured rate in sim time, with valid
camera_info matching the calibration files, and ground truth stamped like the images.

The rate is the simulator's publishing rate: frames published (the headers' seq, which the publisher
counts) over the sim time their stamps span. A frame lost on its way to this test is not a frame the
simulator failed to publish: when rendering falls behind on a busy machine the simulator catches up in a
burst, and a slow subscriber loses part of it in the publisher's queue (stop 17: 25.7 Hz received of 30
published, beside two CPU hogs and a second make test). Images are received undecoded (rospy.AnyMsg, a
16 MB read buffer: decoding three 640x480 cameras at 30 Hz in Python is most of what loses them); only
the image whose fields are checked is decoded."""
import math
import os
import struct
import sys
import unittest

import rospy
import rostest
import yaml
from nav_msgs.msg import Odometry
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import CameraInfo, Image

CAMERAS = {
    # topic base: (frame id, encoding, calibration file)
    "stereo/left": ("stereo_left_optical_frame", "bgr8", "cameras/stereo_left.yaml"),
    # Both images of the stereo pair carry the left frame (robot.yaml image_frame_id): stereo_image_proc
    # requires one frame per pair.
    "stereo/right": ("stereo_left_optical_frame", "bgr8", "cameras/stereo_right.yaml"),
    "ir": ("ir_optical_frame", "mono8", "cameras/ir.yaml"),
}


IMAGE_BUFFER_BYTES = 2 ** 24  # rospy's default 64 kB reads a 900 kB image in many small pieces


def seq_of(raw):
    """The header seq of an undecoded message: the header's seq, secs, nsecs lead the buffer."""
    return struct.unpack_from("<I", raw._buff, 0)[0]


def stamp_of(raw):
    """The header stamp of an undecoded message."""
    _, secs, nsecs = struct.unpack_from("<III", raw._buff, 0)
    return rospy.Time(secs, nsecs)


def decoded_image(raw):
    image = Image()
    image.deserialize(raw._buff)
    return image


class SimCamerasTest(unittest.TestCase):
    def setUp(self):
        self.config_dir = rospy.get_param("~config_dir")
        self.rate = rospy.get_param("~camera_rate_hz")
        self.sim_seconds = rospy.get_param("~sim_seconds")
        self.images = {k: [] for k in CAMERAS}
        self.infos = {k: [] for k in CAMERAS}
        self.truth = {"sim/truth/stereo_left": [], "sim/truth/ir": []}
        self.clock = []
        subs = [rospy.Subscriber("/clock", Clock, lambda m: self.clock.append(m.clock.to_sec()))]
        for base in CAMERAS:
            subs.append(rospy.Subscriber(base + "/image_raw", rospy.AnyMsg, self.images[base].append, queue_size=50,
                                         buff_size=IMAGE_BUFFER_BYTES))
            subs.append(rospy.Subscriber(base + "/camera_info", CameraInfo, self.infos[base].append, queue_size=50))
        for topic in self.truth:
            subs.append(rospy.Subscriber(topic, Odometry, self.truth[topic].append, queue_size=50))
        self.subs = subs

    def wait_for_sim_seconds(self):
        wall_deadline = rospy.get_rostime()  # sim time (use_sim_time); wait on wall time below
        import time
        start_wall = time.time()
        while not rospy.is_shutdown() and time.time() - start_wall < 90.0:
            if self.clock and all(len(v) > 2 for v in self.images.values()):
                first = min(stamp_of(v[0]).to_sec() for v in self.images.values())
                if self.clock[-1] - first > self.sim_seconds:
                    return
            time.sleep(0.1)
        del wall_deadline
        self.fail("the simulator did not publish %s s of images within 90 s wall time (clock: %d msgs)"
                  % (self.sim_seconds, len(self.clock)))

    def test_cameras_rate_info_truth(self):
        self.wait_for_sim_seconds()
        for base, (frame, encoding, calib_file) in CAMERAS.items():
            images = self.images[base]
            stamps = [stamp_of(m).to_sec() for m in images]
            seqs = [seq_of(m) for m in images]
            # Rate in sim time: frames published (seq) over the stamps they cover.
            span = stamps[-1] - stamps[0]
            published = seqs[-1] - seqs[0]
            rate = published / span
            received = len(images) - 1
            print("%s: %d frames published over %.2f s of sim time, %d received" % (base, published, span, received))
            self.assertAlmostEqual(rate, self.rate, delta=0.05 * self.rate, msg="%s rate %.2f Hz" % (base, rate))
            self.assertGreater(received, published // 2, "%s: most frames lost on the way" % base)
            for (a, seq_a), (b, seq_b) in zip(zip(stamps, seqs), zip(stamps[1:], seqs[1:])):
                self.assertGreater(seq_b, seq_a, "%s: frames out of order" % base)
                self.assertAlmostEqual(b - a, (seq_b - seq_a) / self.rate, delta=1e-3,
                                       msg="%s: uneven frame spacing" % base)
            # The newest image whose camera_info has arrived (the info of the very last image may still
            # be on its way: image and info are two topics).
            info_by_stamp = {m.header.stamp: m for m in self.infos[base]}
            paired = [m for m in images if stamp_of(m) in info_by_stamp]
            self.assertGreater(len(paired), len(images) // 2, "%s: most images have no camera_info with their stamp" % base)
            img = decoded_image(paired[-1])
            self.assertEqual(img.encoding, encoding)
            self.assertEqual((img.width, img.height), (640, 480))
            self.assertEqual(img.header.frame_id, frame)
            self.assertEqual(len(img.data), img.step * img.height)
            with open(os.path.join(self.config_dir, calib_file)) as f:
                calib = yaml.safe_load(f)
            info = info_by_stamp[img.header.stamp]
            self.assertEqual(info.header.frame_id, frame)
            self.assertEqual((info.width, info.height), (640, 480))
            self.assertEqual(info.distortion_model, "plumb_bob")
            for got, want in zip(info.K, calib["camera_matrix"]["data"]):
                self.assertAlmostEqual(got, want, places=6)
            for got, want in zip(info.D, calib["distortion_coefficients"]["data"]):
                self.assertAlmostEqual(got, want, places=6)
            for got, want in zip(info.P, calib["projection_matrix"]["data"]):
                self.assertAlmostEqual(got, want, places=6)
            # Not a blank frame: a lit room has texture.
            self.assertGreater(len(set(img.data[::97])), 20, "%s image looks blank" % base)

        # Truth: one message per image stamp, in the camera optical frame (still_3m).
        left_stamps = set(stamp_of(m) for m in self.images["stereo/left"])
        for topic, frame in (("sim/truth/stereo_left", "stereo_left_optical_frame"), ("sim/truth/ir", "ir_optical_frame")):
            msgs = self.truth[topic]
            self.assertTrue(msgs, topic + " silent")
            self.assertEqual(msgs[-1].header.frame_id, frame)
            self.assertEqual(msgs[-1].child_frame_id, "target")
            p = msgs[-1].pose.pose.position
            # Port 3.0 m ahead of base_link, cameras 0.10 m forward of it.
            self.assertAlmostEqual(math.sqrt(p.x ** 2 + p.y ** 2 + p.z ** 2), 2.90, delta=0.01)
            self.assertGreater(p.z, 2.85)  # in front of the camera, along its optical axis
        truth_stamps = set(m.header.stamp for m in self.truth["sim/truth/stereo_left"])
        # The two subscriptions connect at different moments (on a busy machine the truth one can come
        # up several frames after the image one): compare over the span both were connected.
        first, last = min(truth_stamps), max(truth_stamps)
        overlap = {s for s in left_stamps if first <= s <= last}
        self.assertGreater(len(overlap), len(left_stamps) // 2, "truth covers too few of the images")
        missing = sorted(s.to_sec() for s in overlap - truth_stamps)
        self.assertFalse(missing, "images without truth at %s" % missing[:5])


if __name__ == "__main__":
    rospy.init_node("test_sim_cameras")
    rostest.rosrun("docking_sim", "sim_cameras", SimCamerasTest, sys.argv)
