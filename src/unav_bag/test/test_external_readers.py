"""Bags written by unav_bag, read back by readers nobody here wrote: rosbags (both storages) and
mcap + mcap-ros2-support (MCAP, with CRC validation and ros2msg schema decoding, as Foxglove
decodes it). The fixture (make_fixture_bags.cpp) stamps message i at START + i*100 ms (+ k ns
for the k-th topic) and puts i into a field of every message."""
import os
import subprocess
import tempfile

import pytest

from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory
from rosbags.rosbag2 import Reader
from rosbags.typesys import Stores, get_typestore, get_types_from_msg

START = 1764000000000000000
COUNT = 10
TOPICS = {
    "/tf": "tf2_msgs/msg/TFMessage",
    "/rov/odom": "nav_msgs/msg/Odometry",
    "/rov/dvl": "unav_msgs/msg/Dvl",
    "/rov/range": "sensor_msgs/msg/Range",
    "/rov/camera/image": "sensor_msgs/msg/Image",
}


@pytest.fixture(scope="module")
def bags():
    out = tempfile.mkdtemp(prefix="unav_bags_")
    subprocess.run([os.environ["UNAV_FIXTURE_BAGS"], out], check=True)
    return out


def check_message(topic, i, msg):
    """The field the fixture set from i, per topic."""
    if topic == "/tf":
        assert len(msg.transforms) == 1
        tr = msg.transforms[0]
        assert tr.header.frame_id == "map" and tr.child_frame_id == "base_link"
        assert tr.transform.translation.x == float(i)
        assert tr.transform.translation.z == -3.0
        assert tr.transform.rotation.w == 1.0
    elif topic == "/rov/odom":
        assert msg.pose.pose.position.x == 0.5 * i
        assert msg.twist.twist.linear.x == 0.25
        assert len(msg.pose.covariance) == 36
    elif topic == "/rov/dvl":
        assert msg.velocity.x == pytest.approx(0.1 * i, abs=1e-15)
        assert msg.altitude == 2.5 and msg.valid
        assert len(msg.velocity_covariance) == 9
    elif topic == "/rov/range":
        assert msg.radiation_type == 1 and msg.range == 1.5
    elif topic == "/rov/camera/image":
        assert (msg.width, msg.height, msg.encoding, msg.step) == (640, 480, "rgb8", 1920)
        data = bytes(msg.data)
        assert len(data) == 640 * 480 * 3
        assert data[0] == i % 251 and data[1000] == (1000 + i) % 251
    stamp = msg.transforms[0].header.stamp if topic == "/tf" else msg.header.stamp
    assert stamp.sec * 10**9 + stamp.nanosec == START + i * 100_000_000


def topic_index(topic):
    return list(TOPICS).index(topic)


@pytest.mark.parametrize("name", ["mcap", "mcap_zstd", "sqlite3"])
def test_rosbags_reads_every_message(bags, name):
    path = os.path.join(bags, name)
    with Reader(path) as reader:
        assert {c.topic: c.msgtype for c in reader.connections} == TOPICS
        assert reader.message_count == COUNT * len(TOPICS)
        assert reader.start_time == START
        # rosbags reports end = last timestamp + 1 ns.
        assert reader.duration == (COUNT - 1) * 100_000_000 + len(TOPICS) - 1 + 1
        typestore = get_typestore(Stores.ROS2_HUMBLE)
        if name.startswith("mcap"):
            # The schemas in the file are enough: register every type from them.
            for c in reader.connections:
                assert c.msgdef.format.name == "MSG"
                typestore.register(get_types_from_msg(c.msgdef.data, c.msgtype))
        else:
            # sqlite3 (Humble) stores no definitions: the custom type comes from its .msg text.
            with Reader(os.path.join(bags, "mcap")) as m:
                dvl = next(c for c in m.connections if c.topic == "/rov/dvl")
                typestore.register(get_types_from_msg(dvl.msgdef.data, dvl.msgtype))
        for c in reader.connections:
            assert c.msgcount == COUNT
            qos = c.ext.offered_qos_profiles
            assert len(qos) == 1
            assert qos[0].durability.name == ("TRANSIENT_LOCAL" if c.topic == "/rov/range" else "VOLATILE")
            assert qos[0].reliability.name == "RELIABLE"
        seen = {t: 0 for t in TOPICS}
        for conn, timestamp, raw in reader.messages():
            i = seen[conn.topic]
            assert timestamp == START + i * 100_000_000 + topic_index(conn.topic)
            check_message(conn.topic, i, typestore.deserialize_cdr(raw, conn.msgtype))
            seen[conn.topic] += 1
        assert all(n == COUNT for n in seen.values())


