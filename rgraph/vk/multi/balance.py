"""Dynamic load balance for sort-first (``--balance dynamic``): tile heights from each device's
measured time for its tile, damped, as Equalizer's load equalizer does.

Each frame, device ``i`` rendered share ``w_i`` of the rows in ``t_i`` ms (the GPU time of its
tiled passes), so its speed is ``w_i / t_i``; the shares that would finish together are the
speeds normalised, and the next shares move ``damping`` of the way there (damping < 1 keeps a
noisy frame from swinging the split). Heterogeneous pairs (lavapipe + a GPU) settle at very
unequal bands. A floor keeps every device a sliver of the screen so it keeps being measured.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

MIN_SHARE = 0.02


def rebalance(weights: Sequence[float], times_ms: Sequence[float], damping: float = 0.5) -> tuple[float, ...]:
    """The next shares (summing to 1) from this frame's shares and per-device times."""
    total = sum(weights)
    shares = [w / total for w in weights]
    speeds = [s / max(t, 1e-6) for s, t in zip(shares, times_ms, strict=True)]
    target = [v / sum(speeds) for v in speeds]
    mixed = [max(MIN_SHARE, (1 - damping) * s + damping * g) for s, g in zip(shares, target, strict=True)]
    return tuple(m / sum(mixed) for m in mixed)


def tile_times(plan: Any, device_passes: Sequence[dict[str, float]]) -> list[float]:
    """Per device, the GPU ms of its tiled passes (the work the band decides)."""
    tiled = set((plan.multi_device or {}).get("tiled", ()))
    return [sum(ms for name, ms in passes.items() if name in tiled) for passes in device_passes]


def run_balanced(gpus: list[Any], compile_with: Callable[[tuple[float, ...] | None], Any], frames: int,
                 damping: float = 0.5) -> tuple[Any, Any, list[tuple[float, ...]]]:
    """``frames`` frames, re-splitting after each: (last MultiExecutable, its summary, shares per frame).

    ``compile_with(weights)`` compiles the split plan for those shares (None: equal). Each
    frame loads the new plan afresh (the bands are in the recorded scissors)."""
    from rgraph.vk.multi.run import MultiExecutable

    weights: tuple[float, ...] = tuple(1.0 / len(gpus) for _ in gpus)
    history = []
    multi = summary = None
    for _ in range(frames):
        history.append(weights)
        if multi is not None:
            multi.close()
        plan = compile_with(weights)
        multi = MultiExecutable(gpus, plan)
        summary = multi.run(1)
        times = tile_times(plan, summary.device_passes)
        if all(t > 0 for t in times):
            weights = rebalance(weights, times, damping)
    return multi, summary, history
