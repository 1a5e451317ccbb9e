"""Drivers by name and the agent context of a run."""

from __future__ import annotations

from pathlib import Path

import pytest

from skidnav.errors import UserError
from skidnav.realtime.config import config_from_mapping
from skidnav.realtime.control.run import agent_context
from skidnav.realtime.drivers import SimDriver, make_driver
from skidnav.realtime.link.line_client import LineClient, SerialLink, TcpLink
from skidnav.robot.params import RobotParams
from skidnav.world.discretization import Discretization
from tests.realtime.realtime_helpers import wait_for


def test_line_drivers_take_their_tables() -> None:
    config = config_from_mapping(
        {"tcp": {"host": "127.0.0.2", "port": 6000}, "serial": {"url": "loop://", "baudrate": 9600}}
    )
    tcp = make_driver("tcp", config)
    assert isinstance(tcp, LineClient) and isinstance(tcp.link, TcpLink)
    assert (tcp.link.host, tcp.link.port) == ("127.0.0.2", 6000)
    serial = make_driver("serial", config)
    assert isinstance(serial, LineClient) and isinstance(serial.link, SerialLink)
    assert (serial.link.url, serial.link.baudrate) == ("loop://", 9600)
    # every command is valid for as long as the host waits for a pose before tripping
    assert tcp.command_ttl == serial.command_ttl == config.run.pose_timeout


def test_sim_driver_passes_the_run_to_the_server() -> None:
    config = config_from_mapping(
        {"run": {"time_scale": 7.0, "map": "maze", "seed": 5}, "sim": {"slip": "slippery"}}
    )
    driver = make_driver("sim", config)
    assert isinstance(driver, SimDriver)
    arguments = driver.server.arguments
    for flag, value in (
        ("--time-scale", "7.0"),
        ("--map", "maze"),
        ("--seed", "5"),
        ("--slip", "slippery"),
    ):
        assert arguments[arguments.index(flag) + 1] == value


def test_ros2_driver_is_built_by_name_when_installed() -> None:
    pytest.importorskip("skidnav.realtime.link.ros2")
    driver = make_driver("ros2", config_from_mapping({"ros2": {"port": 9999}}))
    assert type(driver).__name__ == "Ros2Driver"
    with pytest.raises(UserError, match=r"\[ros2\]"):
        make_driver("ros2", config_from_mapping({"ros2": {"no_such_option": 1}}))


def test_unknown_driver_and_unknown_tables_are_user_errors() -> None:
    with pytest.raises(UserError, match="unknown driver"):
        make_driver("carrier-pigeon", config_from_mapping({}))
    with pytest.raises(
        UserError,
        match=r"^unknown key 'rnu' in top level \(did you mean 'run'\? expected one of run, ",
    ):
        config_from_mapping({"rnu": {}})
    with pytest.raises(
        UserError,
        match=r"^unknown key 'episode' in \[run\] \(did you mean 'episodes'\? expected one ",
    ):
        config_from_mapping({"run": {"episode": 3}})


def test_model_based_agents_get_the_geometry() -> None:
    robot, grid = RobotParams(), Discretization()
    assert agent_context("q-learning", robot, grid) == {}
    context = agent_context("dyna-kinematic", robot, grid)
    assert context == {"robot": robot, "discretization": grid}


def test_line_drivers_take_the_link_secret_from_a_file_or_the_environment(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    key = tmp_path / "robot.key"
    key.write_text("a secret of the lab, from a file\n", encoding="utf-8")
    monkeypatch.setenv("SKIDNAV_LINK_SECRET", "a secret of the lab, from the environment")
    config = config_from_mapping({"tcp": {"secret_file": str(key)}})
    tcp, serial = make_driver("tcp", config), make_driver("serial", config)
    assert isinstance(tcp, LineClient) and isinstance(serial, LineClient)
    assert tcp.secret == b"a secret of the lab, from a file"
    assert serial.secret == b"a secret of the lab, from the environment"
    monkeypatch.delenv("SKIDNAV_LINK_SECRET")
    plain = make_driver("serial", config)
    assert isinstance(plain, LineClient) and plain.secret is None
    key.write_text("short\n", encoding="utf-8")
    with pytest.raises(UserError, match="at least 16 bytes, got 5"):
        make_driver("tcp", config)


def test_the_sim_server_grants_the_runs_ttl_as_its_longest_lease() -> None:
    for time_scale in (20.0, 1.0, 0.5):
        config = config_from_mapping({"run": {"time_scale": time_scale}})
        driver = make_driver("sim", config)
        assert isinstance(driver, SimDriver)
        arguments = driver.server.arguments
        lease = float(arguments[arguments.index("--max-lease") + 1])
        assert lease == driver.command_ttl == config.run.pose_timeout


def test_the_sim_driver_and_its_server_share_the_environments_secret(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setenv("SKIDNAV_LINK_SECRET", "a secret of the lab, from the environment")
    driver = make_driver("sim", config_from_mapping({"run": {"time_scale": 10.0}}))
    assert isinstance(driver, SimDriver) and driver.secret is not None
    try:
        driver.connect()  # a server without the secret would fail the robot's hello
        wait_for(lambda: driver.latest_pose() is not None, 5.0, "a first pose")
        assert driver.fault is None
    finally:
        driver.shutdown()
