"""Faults inside a ROS bag that a reader must not pass over: wrenches that change frame, a /tf tree that does not
hold together over time (a stopped transform, two parents, a zero quaternion), joint states of several groups on
one topic; and the advice given about them (never an option that ends in the same failure).

Each bag is written message by message with ``rosbags`` (a real rosbag2 sqlite3 file), so a fault sits exactly
where a robot's recorder would put it.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from ftcal.core import LogFormatError
from ftcal.io._bags import read_bag

pytest.importorskip("rosbags")

T0 = 1.7e9  # a ROS clock [s]


class _Bag:
    """Messages of a rosbag2 bag, added one by one and written at once (ROS 2 Humble message types)."""

    def __init__(self) -> None:
        from rosbags.typesys import Stores, get_typestore

        self.store = get_typestore(Stores.ROS2_HUMBLE)
        self.T = self.store.types
        self.messages: list[tuple[str, str, float, object]] = []

    def header(self, t: float, frame: str = ""):
        sec = math.floor(t)
        return self.T["std_msgs/msg/Header"](stamp=self.T["builtin_interfaces/msg/Time"](
            sec=int(sec), nanosec=int(round((t - sec) * 1e9)) % 1_000_000_000), frame_id=frame)

    def wrench(self, t: float, value, frame: str = "ft_sensor", topic: str = "/ft_sensor/wrench") -> None:
        V, W = self.T["geometry_msgs/msg/Vector3"], self.T["geometry_msgs/msg/Wrench"]
        f = [float(v) for v in value]
        msg = self.T["geometry_msgs/msg/WrenchStamped"](header=self.header(t, frame), wrench=W(
            force=V(x=f[0], y=f[1], z=f[2]), torque=V(x=f[3], y=f[4], z=f[5])))
        self.messages.append((topic, "geometry_msgs/msg/WrenchStamped", t + 0.001, msg))

    def joints(self, t: float, names, position, topic: str = "/joint_states") -> None:
        msg = self.T["sensor_msgs/msg/JointState"](header=self.header(t), name=list(names),
                                                   position=np.asarray(position, dtype=float),
                                                   velocity=np.zeros(0), effort=np.zeros(0))
        self.messages.append((topic, "sensor_msgs/msg/JointState", t + 0.001, msg))

    def tf(self, t: float, edges, topic: str = "/tf") -> None:
        """``edges``: (parent, child, quaternion x, y, z, w) each."""
        T = self.T
        transforms = [T["geometry_msgs/msg/TransformStamped"](
            header=self.header(t, parent), child_frame_id=child, transform=T["geometry_msgs/msg/Transform"](
                translation=T["geometry_msgs/msg/Vector3"](x=0.0, y=0.0, z=0.0),
                rotation=T["geometry_msgs/msg/Quaternion"](x=float(q[0]), y=float(q[1]), z=float(q[2]),
                                                           w=float(q[3]))))
            for parent, child, q in edges]
        self.messages.append((topic, "tf2_msgs/msg/TFMessage", t + 0.001, T["tf2_msgs/msg/TFMessage"](
            transforms=transforms)))

    def write(self, path):
        from rosbags.rosbag2 import StoragePlugin, Writer

        with Writer(path, version=9, storage_plugin=StoragePlugin.SQLITE3) as writer:
            connections = {}
            for topic, typ, t, msg in sorted(self.messages, key=lambda m: m[2]):
                if topic not in connections:
                    connections[topic] = writer.add_connection(topic, typ, typestore=self.store)
                writer.write(connections[topic], int(round(t * 1e9)), bytes(self.store.serialize_cdr(msg, typ)))
        return path


UNIT = (0.0, 0.0, 0.0, 1.0)
TURN = (0.0, 0.0, math.sin(math.pi / 4), math.cos(math.pi / 4))  # 90 deg about z
WRENCH = np.array([1.0, 2.0, 3.0, 0.1, 0.2, 0.3])


def _wrenches(bag: _Bag, start: float, stop: float, rate: float = 100.0, **kwargs) -> None:
    for t in np.arange(start, stop, 1.0 / rate):
        bag.wrench(T0 + t, WRENCH, **kwargs)


def test_wrenches_that_change_frame_half_way_are_refused_naming_both_frames_and_the_time(tmp_path):
    bag = _Bag()
    _wrenches(bag, 0.0, 1.0, frame="ft_sensor")
    _wrenches(bag, 1.0, 2.0, frame="tool0")
    for t in np.arange(0.0, 2.0, 0.02):
        bag.joints(T0 + t, ["j1", "j2"], [t, -t])
    path = bag.write(tmp_path / "mixed")
    with pytest.raises(LogFormatError, match=r"change frame at 1700000001\.000 s, from 'ft_sensor' to 'tool0'"):
        read_bag(path)
    one = _Bag()  # the same recording in one frame is read whole
    _wrenches(one, 0.0, 2.0, frame="ft_sensor")
    for t in np.arange(0.0, 2.0, 0.02):
        one.joints(T0 + t, ["j1", "j2"], [t, -t])
    rec = read_bag(one.write(tmp_path / "one"))
    assert rec.frame_id == "ft_sensor" and len(rec.time) == 199  # 0 to 1.98 s (the joints) at 100 Hz


def _tf_bag(tmp_path, name, *, sensor_edge_until: float, extra=()):
    """base_link -> flange (dynamic, 0-10 s), flange -> ft_sensor (dynamic, 90 deg, until ``sensor_edge_until``),
    wrenches 0-10 s; ``extra`` edges are added to every /tf message."""
    bag = _Bag()
    _wrenches(bag, 0.0, 10.0, rate=50.0)
    for t in np.arange(0.0, 10.0, 0.05):
        edges = [("base_link", "flange", UNIT)] + list(extra)
        if t <= sensor_edge_until:
            edges.append(("flange", "ft_sensor", TURN))
        bag.tf(T0 + t, edges)
    return bag.write(tmp_path / name)


def test_a_tf_chain_covers_only_the_time_all_its_own_edges_cover(tmp_path):
    # the sensor's transform stops at 3 s while the flange's goes on: after 3 s the orientation is unknown,
    # so those samples are dropped and said, not read with the last rotation held for 7 s
    path = _tf_bag(tmp_path, "stopped", sensor_edge_until=3.0)
    rec = read_bag(path, tf=("base_link", "ft_sensor"))
    assert rec.time.max() <= T0 + 3.0 + 1e-6 and rec.time.min() == pytest.approx(T0)
    said = " ".join(str(n) for n in rec.notes)
    assert "flange -> ft_sensor until 1700000003.000 s" in said and "were dropped" in said
    assert np.allclose(rec.rotation[:, :2, :2], [[0.0, -1.0], [1.0, 0.0]], atol=1e-9)  # 90 deg about z
    # an edge off the chain (a camera) that stops early does not limit the chain
    full = read_bag(_tf_bag(tmp_path, "camera", sensor_edge_until=10.0), tf=("base_link", "ft_sensor"))
    assert full.time.max() > T0 + 9.9


def test_a_frame_of_the_chain_with_two_parents_is_refused_naming_both(tmp_path):
    path = _tf_bag(tmp_path, "two", sensor_edge_until=10.0, extra=[("tool0", "ft_sensor", UNIT)])
    with pytest.raises(LogFormatError, match=r"frame ft_sensor more than one parent: flange \(/tf at .*\); "
                                             r"tool0 \(/tf at"):
        read_bag(path, tf=("base_link", "ft_sensor"))
    # two parents of a frame off the chain do not matter to the sensor's orientation
    other = _tf_bag(tmp_path, "off", sensor_edge_until=10.0,
                    extra=[("base_link", "camera", UNIT), ("flange", "camera", UNIT)])
    assert read_bag(other, tf=("base_link", "ft_sensor")).rotation.shape[0] > 0


@pytest.mark.parametrize("quat, words", [((0.0, 0.0, 0.0, 0.0), "has zero length"),
                                         ((0.0, 0.0, float("nan"), 1.0), "is not finite")])
def test_an_invalid_quaternion_on_the_chain_is_refused_naming_bag_topic_edge_and_time(tmp_path, quat, words):
    bag = _Bag()
    _wrenches(bag, 0.0, 2.0, rate=50.0)
    for k, t in enumerate(np.arange(0.0, 2.0, 0.05)):
        bag.tf(T0 + t, [("base_link", "ft_sensor", quat if k == 7 else TURN)])
    path = bag.write(tmp_path / "zero")
    with pytest.raises(LogFormatError) as info:
        read_bag(path, tf=("base_link", "ft_sensor"))
    text = str(info.value)
    assert str(path) in text and "topic /tf at 1700000000.350 s" in text, text
    assert "base_link -> ft_sensor" in text and words in text, text


def test_joint_states_are_grouped_by_the_names_of_each_message(tmp_path):
    # a gripper's message comes first on the arm's topic: the arm's messages are still read, the gripper's set aside
    bag = _Bag()
    _wrenches(bag, 0.0, 2.0)
    bag.joints(T0 - 0.01, ["finger"], [0.02])
    for t in np.arange(0.0, 2.0, 0.02):
        bag.joints(T0 + t, ["j1", "j2"], [t, -t])
        if round(t * 50) % 10 == 0:
            bag.joints(T0 + t + 0.001, ["finger"], [0.02])
    rec = read_bag(bag.write(tmp_path / "gripper"))
    assert rec.joint_names == ("j1", "j2")
    assert np.allclose(rec.joints[:, 0], rec.time - T0, atol=1e-6) and np.allclose(rec.joints[:, 1], T0 - rec.time,
                                                                                    atol=1e-6)
    assert any("messages naming other joints (finger) were set aside" in str(n) for n in rec.notes)


def test_clocks_apart_on_receive_times_do_not_advise_receive_times_again(tmp_path):
    bag = _Bag()
    _wrenches(bag, 0.0, 1.0)
    for t in np.arange(5.0, 6.0, 0.02):  # the joints recorded later: no common time on any clock
        bag.joints(T0 + t, ["j1"], [t])
    path = bag.write(tmp_path / "apart")
    with pytest.raises(LogFormatError) as header:
        read_bag(path)
    assert header.value.settings == {"stamps": "receive"}  # on header stamps the recorder's clock may help
    with pytest.raises(LogFormatError, match="not recorded together") as receive:
        read_bag(path, stamps="receive")
    assert not receive.value.settings and "stamps" not in (receive.value.fix or "")


def test_the_advised_tf_is_a_chain_the_bag_holds_and_never_a_frame_to_itself(tmp_path):
    bag = _Bag()
    _wrenches(bag, 0.0, 2.0, rate=50.0, frame="ft_sensor")
    for t in np.arange(0.0, 2.0, 0.05):
        bag.tf(T0 + t, [("ft_sensor", "tool0", TURN)])
    path = bag.write(tmp_path / "root")
    # the wrenches' frame is the root of the tree: "--tf ft_sensor,ft_sensor" would fail the same way
    with pytest.raises(LogFormatError, match="no chain to 'ft_sensor' from another frame") as info:
        read_bag(path, tf=("ft_sensor", "tool0"))
    assert not info.value.settings
    # where the tree holds the wrenches' frame below the base, that pair is advised, and it reads
    good = _Bag()
    _wrenches(good, 0.0, 2.0, rate=50.0, frame="ft_sensor")
    for t in np.arange(0.0, 2.0, 0.05):
        good.tf(T0 + t, [("base_link", "ft_sensor", TURN), ("ft_sensor", "tool0", UNIT)])
    path = good.write(tmp_path / "below")
    with pytest.raises(LogFormatError) as info:
        read_bag(path, tf=("base_link", "tool0"))
    assert tuple(info.value.settings["tf"]) == ("base_link", "ft_sensor")
    assert read_bag(path, tf=tuple(info.value.settings["tf"])).rotation.shape[0] > 0
