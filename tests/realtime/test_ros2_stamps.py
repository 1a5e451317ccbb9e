"""ROS 2 conventions of the rosbridge driver: TwistStamped commands, header-stamped pose ages, tf
poses and malformed messages, against the in-test rosbridge server of test_ros2.py."""

from __future__ import annotations

import json
import logging
import math
from typing import Any

import pytest

from skidnav.errors import UserError
from skidnav.realtime.config import config_from_mapping
from skidnav.realtime.control.safety import SafetyLimits, SafetyMonitor
from skidnav.realtime.drivers import make_driver as driver_by_name
from skidnav.realtime.link.ros2 import Ros2Config
from skidnav.realtime.link.ros2_messages import (
    heading_from_quaternion,
    ros_time,
    seconds_from_stamp,
    wheel_speeds_to_twist,
)
from tests.realtime.test_ros2 import PARAMS, RosbridgeStub, make_driver, odometry, wait_for

WALL = 1_700_000_000.25  # this machine's ROS time in these tests [s since the epoch]
MONO = 50.0  # its monotonic clock [s]


class FakeClock:
    """A clock [s] that stays where the test puts it."""

    def __init__(self, now: float) -> None:
        self.now = now

    def __call__(self) -> float:
        return self.now


@pytest.fixture(scope="module")
def server():
    stub = RosbridgeStub()
    yield stub
    stub.close()


def quaternion(yaw: float, pitch: float = 0.0, roll: float = 0.0) -> dict[str, float]:
    """The rotation Rz(yaw)·Ry(pitch)·Rx(roll) as a quaternion dict (products of axis rotations)."""

    def product(a: tuple[float, ...], b: tuple[float, ...]) -> tuple[float, ...]:
        (w1, x1, y1, z1), (w2, x2, y2, z2) = a, b
        return (
            w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2,
            w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
            w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2,
            w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2,
        )

    about_z = (math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2))
    about_y = (math.cos(pitch / 2), 0.0, math.sin(pitch / 2), 0.0)
    about_x = (math.cos(roll / 2), math.sin(roll / 2), 0.0, 0.0)
    w, x, y, z = product(product(about_z, about_y), about_x)
    return {"x": x, "y": y, "z": z, "w": w}


def transform(
    parent: str, child: str, x: float, y: float, rotation: dict[str, float], sec: int = 0
) -> dict[str, Any]:
    """A ``geometry_msgs/TransformStamped`` dict."""
    return {
        "header": {"stamp": {"sec": sec, "nanosec": 0}, "frame_id": parent},
        "child_frame_id": child,
        "transform": {"translation": {"x": x, "y": y, "z": 0.0}, "rotation": rotation},
    }


# --- commands -------------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("options", "stamp"),
    [
        ({}, {"sec": 0, "nanosec": 0}),  # unsynchronised clocks: the robot stamps on receipt
        ({"clock": "header"}, {"sec": 1_700_000_000, "nanosec": 250_000_000}),
        (
            {"clock": "header", "base_frame_id": "base_footprint"},
            {"sec": 1_700_000_000, "nanosec": 250_000_000},
        ),
    ],
)
def test_jazzy_commands_are_twist_stamped(server, options, stamp) -> None:
    driver = make_driver(server, wall_clock=FakeClock(WALL), **options)
    topic = driver.config.cmd_vel_topic
    try:
        driver.command(0.5, 1.2)
        message = wait_for(lambda: server.ops("publish", topic))[0]["msg"]
    finally:
        driver.close()
    r, c = PARAMS.wheel_radius, PARAMS.half_track
    assert server.ops("advertise", topic)[0]["type"] == "geometry_msgs/TwistStamped"
    assert message == {
        "header": {
            "stamp": stamp,
            "frame_id": options.get("base_frame_id", "base_link"),
        },
        "twist": {
            "linear": {"x": r * (1.2 + 0.5) / 2, "y": 0.0, "z": 0.0},
            "angular": {"x": 0.0, "y": 0.0, "z": r * (1.2 - 0.5) / (2 * c)},
        },
    }


