# SPDX-FileCopyrightText: 2026 fourws developers
# SPDX-License-Identifier: Apache-2.0
"""A bounded memo of what the analysis computes from a vehicle and a law and reuses (critical
speeds, eigenvalue sweeps, Jacobians): the runs of one car and law, a demo's laws of one car,
a study's points share them; a Monte Carlo study, whose every vehicle has its own, does not
keep them all."""

from __future__ import annotations

from collections import OrderedDict
from typing import Callable, Generic, TypeVar

T = TypeVar("T")


class Memo(Generic[T]):
    """The ``size`` most recently used results, by a string key (e.g. a vehicle's
    ``cache_key()`` with the law).

    A computation that returns None (it failed, and said why to whoever asked) or raises is
    not kept: the next caller computes it again and is told why itself.
    """

    def __init__(self, size: int) -> None:
        if size < 1:
            raise ValueError(f"a memo keeps at least one result, got size {size}")
        self.size = int(size)
        self._items: OrderedDict[str, T] = OrderedDict()

    def get(self, key: str, compute: Callable[[], T | None]) -> T | None:
        """The result of ``key``, computed by ``compute`` unless kept (then the kept object
        itself)."""
        if key in self._items:
            self._items.move_to_end(key)
            return self._items[key]
        found = compute()
        if found is not None:
            self._items[key] = found
            if len(self._items) > self.size:
                self._items.popitem(last=False)  # the least recently used
        return found

    def __len__(self) -> int:
        return len(self._items)


__all__ = ["Memo"]
