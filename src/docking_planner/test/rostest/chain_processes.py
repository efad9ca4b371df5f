"""Shared by the fault rostests (supervision_check.py, message_fuzz_check.py): which process runs a node."""
import xmlrpc.client

import rosgraph
import rosnode
import rospy


def pid_of(node_name):
    """The pid of a running node (by its XML-RPC API), or None when it does not answer."""
    caller = rospy.get_name()
    try:
        uri = rosnode.get_api_uri(rosgraph.Master(caller), node_name, skip_cache=True)
        if not uri:
            return None
        code, _, pid = xmlrpc.client.ServerProxy(uri).getPid(caller)
        return pid if code == 1 else None
    except (OSError, xmlrpc.client.Error, rosnode.ROSNodeIOException):
        return None