@pytest.mark.parametrize(
    ("options", "expected"),
    [
        ({}, "geometry_msgs/TwistStamped"),  # default distro: jazzy
        ({"distro": "humble"}, "geometry_msgs/Twist"),
        ({"distro": "iron"}, "geometry_msgs/Twist"),
        ({"distro": "kilted"}, "geometry_msgs/TwistStamped"),
        ({"distro": "rolling"}, "geometry_msgs/TwistStamped"),
        ({"distro": "humble", "stamped": True}, "geometry_msgs/TwistStamped"),
        ({"distro": "jazzy", "stamped": False}, "geometry_msgs/Twist"),
    ],
)
def test_command_type_follows_the_distro_unless_overridden(options, expected) -> None:
    assert Ros2Config(**options).cmd_vel_type == expected


# --- pose stamps ------------------------------------------------------------------------------
def test_header_stamps_give_pose_ages(server) -> None:
    driver = make_driver(
        server, monotonic=FakeClock(MONO), wall_clock=FakeClock(1000.0), clock="header"
    )
    topic = driver.config.pose_topic
    try:
        server.publish(topic, odometry(0.1, 0.2, 0.3, stamp=(999, 800_000_000)))
        pose = wait_for(driver.latest_pose)
        assert pose.stamp == pytest.approx(MONO - 0.2)  # measured 0.2 s before it arrived
        assert driver.latest_measurement() == (pose, pytest.approx(999.8))
        server.publish(topic, odometry(0.2, 0.2, 0.3, stamp=(1000, 10_000_000)))
        pose = wait_for(lambda: (p := driver.latest_pose()) is not None and p.x == 0.2 and p)
        assert pose.stamp == MONO  # 10 ms ahead, within future_tolerance: clamped to arrival
        assert driver.fault is None and driver.refused_poses == 0
    finally:
        driver.close()


def test_arrival_clock_ignores_header_stamps(server) -> None:
    driver = make_driver(server, monotonic=FakeClock(MONO), wall_clock=FakeClock(1000.0))
    try:
        server.publish(driver.config.pose_topic, odometry(0.1, 0.2, 0.3, stamp=(3, 0)))
        pose = wait_for(driver.latest_pose)
    finally:
        driver.close()
    assert pose.stamp == MONO and driver.latest_measurement() is None and driver.fault is None


@pytest.mark.parametrize(
    ("stamp", "reason"),
    [
        ((999, 400_000_000), "0.600 s old (max_pose_age 0.5 s)"),
        ((1000, 200_000_000), "0.200 s in the future (future_tolerance 0.05 s)"),
        ((0, 0), "1000.000 s old"),  # an unset stamp
    ],
)
def test_stale_and_future_stamps_trip(server, stamp, reason) -> None:
    driver = make_driver(server, wall_clock=FakeClock(1000.0), clock="header")
    reasons: list[str] = []
    driver.on_fault = reasons.append
    topic = driver.config.pose_topic
    try:
        server.publish(topic, odometry(0.1, 0.2, 0.3, stamp=(999, 900_000_000)))
        good = wait_for(driver.latest_pose)
        server.publish(topic, odometry(0.4, 0.2, 0.3, stamp=stamp))
        wait_for(lambda: driver.refused_poses == 1)
        assert driver.latest_pose() == good  # refused: the older good pose stays the newest
    finally:
        driver.close()
    assert len(reasons) == 1 and reason in reasons[0] and driver.fault == reasons[0]
    assert driver.malformed_messages == 0


