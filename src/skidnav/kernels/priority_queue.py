"""A max-priority queue of integer items as a binary heap over NumPy arrays (compiled).

Used by prioritized sweeping (Sutton & Barto (2018) §8.4) and by any planner that orders its
updates by priority. Items are integers in ``[0, n_items)`` — for the tabular agents the flat pair
index ``state · n_actions + action``. Each item is in the queue at most once: pushing an item that
is already queued keeps the larger of the two priorities (the book's "if already in the queue, keep
only the higher priority").

Storage (:class:`HeapArrays`): ``priority`` float64 (n_items,) and ``item`` int64 (n_items,) hold
the heap in their first ``size[0]`` slots (slot 0 is the maximum; the children of slot k are
2k+1 and 2k+2); ``position`` int64 (n_items,) maps an item to its slot or −1 when not queued;
``size`` int64 (1,). The queue is mutated in place, so compiled planners can share it.

>>> queue = make_heap(5)
>>> for item, priority in [(3, 0.5), (1, 2.0), (4, 1.0), (3, 3.0), (1, 0.1)]:
...     heap_push(queue, item, priority)
>>> [heap_pop(queue) for _ in range(int(queue.size[0]))]
[(3, 3.0), (1, 2.0), (4, 1.0)]
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from skidnav._jit import jit
from skidnav.kernels.tabular import inline_jit


class HeapArrays(NamedTuple):
    """The heap's arrays (see the module docstring for shapes and meaning)."""

    priority: np.ndarray
    item: np.ndarray
    position: np.ndarray
    size: np.ndarray


def make_heap(n_items: int) -> HeapArrays:
    """An empty queue for items ``0 .. n_items − 1`` (memory: 24 bytes per possible item)."""
    if n_items < 1:
        raise ValueError(f"expected n_items >= 1, got {n_items}")
    return HeapArrays(
        priority=np.zeros(n_items, dtype=np.float64),
        item=np.zeros(n_items, dtype=np.int64),
        position=np.full(n_items, -1, dtype=np.int64),
        size=np.zeros(1, dtype=np.int64),
    )


@inline_jit
def _swap(heap: HeapArrays, slot_a: int, slot_b: int) -> None:
    item_a = heap.item[slot_a]
    item_b = heap.item[slot_b]
    priority_a = heap.priority[slot_a]
    heap.priority[slot_a] = heap.priority[slot_b]
    heap.priority[slot_b] = priority_a
    heap.item[slot_a] = item_b
    heap.item[slot_b] = item_a
    heap.position[item_b] = slot_a
    heap.position[item_a] = slot_b


@inline_jit
def _sift_up(heap: HeapArrays, slot: int) -> None:
    while slot > 0:
        parent = (slot - 1) // 2
        if heap.priority[parent] >= heap.priority[slot]:
            return
        _swap(heap, slot, parent)
        slot = parent


@inline_jit
def _sift_down(heap: HeapArrays, slot: int) -> None:
    size = heap.size[0]
    while True:
        largest = slot
        left = 2 * slot + 1
        right = left + 1
        if left < size and heap.priority[left] > heap.priority[largest]:
            largest = left
        if right < size and heap.priority[right] > heap.priority[largest]:
            largest = right
        if largest == slot:
            return
        _swap(heap, slot, largest)
        slot = largest


@inline_jit
def heap_push(heap: HeapArrays, item: int, priority: float) -> None:
    """Queue ``item`` with ``priority``; if already queued, keep the larger priority."""
    slot = heap.position[item]
    if slot >= 0:
        if priority > heap.priority[slot]:
            heap.priority[slot] = priority
            _sift_up(heap, slot)
        return
    slot = heap.size[0]
    heap.size[0] = slot + 1
    heap.priority[slot] = priority
    heap.item[slot] = item
    heap.position[item] = slot
    _sift_up(heap, slot)


@inline_jit
def heap_pop(heap: HeapArrays) -> tuple[int, float]:
    """Remove and return ``(item, priority)`` of the highest priority; the queue must not be
    empty (check ``heap.size[0] > 0``)."""
    top_item = heap.item[0]
    top_priority = heap.priority[0]
    last = heap.size[0] - 1
    _swap(heap, 0, last)
    heap.size[0] = last
    heap.position[top_item] = -1
    _sift_down(heap, 0)
    return int(top_item), float(top_priority)


@jit
def heap_clear(heap: HeapArrays) -> None:
    """Empty the queue."""
    for slot in range(heap.size[0]):
        heap.position[heap.item[slot]] = -1
    heap.size[0] = 0
