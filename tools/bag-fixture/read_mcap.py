#!/usr/bin/env python3
"""Dev-only reader: decodes every message of a ROS 2 bag (MCAP) with Foxglove's Python `mcap`
and `mcap-ros2-support`, from the schemas stored in the file, and prints a JSON summary for
`prf export-mcap`'s tests: per topic its schema and message count, the first and last joint
state, the robot description, the number of points per point cloud and markers per array,
and the risk range.

    read_mcap.py BAG.mcap
"""

import json
import sys

from mcap_ros2.reader import read_ros2_messages


def main(path):
    topics = {}
    out = {"topics": topics, "clouds": {}, "markers": {}}
    for m in read_ros2_messages(path):
        topic, msg = m.channel.topic, m.ros_msg
        t = topics.setdefault(topic, {"schema": m.schema.name, "count": 0})
        t["count"] += 1
        if topic == "/robot_description":
            out["robot_description"] = msg.data
        elif topic == "/joint_states":
            state = {"name": list(msg.name), "position": list(msg.position),
                     "stamp": msg.header.stamp.sec * 10**9 + msg.header.stamp.nanosec}
            out.setdefault("first_joint_state", state)
            out["last_joint_state"] = state
        elif topic.startswith("/prf/workspace/"):
            names = [f.name for f in msg.fields]
            out["clouds"][topic] = {"frame": msg.header.frame_id, "points": msg.width,
                                    "fields": names, "bytes": len(msg.data)}
        elif schema_is(m, "visualization_msgs/msg/MarkerArray"):
            out["markers"][topic] = len(msg.markers)
        elif topic == "/prf/risk":
            lo, hi = out.get("risk", [msg.data, msg.data])
            out["risk"] = [min(lo, msg.data), max(hi, msg.data)]
    json.dump(out, sys.stdout)


def schema_is(m, name):
    return m.schema.name == name


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    main(sys.argv[1])