# --- tf ---------------------------------------------------------------------------------------
def test_tf_pose_is_the_odom_to_base_link_transform(server) -> None:
    driver = make_driver(
        server,
        pose_topic="/tf_a",
        pose_type="tf2_msgs/msg/TFMessage",
        frame_offset=(0.1, 0.0, 0.0),
        wall_clock=FakeClock(1000.0),
        clock="header",
    )
    reasons: list[str] = []
    driver.on_fault = reasons.append
    wheel = transform("base_link", "left_wheel", 0.0, 0.05, quaternion(0.0, pitch=1.0), sec=1000)
    try:
        assert server.ops("subscribe", "/tf_a")[0]["type"] == "tf2_msgs/msg/TFMessage"
        server.publish("/tf_a", {"transforms": [wheel]})  # other frames only: nothing to read
        rotation = quaternion(2.5, pitch=0.05, roll=-0.1)  # a slightly tilted body
        base = transform("/odom", "base_link", 0.3, -0.1, rotation, sec=1000)
        server.publish("/tf_a", {"transforms": [wheel, base]})
        pose = wait_for(driver.latest_pose)
        assert driver.latest_measurement()[1] == 1000.0 and reasons == []
        server.publish("/tf_a", {"transforms": {"odom": base}})
        unstamped = transform("odom", "base_link", 0.3, -0.1, rotation)  # stamp 0: stale
        server.publish("/tf_a", {"transforms": [wheel, unstamped]})
        wait_for(lambda: driver.malformed_messages == 1 and driver.refused_poses == 1)
    finally:
        driver.close()
    assert (pose.x, pose.y, pose.heading) == pytest.approx((0.4, -0.1, 2.5))
    assert "list of transforms" in reasons[0] and "1000.000 s old" in reasons[1]


@pytest.mark.parametrize(
    ("rotation", "heading"),
    [
        ((0.0, 0.0, 0.7071068, 0.7071068), math.pi / 2),
        ((0.0, 0.0, 1.0, 0.0), math.pi),
        ((0.0, 0.0, -0.3826834, 0.9238795), -math.pi / 4),
        ((0.0, 0.0, 3e300, 3e300), math.pi / 2),  # huge but finite: no overflow
    ],
)
def test_heading_of_known_quaternions(rotation, heading) -> None:
    assert heading_from_quaternion(*rotation) == pytest.approx(heading, abs=1e-6)


# --- malformed messages -------------------------------------------------------------------------
def with_field(message: dict[str, Any], path: str, value: Any) -> dict[str, Any]:
    """A deep copy of ``message`` with the field at ``path`` ("a.b.c") set, or deleted if
    ``value`` is ``...``."""
    copy = json.loads(json.dumps(message))
    *parents, last = path.split(".")
    target = copy
    for key in parents:
        target = target[key]
    if value is ...:
        del target[last]
    else:
        target[last] = value
    return copy


GOOD = odometry(0.1, 0.1, 0.0, stamp=(1000, 0))  # each entry below breaks one thing of it
MALFORMED = [
    with_field(GOOD, "header", ...),
    with_field(GOOD, "header.stamp", ...),
    with_field(GOOD, "header.stamp.nanosec", 1_000_000_000),
    with_field(GOOD, "header.stamp.sec", "999"),
    with_field(GOOD, "header.stamp.sec", 2**40),
    with_field(GOOD, "header.stamp.sec", -1),
    with_field(GOOD, "header.stamp.sec", True),
    with_field(GOOD, "pose.pose.position.x", 10**400),
    with_field(GOOD, "pose.pose.position.x", math.inf),
    with_field(GOOD, "pose.pose.position.y", "0.2"),
    with_field(GOOD, "pose.pose.orientation.w", None),
    with_field(GOOD, "pose.pose", [1, 2, 3]),
    [],
]


