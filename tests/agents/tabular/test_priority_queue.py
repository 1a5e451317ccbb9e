"""The binary-heap priority queue (skidnav.agents.tabular.priority_queue)."""

from __future__ import annotations

from hypothesis import given, settings
from hypothesis import strategies as st

from skidnav.agents.tabular.priority_queue import heap_clear, heap_pop, heap_push, make_heap

N_ITEMS = 30
pushes = st.lists(
    st.tuples(st.integers(0, N_ITEMS - 1), st.floats(0.0, 100.0, allow_nan=False)), max_size=80
)


@settings(max_examples=150, deadline=None)
@given(pushes)
def test_pops_in_priority_order_keeping_each_items_largest_priority(
    operations: list[tuple[int, float]],
) -> None:
    heap = make_heap(N_ITEMS)
    expected: dict[int, float] = {}
    for item, priority in operations:
        heap_push(heap, item, priority)
        expected[item] = max(priority, expected.get(item, priority))
    popped = [heap_pop(heap) for _ in range(int(heap.size[0]))]
    priorities = [priority for _, priority in popped]
    assert priorities == sorted(priorities, reverse=True)
    assert dict(popped) == expected
    assert len(popped) == len(expected)
    assert (heap.position == -1).all()


@settings(max_examples=50, deadline=None)
@given(pushes, st.integers(0, 10))
def test_interleaved_pops_always_return_the_current_maximum(
    operations: list[tuple[int, float]], pop_every: int
) -> None:
    heap = make_heap(N_ITEMS)
    queued: dict[int, float] = {}
    for index, (item, priority) in enumerate(operations):
        heap_push(heap, item, priority)
        queued[item] = max(priority, queued.get(item, priority))
        if pop_every and index % pop_every == 0:
            item_out, priority_out = heap_pop(heap)
            assert priority_out == max(queued.values())
            assert queued.pop(item_out) == priority_out
    assert int(heap.size[0]) == len(queued)
    heap_clear(heap)
    assert int(heap.size[0]) == 0 and (heap.position == -1).all()
