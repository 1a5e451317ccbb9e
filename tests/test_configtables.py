"""The config-table conventions: one-line "where: problem" errors, the same from every loader."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import pytest

from skidnav.errors import EXCERPT_CHARS, ConfigKeyError, UserError, first_line, within
from skidnav.experiments.configfile import parse_config
from skidnav.files.configtables import build_dataclass, check_keys, resolve_path, table, table_array
from skidnav.realtime.config import config_from_mapping
from tests.experiments.exp_support import TINY_TOML


@dataclass(frozen=True)
class Settings:
    count: int = 1
    name: str = "a"

    def __post_init__(self) -> None:
        if self.count < 1:
            raise ValueError(f"expected count >= 1, got {self.count}")


def test_table_returns_a_table_and_refuses_anything_else() -> None:
    assert table({"a": 1}, "[x]") == {"a": 1}
    for value in (3, "s", [1], None):
        with pytest.raises(UserError, match=r"^\[x\]: expected a table, got "):
            table(value, "[x]")


def test_table_array_names_the_item_that_is_not_a_table() -> None:
    assert table_array([{"a": 1}, {}], "maps") == [{"a": 1}, {}]
    with pytest.raises(UserError, match=r"^expected at least one \[\[maps\]\] table$"):
        table_array([], "maps")
    with pytest.raises(UserError, match=r"^\[\[maps\]\] #2: expected a table, got 3$"):
        table_array([{}, 3], "maps")


def test_check_keys_names_the_first_unknown_key_and_the_known_ones() -> None:
    check_keys({"b": 1, "a": 2}, ("a", "b"), "[x]")
    with pytest.raises(UserError) as caught:
        check_keys({"a": 1, "zz": 2, "yy": 3}, ("a", "b"), "[x]")
    assert str(caught.value) == "unknown key 'zz' in [x] (expected one of a, b)"


def test_a_long_or_hostile_unknown_key_is_quoted_in_part_on_one_line() -> None:
    with pytest.raises(UserError) as caught:
        check_keys({"k\n" * 5000: 1}, ("a",), "[x]")
    message = str(caught.value)
    assert "\n" not in message and len(message) < 2 * EXCERPT_CHARS + 40, message


def test_build_dataclass_checks_keys_then_the_class_validates() -> None:
    assert build_dataclass(Settings, {"count": 3}, "[s]") == Settings(count=3)
    assert build_dataclass(Settings, {}, "[s]") == Settings()
    cases = {
        "[s]: expected a table, got 3": 3,
        "unknown key 'size' in [s] (expected one of count, name)": {"size": 3},
        "expected count >= 1, got 0 in [s]": {"count": 0},
    }
    for message, value in cases.items():
        with pytest.raises(UserError) as caught:
            build_dataclass(Settings, value, "[s]")
        assert str(caught.value) == message
    with pytest.raises(UserError, match=r" in \[s\]$"):  # a TypeError of the class, one line
        build_dataclass(Settings, {"count": "many"}, "[s]")


def test_resolve_path_is_relative_to_the_config_folder(tmp_path: Path) -> None:
    folder = tmp_path / "configs"
    assert resolve_path("maps/a.txt", folder) == folder.resolve() / "maps" / "a.txt"
    assert resolve_path("../a.txt", folder) == tmp_path.resolve() / "a.txt"
    absolute = str(tmp_path.resolve() / "b.txt")
    assert resolve_path(absolute, folder) == Path(absolute)


def test_both_loaders_word_the_same_faults_alike() -> None:
    with pytest.raises(UserError) as experiment:
        parse_config(TINY_TOML.replace("episodes = 6", "episods = 6"), "a.toml")
    with pytest.raises(UserError) as realtime:
        config_from_mapping({"run": {"episods": 6}})
    assert str(experiment.value).startswith("unknown key 'episods' in a.toml: [experiment] (did ")
    assert str(realtime.value).startswith("unknown key 'episods' in [run] (did you mean 'epi")
    with pytest.raises(UserError, match=r"^\[env\]: expected a table, got 3 in a\.toml$"):
        parse_config("env = 3\n" + TINY_TOML, "a.toml")
    with pytest.raises(UserError, match=r"^\[sim\]: expected a table, got 3$"):
        config_from_mapping({"sim": 3})


@dataclass(frozen=True)
class Typed:
    count: int = 1
    scale: float = 1.0
    flag: bool = False
    name: str = "a"
    limit: float | None = None
    items: tuple[int, ...] = ()


def test_build_dataclass_checks_the_type_of_every_simple_field() -> None:
    values = {"count": 2, "scale": 3, "flag": True, "name": "b", "limit": None, "items": (1,)}
    assert build_dataclass(Typed, values, "[t]") == Typed(2, 3, True, "b", None, (1,))
    cases = {
        "expected count to be an integer, got True in [t]": {"count": True},
        "expected count to be an integer, got 2.0 in [t]": {"count": 2.0},
        "expected scale to be a number, got '1.5' in [t]": {"scale": "1.5"},
        "expected flag to be true or false, got 'yes' in [t]": {"flag": "yes"},
        "expected flag to be true or false, got 1 in [t]": {"flag": 1},
        "expected name to be a string, got 3 in [t]": {"name": 3},
        "expected limit to be a number, got 'none' in [t]": {"limit": "none"},
    }
    for message, value in cases.items():
        with pytest.raises(UserError) as caught:
            build_dataclass(Typed, value, "[t]")
        assert str(caught.value) == message
    assert build_dataclass(Typed, {"items": ["x"]}, "[t]").items == ["x"]  # left to the class


KEY_FIRST_CHARS = 60
"""The misspelt key must show within this many characters of the command's one error line."""


@pytest.mark.parametrize(
    ("edit", "key", "guess"),
    [
        (("planning_steps = 5", "planing_steps = 5"), "planing_steps", "planning_steps"),
        (("episodes = 6", "episods = 6"), "episods", "episodes"),
        (('kind = "free"', 'kind = "free"\nlable = "m"'), "lable", "label"),
        (('label = "dyna-q-5"', 'labl = "dyna-q-5"'), "labl", "label"),
    ],
)
def test_a_misspelt_key_leads_the_error_line_however_long_the_path(
    edit: tuple[str, str], key: str, guess: str, tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:  # fmt: skip
    from skidnav.cli import main

    folder = tmp_path / ("a-long-folder-name-" * 8)
    folder.mkdir()
    config = folder / "experiment.toml"
    config.write_text(TINY_TOML.replace(*edit))
    assert main(["run", str(config), "--out", str(tmp_path / "out")]) == 2
    line = capsys.readouterr().err.strip()
    assert "\n" not in line and line.index(f"unknown key {key!r}") < KEY_FIRST_CHARS, line
    assert str(config) in line and f"did you mean {guess!r}?" in line
    assert not (tmp_path / "out").exists()


def test_the_cut_of_a_long_error_keeps_the_key() -> None:
    known = [f"option_number_{n}" for n in range(50)]
    with pytest.raises(ConfigKeyError) as caught:
        check_keys({"planing_steps": 1}, known, "[[agents]] #1 params")
    error = within(within(caught.value, "agent 'dyna-full'"), "/very/long/" * 30 + "a.toml")
    assert len(str(error)) > 600 and first_line(error).startswith("unknown key 'planing_steps' in")