def test_malformed_messages_trip_with_one_log_line_and_the_reader_survives(server, caplog) -> None:
    caplog.set_level(logging.DEBUG, logger="skidnav.realtime.link.ros2")
    driver = make_driver(server, wall_clock=FakeClock(1000.0), clock="header")
    reasons: list[str] = []
    driver.on_fault = reasons.append
    topic = driver.config.pose_topic
    try:
        for message in MALFORMED:
            server.publish(topic, message)
        wait_for(lambda: driver.malformed_messages == len(MALFORMED))
        server.publish(topic, odometry(0.3, 0.2, 0.1, stamp=(1000, 0)))  # still reading
        pose = wait_for(driver.latest_pose)
        assert pose.x == 0.3
        fault = driver.fault
        driver.close()
        driver.connect()  # a fresh link clears the fault
        assert driver.fault is None
    finally:
        driver.close()
    assert len(reasons) == len(MALFORMED) and fault == reasons[0]
    assert all("\n" not in reason and len(reason) < 160 for reason in reasons)
    assert "missing field header" in reasons[0] and "nanosec" in reasons[2]
    assert "out of range" in reasons[7] and "finite" in reasons[8]
    ours = [r for r in caplog.records if r.name == "skidnav.realtime.link.ros2"]
    assert [r.getMessage() for r in ours if r.levelno == logging.WARNING] == [reasons[0]]
    assert not [r for r in caplog.records if r.exc_info or r.levelno >= logging.ERROR]


# --- pure conversions and config ------------------------------------------------------------------
def test_stamp_conversions() -> None:
    assert ros_time(WALL) == {"sec": 1_700_000_000, "nanosec": 250_000_000}
    assert ros_time(12.9999999999) == {"sec": 13, "nanosec": 0}  # rounding carries into sec
    assert seconds_from_stamp(ros_time(1234.5)) == 1234.5
    for bad in ({"sec": 1}, {"sec": 1.0, "nanosec": 0}, {"sec": 1, "nanosec": -1}, [1, 0]):
        with pytest.raises(ValueError, match="stamp"):
            seconds_from_stamp(bad)
    assert wheel_speeds_to_twist(0.0, 0.0, PARAMS)["angular"]["z"] == 0.0


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"distro": "foxy"}, "distro"),
        ({"stamped": "yes"}, "stamped"),
        ({"clock": "ros"}, "clock"),
        ({"max_pose_age": 0.0}, "max_pose_age"),
        ({"future_tolerance": -0.1}, "future_tolerance"),
        ({"future_tolerance": math.inf}, "future_tolerance"),
        ({"base_frame_id": "/base_link"}, "base_frame_id"),
        ({"odom_frame_id": ""}, "odom_frame_id"),
    ],
)
def test_config_validation_of_the_ros_conventions(kwargs, message) -> None:
    with pytest.raises(ValueError, match=message):
        Ros2Config(**kwargs)


def test_ros2_table_options_reach_the_driver_and_bad_ones_end_in_one_line() -> None:
    table = {"distro": "humble", "clock": "header", "pose_type": "tf2_msgs/TFMessage"}
    driver = driver_by_name("ros2", config_from_mapping({"ros2": {**table, "pose_topic": "/tf"}}))
    config = driver.config  # type: ignore[attr-defined]
    assert (config.cmd_vel_type, config.clock, config.tf_poses) == (
        "geometry_msgs/Twist",
        "header",
        True,
    )
    with pytest.raises(UserError, match=r"^expected distro in .*got 'foxy' in \[ros2\]$"):
        driver_by_name("ros2", config_from_mapping({"ros2": {"distro": "foxy"}}))


def test_a_refused_pose_trips_the_safety_monitor(server) -> None:
    driver = make_driver(server, wall_clock=FakeClock(1000.0), clock="header")
    monitor = SafetyMonitor(driver, SafetyLimits())  # sets driver.on_fault to its trip
    try:
        server.publish(driver.config.pose_topic, odometry(0.1, 0.2, 0.3, stamp=(998, 0)))
        wait_for(monitor.tripped.is_set)
    finally:
        driver.close()
    assert "2.000 s old" in monitor.reason
