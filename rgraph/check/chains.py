"""Execution dependency chains on one queue, shared by every record on it.

Execution dependencies of a barrier are global: a barrier orders every earlier command
whose stages meet its source scope before every later command whose stages meet its
destination scope, whatever resource the barrier names. So what a past access is
ordered before depends only on its stages and on the barriers recorded since, not on
the resource. Records therefore point at a *class*; all records of a class share

- ``C``: the stages whose presence in a barrier's source scope extends the chain (the
  access's own stages plus every stage the chain has reached), and
- ``R``: the stages the chain has reached (later commands in those stages are ordered
  after the access).

A barrier batch (one vkCmdPipelineBarrier2) updates every class at once: each barrier
whose source stages meet ``C`` adds its destination stages to both masks. Barriers of
one batch do not chain with one another. Classes whose masks become equal merge
(union-find), so the number of live classes stays small however long the frame is.
"""

from __future__ import annotations

BarrierStages = list[tuple[int, int]]  # (src stages, dst stages) of each barrier in a batch


def batch_add(pairs: BarrierStages, chain_stages: int) -> int:
    """Destination stages that a batch adds to a chain whose source-side stages are given."""
    add = 0
    for src, dst in pairs:
        if src & chain_stages:
            add |= dst
    return add


class ChainRegistry:
    """Union-find of chain classes for one queue, keyed by their (C, R) masks."""

    def __init__(self) -> None:
        self._parent: list[int] = []
        self._c: list[int] = []
        self._r: list[int] = []
        self._roots: dict[tuple[int, int], int] = {}
        self._born: dict[tuple[int, int], int] = {}

    def _new(self, c: int, r: int) -> int:
        self._parent.append(len(self._parent))
        self._c.append(c)
        self._r.append(r)
        return len(self._parent) - 1

    def find(self, x: int) -> int:
        parent = self._parent
        root = x
        while parent[root] != root:
            root = parent[root]
        while parent[x] != root:
            parent[x], x = root, parent[x]
        return root

    def masks(self, x: int) -> tuple[int, int]:
        """(C, R) of the class that ``x`` belongs to, as of now."""
        root = self.find(x)
        return self._c[root], self._r[root]

    def reach(self, x: int) -> int:
        return self._r[self.find(x)]

    def get(self, c: int, r: int) -> int:
        """A class with these masks, outside a batch (e.g. a fresh access: ``get(stage, 0)``)."""
        key = (c, r)
        found = self._roots.get(key)
        if found is None:
            found = self._roots[key] = self._new(c, r)
        return found

    def born(self, c: int, r: int) -> int:
        """A class created while a batch is being applied: its masks are already final for
        this batch, so ``apply_batch`` must not extend it."""
        key = (c, r)
        found = self._born.get(key)
        if found is None:
            found = self._born[key] = self._new(c, r)
        return found

    def apply_batch(self, pairs: BarrierStages) -> None:
        """Extend every pre-existing class by one barrier batch, then admit the born ones."""
        if pairs:
            merged: dict[tuple[int, int], int] = {}
            for (c, r), root in self._roots.items():
                add = batch_add(pairs, c)
                key = (c | add, r | add)
                if add:
                    self._c[root], self._r[root] = key
                other = merged.get(key)
                if other is None:
                    merged[key] = root
                else:
                    self._parent[root] = other
            self._roots = merged
        for key, root in self._born.items():
            other = self._roots.get(key)
            if other is None:
                self._roots[key] = root
            else:
                self._parent[root] = other
        self._born = {}

    def __len__(self) -> int:
        return len(self._roots)
