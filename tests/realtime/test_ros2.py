"""The ROS 2 driver against an in-test rosbridge v2 server (``websockets``, loopback, free port).

roslibpy's Twisted reactor is process-wide and cannot be restarted, so these tests never stop it;
every test opens and closes its own driver connection on the one running reactor (which is what
``test_drivers_connect_and_close_repeatedly`` checks).
"""

from __future__ import annotations

import asyncio
import itertools
import json
import math
import socket
import threading
import time
from collections.abc import Callable
from typing import Any

import pytest
from websockets.asyncio.server import ServerConnection, serve

from skidnav.realtime.link.ros2 import Ros2Config, Ros2Driver
from skidnav.realtime.link.ros2_messages import (
    compose,
    heading_from_quaternion,
    pose_from_message,
    wheel_speeds_to_twist,
)
from skidnav.robot.params import RobotParams

PARAMS = RobotParams()


class RosbridgeStub:
    """Enough of rosbridge v2 for roslibpy: advertise, publish, subscribe, unadvertise, unsubscribe.

    Records every operation received; forwards publications to the topic's subscribers; the test
    publishes to subscribers with :meth:`publish`.
    """

    def __init__(self) -> None:
        self.operations: list[tuple[int, dict[str, Any]]] = []  # (connection number, message)
        self.opened = 0
        self.closed = 0
        self._subscribers: dict[str, set[ServerConnection]] = {}
        self._lock = threading.Lock()
        self._loop = asyncio.new_event_loop()
        self._ready = threading.Event()
        self._stopping: asyncio.Future[None] | None = None
        self._thread = threading.Thread(target=self._loop.run_until_complete, args=(self._main(),))
        self._thread.start()
        assert self._ready.wait(5), "stub server did not start"

    async def _main(self) -> None:
        self._stopping = self._loop.create_future()
        async with serve(self._handle, "127.0.0.1", 0) as server:
            self.port = next(iter(server.sockets)).getsockname()[1]
            self._ready.set()
            await self._stopping

    async def _handle(self, connection: ServerConnection) -> None:
        with self._lock:
            self.opened += 1
            number = self.opened
        try:
            async for raw in connection:
                message = json.loads(raw)
                with self._lock:
                    self.operations.append((number, message))
                await self._dispatch(connection, message)
        finally:
            for subscribers in self._subscribers.values():
                subscribers.discard(connection)
            with self._lock:
                self.closed += 1

    async def _dispatch(self, connection: ServerConnection, message: dict[str, Any]) -> None:
        op, topic = message["op"], message.get("topic", "")
        if op == "subscribe":
            self._subscribers.setdefault(topic, set()).add(connection)
        elif op == "unsubscribe":
            self._subscribers.get(topic, set()).discard(connection)
        elif op == "publish":
            await self._broadcast(topic, message["msg"])
        elif op not in ("advertise", "unadvertise"):
            raise AssertionError(f"unexpected rosbridge op {op!r}")

    async def _broadcast(self, topic: str, msg: dict[str, Any]) -> None:
        frame = json.dumps({"op": "publish", "topic": topic, "msg": msg})
        for connection in list(self._subscribers.get(topic, ())):
            await connection.send(frame)

    def publish(self, topic: str, msg: dict[str, Any]) -> None:
        """Send ``msg`` on ``topic`` to every subscribed client."""
        asyncio.run_coroutine_threadsafe(self._broadcast(topic, msg), self._loop).result(5)

    def ops(self, op: str, topic: str | None = None) -> list[dict[str, Any]]:
        with self._lock:
            return [
                m for _, m in self.operations if m["op"] == op and topic in (None, m.get("topic"))
            ]

    def close(self) -> None:
        assert self._stopping is not None
        self._loop.call_soon_threadsafe(self._stopping.set_result, None)
        self._thread.join(10)
        self._loop.close()


