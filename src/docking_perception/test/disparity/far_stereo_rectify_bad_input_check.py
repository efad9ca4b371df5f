#!/usr/bin/env python3
"""far_stereo_rectify drops bad pairs with a reason and keeps rectifying good ones (issue 15).

The check publishes left and right image_mono with camera_info_checked at matching stamps, as the image
guards do, and reads stereo/far/full/{left,right}/image_rect and /diagnostics ("far stereo rectify").
Wall-clock stamps (no /clock here). Each case sends pairs until the node has answered it: an output
at the pair's stamp (good) or a higher drop count (bad).
"""
import threading
import time
import unittest

import numpy as np
import rospy
import rostest
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from sensor_msgs.msg import CameraInfo, Image

PKG = "docking_perception"
STATUS = "far stereo rectify"
WIDTH, HEIGHT, FOCAL, BASELINE = 640, 480, 550.0, 0.10


def camera_info(stamp, right, binning=1, calibrated=True):
    info = CameraInfo()
    info.header.stamp, info.header.frame_id = stamp, "stereo_left_optical_frame"
    info.width, info.height = WIDTH, HEIGHT
    info.distortion_model, info.D = "plumb_bob", [0.0] * 5
    f = FOCAL if calibrated else 0.0
    info.K = [f, 0.0, 319.5, 0.0, f, 239.5, 0.0, 0.0, 1.0]
    info.R = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]
    info.P = [f, 0.0, 319.5, -f * BASELINE if right else 0.0, 0.0, f, 239.5, 0.0, 0.0, 0.0, 1.0, 0.0]
    info.binning_x = info.binning_y = binning
    return info


def image(stamp, encoding="mono8"):
    channels = 3 if encoding == "rgb8" else 1
    rng = np.random.default_rng(int(stamp.to_nsec()) % 1000)
    pixels = rng.integers(0, 255, size=(HEIGHT, WIDTH * channels), dtype=np.uint8)
    msg = Image()
    msg.header.stamp, msg.header.frame_id = stamp, "stereo_left_optical_frame"
    msg.height, msg.width, msg.encoding, msg.step = HEIGHT, WIDTH, encoding, WIDTH * channels
    msg.data = pixels.tobytes()
    return msg


class FarStereoRectifyBadInput(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("far_stereo_rectify_bad_input_check")

    def setUp(self):
        self.lock = threading.Lock()
        self.rectified = {"left": [], "right": []}  # (stamp ns, width, height, encoding)
        self.status = None  # (level, message, values)
        for side in ("left", "right"):
            rospy.Subscriber(f"stereo/far/full/{side}/image_rect", Image, self.on_rectified, callback_args=side,
                             queue_size=10)
        rospy.Subscriber("/diagnostics", DiagnosticArray, self.on_diagnostics, queue_size=50)
        self.publishers = {
            "left_image": rospy.Publisher("stereo/left/image_mono", Image, queue_size=5),
            "left_info": rospy.Publisher("stereo/left/camera_info_checked", CameraInfo, queue_size=5),
            "right_image": rospy.Publisher("stereo/right/image_mono", Image, queue_size=5),
            "right_info": rospy.Publisher("stereo/right/camera_info_checked", CameraInfo, queue_size=5),
        }
        self.deadline = time.monotonic() + rospy.get_param("~timeout_s", 60.0)

    def on_rectified(self, msg, side):
        with self.lock:
            self.rectified[side].append((msg.header.stamp.to_nsec(), msg.width, msg.height, msg.encoding))

    def on_diagnostics(self, msg):
        for status in msg.status:
            if STATUS in status.name:
                with self.lock:
                    self.status = (status.level, status.message, {kv.key: kv.value for kv in status.values})

    def latest_status(self):
        with self.lock:
            return self.status

    def dropped(self):
        status = self.latest_status()
        return int(status[2]["pairs dropped"]) if status and "pairs dropped" in status[2] else 0

    def send_pair(self, encoding="mono8", binning=1, calibrated=True):
        stamp = rospy.Time.now()
        self.publishers["left_info"].publish(camera_info(stamp, False, binning, calibrated))
        self.publishers["right_info"].publish(camera_info(stamp, True, binning, calibrated))
        self.publishers["left_image"].publish(image(stamp, encoding))
        self.publishers["right_image"].publish(image(stamp))
        return stamp.to_nsec()

    def stamps_out(self, side="left"):
        with self.lock:
            return {row[0] for row in self.rectified[side]}

    def wait_until(self, what, predicate, send=None):
        while time.monotonic() < self.deadline and not rospy.is_shutdown():
            if send is not None:
                send()
            if predicate():
                return
            time.sleep(0.2)
        self.fail(f"timed out waiting until {what} (last status: {self.latest_status()})")

    def expect_good_pairs_rectified(self):
        sent = []
        self.wait_until("a good pair comes out rectified on both sides",
                        lambda: any(s in self.stamps_out("left") and s in self.stamps_out("right") for s in sent),
                        send=lambda: sent.append(self.send_pair()))
        with self.lock:
            row = self.rectified["left"][-1]
        self.assertEqual((row[1], row[2], row[3]), (WIDTH, HEIGHT, "mono8"))

    def expect_dropped(self, what, reason_part, **bad):
        before = self.dropped()
        sent = []
        # Sent until the status names this case's reason (a pair of the case before may be dropped first).
        self.wait_until(f"a pair with {what} is dropped and the status says why",
                        lambda: self.dropped() > before and reason_part in self.latest_status()[1],
                        send=lambda: sent.append(self.send_pair(**bad)))
        level, message, values = self.latest_status()
        self.assertEqual(level, DiagnosticStatus.WARN, message)
        self.assertIn(reason_part, values["last drop reason"])
        self.assertFalse(set(sent) & self.stamps_out("left"), f"a pair with {what} was published")
        self.assertFalse(set(sent) & self.stamps_out("right"), f"a pair with {what} was published")

    def test_bad_pairs_are_dropped_with_a_reason_and_good_ones_still_pass(self):
        self.wait_until("the node subscribes to the cameras",
                        lambda: self.publishers["left_image"].get_num_connections() > 0 and
                        self.publishers["right_info"].get_num_connections() > 0)
        self.expect_good_pairs_rectified()
        self.expect_dropped("a colour image", "encoding must be mono8", encoding="rgb8")
        self.expect_dropped("a binned camera_info", "already binned", binning=2)
        self.expect_dropped("an uncalibrated camera_info", "positive focal lengths", calibrated=False)
        self.expect_good_pairs_rectified()
        self.wait_until("the status is OK again",
                        lambda: self.latest_status()[0] == DiagnosticStatus.OK,
                        send=self.send_pair)


if __name__ == "__main__":
    rostest.rosrun(PKG, "far_stereo_rectify_bad_input", FarStereoRectifyBadInput)
