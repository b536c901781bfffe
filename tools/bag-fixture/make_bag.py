#!/usr/bin/env python3
"""Dev-only fixture generator: writes a prf dataset as a ROS 2 bag, the way rosbag2 records one.

An independent writer for `prf import-bag`'s tests: Foxglove's Python `mcap` and
`mcap-ros2-support` packages serialise the messages (CDR) from the ROS 2 message definitions
below, so the project's reader is checked against someone else's encoder.

    make_bag.py DATASET_DIR OUT_DIR

writes OUT_DIR/bag.mcap and OUT_DIR/tasks.yaml:

- /joint_states  sensor_msgs/msg/JointState, one per trajectory row: the arm joints in a
  shuffled order, and the gripper as a finger joint (0.04 m open, 0 closed);
- /odom          nav_msgs/msg/Odometry, every other row (50 Hz), frame map → base_footprint;
- /tf            tf2_msgs/msg/TFMessage, every row: map → base_footprint and an unrelated
  base_footprint → laser;
- programs back to back with 2 s of silence between them, stamps from 1.7e9 s.
"""

import csv
import json
import math
import sys
from pathlib import Path

import yaml
from mcap_ros2.writer import Writer

SEP = "=" * 80 + "\n"
TIME = "MSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec\n"
HEADER = "MSG: std_msgs/Header\nbuiltin_interfaces/Time stamp\nstring frame_id\n"
VECTOR3 = "MSG: geometry_msgs/Vector3\nfloat64 x\nfloat64 y\nfloat64 z\n"
POINT = "MSG: geometry_msgs/Point\nfloat64 x\nfloat64 y\nfloat64 z\n"
QUATERNION = "MSG: geometry_msgs/Quaternion\nfloat64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1\n"


def msgdef(main, *deps):
    return main + "".join(SEP + d for d in deps)


JOINT_STATE = msgdef(
    "std_msgs/Header header\nstring[] name\nfloat64[] position\nfloat64[] velocity\nfloat64[] effort\n",
    HEADER,
    TIME,
)
ODOMETRY = msgdef(
    "std_msgs/Header header\nstring child_frame_id\ngeometry_msgs/PoseWithCovariance pose\n"
    "geometry_msgs/TwistWithCovariance twist\n",
    HEADER,
    TIME,
    "MSG: geometry_msgs/PoseWithCovariance\nPose pose\nfloat64[36] covariance\n",
    "MSG: geometry_msgs/Pose\nPoint position\nQuaternion orientation\n",
    POINT,
    QUATERNION,
    "MSG: geometry_msgs/TwistWithCovariance\nTwist twist\nfloat64[36] covariance\n",
    "MSG: geometry_msgs/Twist\nVector3 linear\nVector3 angular\n",
    VECTOR3,
)
TF_MESSAGE = msgdef(
    "geometry_msgs/TransformStamped[] transforms\n",
    "MSG: geometry_msgs/TransformStamped\nstd_msgs/Header header\nstring child_frame_id\n"
    "Transform transform\n",
    HEADER,
    TIME,
    "MSG: geometry_msgs/Transform\nVector3 translation\nQuaternion rotation\n",
    VECTOR3,
    QUATERNION,
)

ARM = [f"iiwa_joint_{i}" for i in range(1, 8)]
# The order the joint states list them in: not the robot's.
ORDER = ["iiwa_joint_3", "gripper_finger_joint", "iiwa_joint_7", "iiwa_joint_1", "iiwa_joint_5",
         "iiwa_joint_2", "iiwa_joint_6", "iiwa_joint_4"]
OPEN, CLOSED = 0.04, 0.0
ORIGIN_NS = 1_700_000_000 * 10**9
GAP_NS = 2 * 10**9


def stamp(ns):
    return {"sec": ns // 10**9, "nanosec": ns % 10**9}


def yaw_quaternion(yaw):
    return {"x": 0.0, "y": 0.0, "z": math.sin(yaw / 2), "w": math.cos(yaw / 2)}


def main(dataset, out):
    manifest = json.loads((dataset / "manifest.json").read_text())
    out.mkdir(parents=True, exist_ok=True)
    programs = []
    with open(out / "bag.mcap", "wb") as f:
        w = Writer(f)
        js_schema = w.register_msgdef("sensor_msgs/msg/JointState", JOINT_STATE)
        odom_schema = w.register_msgdef("nav_msgs/msg/Odometry", ODOMETRY)
        tf_schema = w.register_msgdef("tf2_msgs/msg/TFMessage", TF_MESSAGE)
        offset = ORIGIN_NS
        for entry in manifest["demonstrations"]:
            rows = list(csv.DictReader(open(dataset / entry["trajectory"])))
            task = json.loads((dataset / entry["task"]).read_text())
            for k, r in enumerate(rows):
                t = offset + round(float(r["t"]) * 1e9)
                g = float(r["gripper"])
                pos = {a: float(r[f"a{i + 1}"]) for i, a in enumerate(ARM)}
                pos["gripper_finger_joint"] = OPEN + g * (CLOSED - OPEN)
                header = {"stamp": stamp(t), "frame_id": ""}
                w.write_message(
                    "/joint_states", js_schema,
                    {"header": header, "name": ORDER, "position": [pos[n] for n in ORDER],
                     "velocity": [], "effort": []},
                    log_time=t, publish_time=t)
                x, y, yaw = float(r["base_x"]), float(r["base_y"]), float(r["base_yaw"])
                base = {"translation": {"x": x, "y": y, "z": 0.0}, "rotation": yaw_quaternion(yaw)}
                laser = {"translation": {"x": 0.3, "y": 0.0, "z": 0.2},
                         "rotation": yaw_quaternion(0.0)}
                w.write_message(
                    "/tf", tf_schema,
                    {"transforms": [
                        {"header": {"stamp": stamp(t), "frame_id": "base_footprint"},
                         "child_frame_id": "laser", "transform": laser},
                        {"header": {"stamp": stamp(t), "frame_id": "map"},
                         "child_frame_id": "base_footprint", "transform": base}]},
                    log_time=t, publish_time=t)
                if k % 2 == 0 or k == len(rows) - 1:
                    zero = {"x": 0.0, "y": 0.0, "z": 0.0}
                    w.write_message(
                        "/odom", odom_schema,
                        {"header": {"stamp": stamp(t), "frame_id": "map"},
                         "child_frame_id": "base_footprint",
                         "pose": {"pose": {"position": {"x": x, "y": y, "z": 0.0},
                                           "orientation": yaw_quaternion(yaw)},
                                  "covariance": [0.0] * 36},
                         "twist": {"twist": {"linear": zero, "angular": zero},
                                   "covariance": [0.0] * 36}},
                        log_time=t, publish_time=t)
            end = offset + round(float(rows[-1]["t"]) * 1e9)
            programs.append({"id": entry["id"], "start": (offset - ORIGIN_NS) / 1e9,
                             "end": (end - ORIGIN_NS) / 1e9, "task": task})
            offset = end + GAP_NS
        w.finish()
    annotation = {
        "robot": manifest["robot"],
        "clearance_demo_m": manifest["clearance_demo_m"],
        "gripper": {"joint": "gripper_finger_joint", "open": OPEN, "closed": CLOSED},
        "parts": manifest["parts"],
        "locations": manifest["locations"],
        "programs": programs,
    }
    (out / "tasks.yaml").write_text(yaml.safe_dump(annotation, sort_keys=False))


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    main(Path(sys.argv[1]), Path(sys.argv[2]))
