"""Seeded random placement instances shaped like render-graph transients."""

from __future__ import annotations

import random

from rgraph.memory.model import Block, align_up

KIB = 1024
MIB = 1024 * KIB


def random_blocks(count: int, seed: int, passes: int | None = None) -> list[Block]:
    """``count`` blocks over ``passes`` passes (default count // 2): mostly short lifetimes,
    a few long ones; image-like sizes (64 KiB aligned, optimal class) and buffers (256 B
    aligned, linear class)."""
    rng = random.Random(seed)
    passes = passes or max(count // 2, 4)
    blocks = []
    for i in range(count):
        start = rng.randrange(passes)
        length = int(rng.expovariate(1 / 4)) if rng.random() < 0.85 else rng.randrange(passes)
        end = min(passes - 1, start + length)
        if rng.random() < 0.7:
            w, h = rng.choice([(3840, 2160), (1920, 1080), (960, 540), (480, 270), (1024, 1024), (512, 512)])
            size = align_up(w * h * rng.choice([1, 2, 4, 8, 16]), 64 * KIB)
            blocks.append(Block(f"img{i}", start, end, size, 64 * KIB, "device_local_optimal"))
        else:
            size = align_up(int(rng.lognormvariate(12, 2.0)) + 1, 256)
            blocks.append(Block(f"buf{i}", start, end, size, 256, "device_local_linear"))
    return blocks
