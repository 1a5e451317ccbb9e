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

Speed: the helpers are inlined into the compiled planners and each has **one exit**, every
array read or written last on that one path. numba then removes the reference counting of the
arrays bound to the helper's parameters (its LLVM pass pairs an increment with a decrement only
when the decrement post-dominates it); with early returns it cannot, and the atomic increments
and decrements of the four arrays at every push, pop and swap took most of prioritized
sweeping's time. Slots and items are non-negative where they index, and are cast to
``np.uint64`` there: numba wraps a signed index that may be negative (a shift, a mask and the
array's length reloaded at every access), not an unsigned one — a quarter of the instructions of
a sift. The values are the same, compiled or not.

>>> queue = make_heap(5)
>>> for item, priority in [(3, 0.5), (1, 2.0), (4, 1.0), (3, 3.0), (1, 0.1)]:
...     heap_push(queue, item, priority)
>>> [heap_pop(queue) for _ in range(int(queue.size[0]))]
[(3, 3.0), (1, 2.0), (4, 1.0)]
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from skidnav._jit import inline_jit, jit


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
def sift_up(
    priority: np.ndarray, item: np.ndarray, position: np.ndarray, slot: int, value: float, key: int
) -> None:
    """Place ``key`` with priority ``value`` at ``slot`` or above it: each parent of lower
    priority moves down one level (the same final heap as swapping level by level)."""
    while slot > 0:
        parent = (slot - 1) // 2
        above = priority[np.uint64(parent)]
        if above >= value:
            break
        moved = item[np.uint64(parent)]
        priority[np.uint64(slot)] = above
        item[np.uint64(slot)] = moved
        position[np.uint64(moved)] = slot
        slot = parent
    priority[np.uint64(slot)] = value
    item[np.uint64(slot)] = key
    position[np.uint64(key)] = slot


@inline_jit
def sift_down(
    priority: np.ndarray, item: np.ndarray, position: np.ndarray, size: int, value: float, key: int
) -> None:
    """Place ``key`` with priority ``value`` from the root down among the first ``size`` slots:
    at each level the larger child (the left one on ties) moves up if it beats ``value`` (the
    same final heap as swapping level by level)."""
    slot = 0
    while True:
        largest, best = slot, value
        left = 2 * slot + 1
        if left < size and priority[np.uint64(left)] > best:
            largest, best = left, priority[np.uint64(left)]
        if left + 1 < size and priority[np.uint64(left + 1)] > best:
            largest = left + 1
        if largest == slot:
            break
        moved = item[np.uint64(largest)]
        priority[np.uint64(slot)] = priority[np.uint64(largest)]
        item[np.uint64(slot)] = moved
        position[np.uint64(moved)] = slot
        slot = largest
    priority[np.uint64(slot)] = value
    item[np.uint64(slot)] = key
    position[np.uint64(key)] = slot


@inline_jit
def push(
    priority: np.ndarray,
    item: np.ndarray,
    position: np.ndarray,
    size: np.ndarray,
    key: int,
    value: float,
) -> None:
    """:func:`heap_push` on the heap's arrays. A queued item whose priority does not grow sifts
    with its own priority, which moves nothing: one path, see the module docstring."""
    slot = position[np.uint64(key)]
    n_queued = size[0]
    if slot < 0:
        slot = n_queued
        n_queued += 1
    elif priority[np.uint64(slot)] >= value:
        value = priority[np.uint64(slot)]
    size[0] = n_queued
    sift_up(priority, item, position, slot, value, key)


@inline_jit
def pop(
    priority: np.ndarray, item: np.ndarray, position: np.ndarray, size: np.ndarray
) -> tuple[int, float]:
    """:func:`heap_pop` on the heap's arrays: the last entry sifts down from the root, and the
    freed slot keeps the popped entry (as a swap with the root would leave it)."""
    top_item = item[0]
    top_priority = priority[0]
    last = size[0] - 1
    size[0] = last
    sift_down(priority, item, position, last, priority[np.uint64(last)], item[np.uint64(last)])
    priority[np.uint64(last)] = top_priority
    item[np.uint64(last)] = top_item
    position[np.uint64(top_item)] = -1
    return int(top_item), float(top_priority)


@inline_jit
def heap_push(heap: HeapArrays, item: int, priority: float) -> None:
    """Queue ``item`` with ``priority``; if already queued, keep the larger priority."""
    push(heap.priority, heap.item, heap.position, heap.size, item, priority)


@inline_jit
def heap_pop(heap: HeapArrays) -> tuple[int, float]:
    """Remove and return ``(item, priority)`` of the highest priority; the queue must not be
    empty (check ``heap.size[0] > 0``)."""
    return pop(heap.priority, heap.item, heap.position, heap.size)


@jit
def heap_clear(heap: HeapArrays) -> None:
    """Empty the queue."""
    for slot in range(heap.size[0]):
        heap.position[heap.item[slot]] = -1
    heap.size[0] = 0
