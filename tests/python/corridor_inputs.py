"""The node's inputs the tests and the service benchmark send: a drone in the middle of a corridor
along x, seen by the paper's LiDAR, and its odometry. A plain module (no pytest), so that client
processes such as ``service_clients.py`` build the same messages as the in-process rig."""

from __future__ import annotations

import math

from nav_msgs.msg import Odometry
from sensor_msgs.msg import LaserScan


def corridor_scan(sec: int, width: float = 2.5, beams: int = 180, nanosec: int = 0) -> LaserScan:
    """A 360° scan from the middle of a corridor along x, 3 m range (the paper's LiDAR), stamped
    ``sec.nanosec``."""
    scan = LaserScan()
    scan.header.stamp.sec = sec
    scan.header.stamp.nanosec = nanosec
    scan.header.frame_id = "base_link"
    scan.angle_min = -math.pi
    scan.angle_increment = 2 * math.pi / beams
    scan.angle_max = scan.angle_min + (beams - 1) * scan.angle_increment
    scan.range_min = 0.02
    scan.range_max = 3.0
    ranges = []
    for i in range(beams):
        s = abs(math.sin(scan.angle_min + i * scan.angle_increment))
        r = width / 2 / s if s > 1e-9 else math.inf
        ranges.append(r if r <= scan.range_max else math.inf)
    scan.ranges = ranges
    return scan


def odometry(vx: float = 0.5) -> Odometry:
    """Level, 1 m up, moving along x at ``vx`` m/s."""
    odom = Odometry()
    odom.header.frame_id = "odom"
    odom.child_frame_id = "base_link"
    odom.pose.pose.position.z = 1.0
    odom.pose.pose.orientation.w = 1.0
    odom.twist.twist.linear.x = vx
    return odom
