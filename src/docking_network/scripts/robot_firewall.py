#!/usr/bin/env python3
"""The robot's firewall: only the robot's own computers reach ROS_IP.

ROS 1 has no authentication: whoever reaches a node's ports can stop it (XML-RPC `shutdown`), feed it
(`publisherUpdate`, `cmd_vel`) or change its parameters. The bind guard (libdocking_bind_ros_ip, preloaded
by devel/setup.bash) puts every ROS server socket on ROS_IP alone, but any host that can route packets
to ROS_IP still reaches it: a guest on the robot network, or a host on another network of the robot
(Linux accepts a packet for any of its addresses on any interface). This rule set (nftables, table
`inet docking_ros`) drops every new connection to ROS_IP whose source is not in the allow list; replies
to connections the robot opens are kept.

    sudo rosrun docking_network robot_firewall.py --allow 10.42.0.2            # the laptop; apply
    sudo rosrun docking_network robot_firewall.py --allow 10.42.0.2 --print    # show, apply nothing
    sudo rosrun docking_network robot_firewall.py --remove
ROS_IP (or --ros-ip) is the robot's own address on the robot network; it is always allowed.
"""
import argparse
import ipaddress
import os
import subprocess
import sys

TABLE = "docking_ros"


def ruleset(ros_ip, allowed):
    family = "ip" if ros_ip.version == 4 else "ip6"
    sources = ", ".join(sorted({str(ros_ip)} | {str(a) for a in allowed}))
    return (
        f"table inet {TABLE} {{\n"
        f"  chain input {{\n"
        f"    type filter hook input priority filter; policy accept;\n"
        f"    ct state established,related accept\n"
        f"    {family} daddr {ros_ip} {family} saddr != {{ {sources} }} drop\n"
        f"  }}\n"
        f"}}\n")


def run_nft(script):
    done = subprocess.run(["nft", "-f", "-"], input=script, text=True, capture_output=True)
    if done.returncode != 0:
        sys.exit("robot_firewall: nft refused the rules: %s" % done.stderr.strip())


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--allow", action="append", default=[], metavar="ADDRESS",
                        help="a computer of the robot that may reach ROS_IP (repeat for each)")
    parser.add_argument("--ros-ip", default=os.environ.get("ROS_IP", ""), help="the robot's address (default: ROS_IP)")
    parser.add_argument("--print", action="store_true", help="print the rule set; apply nothing")
    parser.add_argument("--remove", action="store_true", help="remove the rule set")
    args = parser.parse_args()
    if args.remove:
        subprocess.run(["nft", "delete", "table", "inet", TABLE], capture_output=True)
        return
    try:
        ros_ip = ipaddress.ip_address(args.ros_ip)
        allowed = [ipaddress.ip_address(a) for a in args.allow]
    except ValueError as error:
        sys.exit("robot_firewall: %s (ROS_IP or --ros-ip must be the robot's IP address)" % error)
    if ros_ip.is_loopback:
        sys.exit("robot_firewall: ROS_IP %s is a loopback address: no other host reaches it, nothing to do" % ros_ip)
    if any(a.version != ros_ip.version for a in allowed):
        sys.exit("robot_firewall: the allowed addresses must be of ROS_IP's family (IPv%d)" % ros_ip.version)
    rules = ruleset(ros_ip, allowed)
    if args.print:
        print(rules, end="")
        return
    # Replace, never stack: the table is deleted (if there) and written again in one transaction.
    run_nft(f"table inet {TABLE}\ndelete table inet {TABLE}\n" + rules)
    print("robot_firewall: only %s reach %s" % (", ".join(str(a) for a in [ros_ip] + allowed), ros_ip))


if __name__ == "__main__":
    main()
