"""An endless, deterministic supply of block preorderings for the search's dives.

First MiniMalloc's static preorderings (``search.PREORDERINGS``), then the same ones with
seeded noise on the ranks: a block moves by up to ``NOISE`` of the block count. Dives that
fail under one ordering often succeed under a near one, so restarts under perturbed orders
beat deeper backtracking under a fixed one. The seed is fixed: same input, same orders.
"""

from __future__ import annotations

import random

from rgraph.memory.instance import Instance
from rgraph.memory.search import PREORDERINGS, preorder

#: How far (as a fraction of the block count) noise may move a block in a preordering.
NOISE = 0.1
SEED = 0x5EED


class Preorders:
    """``next()`` gives the static preorderings in turn, then perturbed copies of them."""

    def __init__(self, inst: Instance, seed: int = SEED):
        self.base = [preorder(inst, h) for h in PREORDERINGS]
        self.rng = random.Random(seed)
        self.count = 0

    def next(self) -> list[int]:
        base = self.base[self.count % len(self.base)]
        self.count += 1
        if self.count <= len(self.base):
            return base
        return perturbed(base, self.rng, NOISE)


def perturbed(order: list[int], rng: random.Random, noise: float) -> list[int]:
    """``order`` with each rank shifted by a uniform amount in [0, noise * len(order))."""
    spread = noise * len(order)
    key = {block: rank + rng.random() * spread for rank, block in enumerate(order)}
    return sorted(order, key=key.__getitem__)
