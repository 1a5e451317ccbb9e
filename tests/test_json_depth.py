"""The JSON nesting pre-check: exact on valid JSON, the same state machine as a byte-by-byte scan
on any bytes whatever the block size, and memory linear in the text with a small constant (a
regular expression took about 125 bytes per byte of a string literal: 5 GB for 40 MB)."""

from __future__ import annotations

import json
import tracemalloc
from typing import Any

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from skidnav.files import jsondepth
from skidnav.files.jsondepth import json_depth
from skidnav.files.saved import nesting_depth, parse_json


def scanned_depth(data: bytes) -> int:
    """The pre-check's rule, one byte at a time: a backslash escapes the next byte, an unescaped
    quote toggles the string state, brackets outside strings count."""
    inside = escaped = False
    depth = deepest = 0
    for byte in data:
        was_escaped, escaped = escaped, byte == ord("\\") and not escaped
        if byte == ord('"') and not was_escaped:
            inside = not inside
        elif not inside and byte in b"[{":
            depth += 1
            deepest = max(deepest, depth)
        elif not inside and byte in b"]}":
            depth -= 1
    return deepest


JSON_VALUES = st.recursive(
    st.none() | st.booleans() | st.integers() | st.text(alphabet='[]{}"\\ab\n€'),
    lambda children: (
        st.lists(children, max_size=4)
        | st.dictionaries(st.text(alphabet='[]{}"\\k', max_size=5), children, max_size=4)
    ),
    max_leaves=30,
)


@pytest.mark.parametrize("block", [1, 2, 3, 7, 4096])
def test_the_blocks_scan_as_one_byte_at_a_time(block: int, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(jsondepth, "BLOCK_BYTES", block)

    @settings(max_examples=150, deadline=None, database=None)
    @given(st.binary(max_size=64) | st.lists(st.sampled_from(list(b'"\\[]{}a')), max_size=64))
    def check(data: bytes | list[int]) -> None:
        data = bytes(data)
        assert json_depth(data) == scanned_depth(data)

    check()


@settings(max_examples=200, deadline=None, database=None)
@given(JSON_VALUES, st.sampled_from([1, 5, 4096]))
def test_the_depth_of_valid_json_is_its_nesting(value: Any, block: int) -> None:
    text = json.dumps(value, ensure_ascii=False)
    original, jsondepth.BLOCK_BYTES = jsondepth.BLOCK_BYTES, block
    try:
        assert json_depth(text) == json_depth(text.encode()) == nesting_depth(value)
    finally:
        jsondepth.BLOCK_BYTES = original


def test_a_long_string_literal_is_checked_in_linear_memory() -> None:
    size = 8 * 2**20
    data = b'{"a": "' + b"x" * size + b'"}'
    tracemalloc.start()
    try:
        assert json_depth(data) == 1
        scan_peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.reset_peak()
        assert len(parse_json(data, "literal.json")["a"]) == size
        parse_peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert scan_peak < 4 * jsondepth.BLOCK_BYTES + 2**20  # the blocks, not the text
    assert parse_peak < 3 * size  # the text once as str, once parsed