@pytest.mark.parametrize("name", ["mcap", "mcap_zstd"])
def test_mcap_ros2_decodes_with_crc_and_summary(bags, name):
    (path,) = [os.path.join(bags, name, f) for f in os.listdir(os.path.join(bags, name)) if f.endswith(".mcap")]
    with open(path, "rb") as f:
        reader = make_reader(f, validate_crcs=True, decoder_factories=[DecoderFactory()])
        header = reader.get_header()
        assert header.profile == "ros2"
        summary = reader.get_summary()
        assert summary.statistics.message_count == COUNT * len(TOPICS)
        assert summary.statistics.message_start_time == START
        assert len(summary.chunk_indexes) > 1
        assert {c.topic: summary.schemas[c.schema_id].name for c in summary.channels.values()} == TOPICS
        assert all(s.encoding == "ros2msg" for s in summary.schemas.values())
        assert all(c.message_encoding == "cdr" for c in summary.channels.values())
        assert all("offered_qos_profiles" in c.metadata for c in summary.channels.values())
        seen = {t: 0 for t in TOPICS}
        for schema, channel, message, msg in reader.iter_decoded_messages(log_time_order=True):
            i = seen[channel.topic]
            assert message.log_time == START + i * 100_000_000 + topic_index(channel.topic)
            check_message(channel.topic, i, msg)
            seen[channel.topic] += 1
        assert all(n == COUNT for n in seen.values())
    # A reader that does not use the index (streaming, as over a pipe) sees the same messages.
    with open(path, "rb") as f:
        from mcap.stream_reader import StreamReader
        from mcap.records import Message
        n = sum(1 for r in StreamReader(f, validate_crcs=True).records if isinstance(r, Message))
        assert n == COUNT * len(TOPICS)


def test_metadata_yaml_matches_storage(bags):
    import yaml
    for name in ("mcap", "sqlite3"):
        with open(os.path.join(bags, name, "metadata.yaml")) as f:
            meta = yaml.safe_load(f)["rosbag2_bagfile_information"]
        assert meta["version"] == 5
        assert meta["storage_identifier"] == name
        assert meta["message_count"] == COUNT * len(TOPICS)
        assert meta["starting_time"]["nanoseconds_since_epoch"] == START
        assert meta["relative_file_paths"] == [f"{name}_0." + ("mcap" if name == "mcap" else "db3")]
        assert {t["topic_metadata"]["name"]: t["message_count"] for t in meta["topics_with_message_count"]} == {
            t: COUNT for t in TOPICS}


def test_every_interface_type_decodes(bags):
    """all_types: every message type of interfaces/ (one topic each, fields at their defaults),
    decoded by mcap-ros2-support from the file's own schemas and by rosbags from the same
    schemas (the dependency names must resolve: `MSG: std_msgs/Header`, as rosbag2 writes)."""
    (path,) = [os.path.join(bags, "all_types", f) for f in os.listdir(os.path.join(bags, "all_types"))
               if f.endswith(".mcap")]
    with open(path, "rb") as f:
        reader = make_reader(f, validate_crcs=True, decoder_factories=[DecoderFactory()])
        summary = reader.get_summary()
        types = {summary.schemas[c.schema_id].name for c in summary.channels.values()}
        assert len(types) >= 40 and "unav_msgs/msg/Dvl" in types and "nav_msgs/msg/Odometry" in types
        for schema in summary.schemas.values():
            assert "/msg/" not in schema.data.decode().split("MSG: ", 1)[-1].split("\n", 1)[0]
        decoded = sum(1 for _ in reader.iter_decoded_messages())
        assert decoded == 2 * len(summary.channels)
    typestore = get_typestore(Stores.EMPTY)
    with Reader(os.path.join(bags, "all_types")) as reader:
        for c in reader.connections:
            typestore.register(get_types_from_msg(c.msgdef.data, c.msgtype))
        for conn, _, raw in reader.messages():
            typestore.deserialize_cdr(raw, conn.msgtype)
