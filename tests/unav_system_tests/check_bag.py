#!/usr/bin/env python3
"""Reads a bag recorded by `unav bag record` with the readers nobody here wrote and checks it.

Usage: check_bag.py BAG_DIR TOPIC:MIN_COUNT...
Every listed topic must hold at least MIN_COUNT messages; every message of every topic must
decode with the schema in the bag (MCAP: rosbags from the ros2msg schema and mcap-ros2-support;
sqlite3: rosbags with the Humble type store); counts must equal metadata.yaml. Prints
"<topic> <count>" per topic, then the first and last x of the ground-truth odometry.
"""
import os
import sys

import yaml
from rosbags.rosbag2 import Reader
from rosbags.typesys import Stores, get_typestore, get_types_from_msg


def main():
    bag = sys.argv[1]
    wants = {t.rsplit(":", 1)[0]: int(t.rsplit(":", 1)[1]) for t in sys.argv[2:]}
    with open(os.path.join(bag, "metadata.yaml")) as f:
        meta = yaml.safe_load(f)["rosbag2_bagfile_information"]
    meta_counts = {t["topic_metadata"]["name"]: t["message_count"] for t in meta["topics_with_message_count"]}
    typestore = get_typestore(Stores.ROS2_HUMBLE)
    counts = {}
    xs = []
    with Reader(bag) as reader:
        if meta["storage_identifier"] == "mcap":
            for c in reader.connections:
                assert c.msgdef.data, f"{c.topic}: no schema in the MCAP"
                typestore.register(get_types_from_msg(c.msgdef.data, c.msgtype))
        for conn, _, raw in reader.messages():
            if conn.msgtype not in typestore.types:
                continue  # sqlite3 without a definition for a custom type
            msg = typestore.deserialize_cdr(raw, conn.msgtype)
            counts[conn.topic] = counts.get(conn.topic, 0) + 1
            if conn.topic == "/tf":
                assert msg.transforms, "empty /tf message"
            if conn.msgtype == "nav_msgs/msg/Odometry" and "ground_truth" in conn.topic:
                xs.append(msg.pose.pose.position.x)
    for topic, n in sorted(counts.items()):
        print(topic, n)
        assert meta_counts.get(topic) == n, f"{topic}: {n} decoded, metadata.yaml says {meta_counts.get(topic)}"
    for topic, n in wants.items():
        assert counts.get(topic, 0) >= n, f"{topic}: {counts.get(topic, 0)} messages, expected >= {n}"
    if meta["storage_identifier"] == "mcap":
        from mcap.reader import make_reader
        from mcap_ros2.decoder import DecoderFactory
        (path,) = [os.path.join(bag, f) for f in os.listdir(bag) if f.endswith(".mcap")]
        with open(path, "rb") as f:
            n = sum(1 for _ in make_reader(f, validate_crcs=True, decoder_factories=[DecoderFactory()])
                    .iter_decoded_messages())
        assert n == meta["message_count"], f"mcap-ros2 decoded {n} of {meta['message_count']}"
    if xs:
        print("odom_x", xs[0], xs[-1])


if __name__ == "__main__":
    main()
