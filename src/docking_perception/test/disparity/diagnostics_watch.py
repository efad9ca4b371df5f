"""What the disparity-stage rostests share (issue 15): the latest status of one diagnostics entry, waits
on it with a deadline, and the PID of a node (to kill it; roslaunch respawns it)."""
import threading
import time
import xmlrpc.client

import rosgraph
import rosnode
import rospy
from diagnostic_msgs.msg import DiagnosticArray


def pid_of(caller, node):
    uri = rosnode.get_api_uri(rosgraph.Master(caller), node)
    return xmlrpc.client.ServerProxy(uri).getPid(caller)[2]


class StatusWatch:
    """The latest reading of the /diagnostics entry whose name contains `name_part`: `read(values, msg)`
    turns its key/value dict into a reading, or None when the keys it needs are not there."""

    def __init__(self, name_part, read, timeout_s):
        self.name_part, self.read = name_part, read
        self.lock = threading.Lock()
        self.reading = None
        self.deadline = time.monotonic() + timeout_s
        rospy.Subscriber("/diagnostics", DiagnosticArray, self.on_diagnostics, queue_size=50)

    def on_diagnostics(self, msg):
        for status in msg.status:
            if self.name_part in status.name:
                reading = self.read({kv.key: kv.value for kv in status.values}, msg)
                if reading is not None:
                    with self.lock:
                        self.reading = reading

    def latest(self):
        with self.lock:
            return self.reading

    def wait_for(self, what, predicate):
        """The first reading that satisfies predicate; None on timeout (the caller fails with `what`)."""
        while time.monotonic() < self.deadline and not rospy.is_shutdown():
            reading = self.latest()
            if reading is not None and predicate(reading):
                return reading
            time.sleep(0.2)
        return None