def wait_for(condition: Callable[[], Any], timeout: float = 5.0) -> Any:
    """Poll ``condition`` until truthy (returned) or fail after ``timeout`` seconds."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        value = condition()
        if value:
            return value
        time.sleep(0.01)
    raise AssertionError("condition not met in time")


@pytest.fixture(scope="module")
def server():
    stub = RosbridgeStub()
    yield stub
    stub.close()


TOPIC_NUMBERS = itertools.count()


def make_driver(
    server: RosbridgeStub,
    *,
    monotonic: Callable[[], float] = time.monotonic,
    wall_clock: Callable[[], float] = time.time,
    **kwargs: Any,
) -> Ros2Driver:
    """A connected driver on topics no other test uses (the stub is shared by the module), with
    the given monotonic and wall clocks and config fields; waits until it has subscribed."""
    number = next(TOPIC_NUMBERS)
    topics = {"cmd_vel_topic": f"/cmd_vel_{number}", "pose_topic": f"/odom_{number}"}
    config = Ros2Config(port=server.port, connect_timeout=5.0, **{**topics, **kwargs})
    driver = Ros2Driver(config, PARAMS, clock=monotonic, wall_clock=wall_clock)
    driver.connect()
    wait_for(lambda: server.ops("subscribe", config.pose_topic))
    return driver


def odometry(x: float, y: float, heading: float, stamp: tuple[int, int] = (0, 0)) -> dict[str, Any]:
    """A ``nav_msgs/Odometry`` dict at (x [m], y [m], heading [rad]), stamped (sec, nanosec)."""
    pose = {
        "position": {"x": x, "y": y, "z": 0.0},
        "orientation": {"x": 0.0, "y": 0.0, "z": math.sin(heading / 2), "w": math.cos(heading / 2)},
    }
    return {
        "header": {"stamp": {"sec": stamp[0], "nanosec": stamp[1]}, "frame_id": "odom"},
        "child_frame_id": "base_link",
        "pose": {"pose": pose, "covariance": [0.0] * 36},
        "twist": {"twist": {}, "covariance": [0.0] * 36},
    }


def pose_stamped(x: float, y: float, heading: float) -> dict[str, Any]:
    return {"header": {"frame_id": "map"}, "pose": odometry(x, y, heading)["pose"]["pose"]}


@pytest.mark.parametrize(("left", "right"), [(1.7, 1.7), (-1.7, 1.7), (1.7, -1.7), (0.5, 1.2)])
def test_wheel_speeds_reach_the_server_as_unstamped_twists_for_humble(server, left, right) -> None:
    driver = make_driver(server, distro="humble")
    topic = driver.config.cmd_vel_topic
    try:
        driver.command(left, right)
        message = wait_for(lambda: server.ops("publish", topic))[0]["msg"]
    finally:
        driver.close()
    r, c = PARAMS.wheel_radius, PARAMS.half_track
    assert set(message) == {"linear", "angular"}  # a bare Twist: no header
    assert message["linear"]["x"] == pytest.approx(r * (right + left) / 2)
    assert message["angular"]["z"] == pytest.approx(r * (right - left) / (2 * c))
    assert message["linear"]["y"] == message["angular"]["x"] == 0.0
    assert server.ops("advertise", topic)[0]["type"] == "geometry_msgs/Twist"


@pytest.mark.parametrize(
    ("topic", "pose_type", "make_message"),
    [
        ("/odom_a", "nav_msgs/Odometry", odometry),
        ("/robot_pose_a", "geometry_msgs/msg/PoseStamped", pose_stamped),
    ],
)
def test_published_poses_reach_latest_pose(server, topic, pose_type, make_message) -> None:
    driver = make_driver(server, pose_topic=topic, pose_type=pose_type)
    try:
        assert driver.latest_pose() is None
        assert server.ops("subscribe", topic)[0]["type"] == pose_type
        before = time.monotonic()
        for x, y, heading in [(0.1, 0.2, 0.3), (0.31, 0.22, -2.9)]:
            server.publish(topic, make_message(x, y, heading))
            pose = wait_for(lambda x=x: (p := driver.latest_pose()) is not None and p.x == x and p)
            assert (pose.y, pose.heading) == pytest.approx((y, heading))
            assert before <= pose.stamp <= time.monotonic()
    finally:
        driver.close()


def test_frame_offset_places_odometry_in_the_arena(server) -> None:
    driver = make_driver(server, frame_offset=(0.1, 0.05, math.pi / 2))
    try:
        server.publish(driver.config.pose_topic, odometry(0.2, 0.0, 0.0))
        pose = wait_for(driver.latest_pose)
    finally:
        driver.close()
    assert (pose.x, pose.y, pose.heading) == pytest.approx((0.1, 0.25, math.pi / 2))


def test_malformed_pose_messages_are_refused_and_trip(server) -> None:
    driver = make_driver(server)
    reasons: list[str] = []
    driver.on_fault = reasons.append
    try:
        topic = driver.config.pose_topic
        server.publish(topic, odometry(0.4, 0.3, 1.0))
        good = wait_for(driver.latest_pose)
        server.publish(topic, {"pose": {"position": {}}})
        bad = odometry(0.1, 0.1, 0.0)
        bad["pose"]["pose"]["orientation"] = {"x": 0.0, "y": 0.0, "z": 0.0, "w": 0.0}
        server.publish(topic, bad)
        wait_for(lambda: driver.malformed_messages == 2)
        assert driver.latest_pose() == good
        assert "missing field pose.pose" in reasons[0] and "quaternion" in reasons[1]
        assert driver.fault == reasons[0]
    finally:
        driver.close()


def test_stop_sends_zero_twist_and_close_stops_then_disconnects(server) -> None:
    driver = make_driver(server)
    topic = driver.config.cmd_vel_topic
    driver.command(1.7, 1.7)
    assert driver.stop() is True
    # stop() returns once sent: the zero twist is on the wire, so it arrives without a new send.
    sent = wait_for(lambda: len(server.ops("publish", topic)) == 2 and server.ops("publish", topic))
    zero = wheel_speeds_to_twist(0.0, 0.0, PARAMS)
    assert sent[0]["msg"]["twist"]["linear"]["x"] > 0
    assert sent[1]["msg"]["twist"] == zero  # Jazzy by default: TwistStamped
    driver.command(-1.7, 1.7)
    driver.close()
    assert not driver.connected and driver.stop() is False
    wait_for(lambda: server.closed == server.opened)
    sent = server.ops("publish", topic)
    assert len(sent) == 4
    assert sent[2]["msg"]["twist"]["angular"]["z"] > 0
    assert sent[3]["msg"]["twist"] == zero
    assert server.ops("unadvertise", topic) and server.ops("unsubscribe", driver.config.pose_topic)
    with pytest.raises(ConnectionError, match="not connected"):
        driver.command(1.0, 1.0)


def test_drivers_connect_and_close_repeatedly(server) -> None:
    opened = server.opened
    for _ in range(3):
        with Ros2Driver(Ros2Config(port=server.port), PARAMS) as driver:
            assert driver.connected
    wait_for(lambda: server.opened == opened + 3 and server.closed == server.opened)


def test_unreachable_rosbridge_times_out_with_one_line() -> None:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]  # nothing listens here once closed
    driver = Ros2Driver(Ros2Config(port=port, connect_timeout=0.5))
    start = time.monotonic()
    with pytest.raises(ConnectionError) as caught:
        driver.connect()
    assert time.monotonic() - start < 3.0
    assert str(caught.value) == f"cannot reach rosbridge at ws://127.0.0.1:{port} within 0.5 s"
    assert not driver.connected and driver.stop() is False
    driver.close()  # nothing to close: must not raise


def test_conversions() -> None:
    twist = wheel_speeds_to_twist(-1.0, 1.0, PARAMS)
    assert twist["linear"]["x"] == 0.0
    assert twist["angular"]["z"] == pytest.approx(PARAMS.wheel_radius / PARAMS.half_track)
    for heading in (-3.0, -1.0, 0.0, 0.5, 3.1):
        quaternion = (0.0, 0.0, math.sin(heading / 2), math.cos(heading / 2))
        assert heading_from_quaternion(*quaternion) == pytest.approx(heading)
    assert pose_from_message(pose_stamped(1.0, 2.0, 0.5), "geometry_msgs/PoseStamped") == (
        pytest.approx((1.0, 2.0, 0.5))
    )
    assert compose((0.0, 0.0, math.pi), (0.0, 0.0, math.pi))[2] == pytest.approx(0.0, abs=1e-12)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"port": 0}, "port"),
        ({"pose_type": "std_msgs/String"}, "pose_type"),
        ({"cmd_vel_topic": "cmd_vel"}, "starting with '/'"),
        ({"connect_timeout": 0.0}, "positive timeouts"),
        ({"frame_offset": (0.0, math.nan, 0.0)}, "frame_offset"),
    ],
)
def test_config_validation(kwargs, message) -> None:
    with pytest.raises(ValueError, match=message):
        Ros2Config(**kwargs)
