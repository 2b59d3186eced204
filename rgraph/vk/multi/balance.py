"""Dynamic load balance for sort-first (``--balance dynamic``): tile heights from each device's
measured time for its tile, damped, as Equalizer's load equalizer does.

Each frame, device ``i`` rendered share ``w_i`` of the rows in ``t_i`` ms (the GPU time of its
tiled passes), so its speed is ``w_i / t_i``; the shares that would finish together are the
speeds normalised, and the next shares move ``damping`` of the way there (damping < 1 keeps a
noisy frame from swinging the split). Heterogeneous pairs (lavapipe + a GPU) settle at very
unequal bands. A floor keeps every device a sliver of the screen so it keeps being measured.

``DynamicBalance`` applies the shares in steps of ``QUANTUM_ROWS`` rows and keeps the loaded
executable of each band layout, so a plan is re-compiled and loaded only when a band edge
crosses a step (none once the shares settle), not every frame.
"""

from __future__ import annotations

from collections import OrderedDict
from collections.abc import Callable, Sequence
from typing import Any

MIN_SHARE = 0.02
#: band heights move in steps of this many rows (a new layout = a new plan load)
QUANTUM_ROWS = 8


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


def quantize(weights: Sequence[float], height: int, quantum: int = QUANTUM_ROWS) -> tuple[int, ...]:
    """Rows per band for ``weights``: multiples of ``quantum`` (the last band takes the rest),
    at least one quantum each where the height allows, summing to ``height``."""
    n = len(weights)
    q = max(1, min(quantum, height // n))
    total = sum(weights)
    rows, edge, acc = [], 0, 0.0
    for i, w in enumerate(weights[:-1]):
        acc += w
        room = height - q * (n - 1 - i)  # leave every later band a quantum
        nxt = min(room, max(edge + q, round(height * acc / total / q) * q))
        rows.append(nxt - edge)
        edge = nxt
    rows.append(height - edge)
    return tuple(rows)


class DynamicBalance:
    """``--balance dynamic`` for sort-first without re-loading the plan every frame.

    The shares move continuously (``rebalance``), but the bands follow them in steps of
    ``quantum`` rows, and the executable of each band layout is kept (the ``keep`` most recent
    ones): a new plan is compiled and loaded only when a share crosses a step, and none once
    the shares settle. Frame numbers continue across layouts (``MultiExecutable.seek``), so
    every frame-dependent value is the one-device frame's; a layout's persistent resources are
    its own (a temporal pass restarts its history after a layout change).

    Quacks like the ``MultiExecutable`` it currently runs (``plan``, ``plans``, ``read_back``).
    """

    def __init__(self, gpus: list[Any], compile_with: Callable[[tuple[float, ...] | None], Any], *,
                 damping: float = 0.5, quantum: int = QUANTUM_ROWS, keep: int = 4, **multi_options: Any) -> None:
        first = compile_with(None)
        self.height = sum(rows for _y, rows in first.multi_device["bands"])
        self.gpus, self.compile_with, self.damping, self.quantum, self.keep = gpus, compile_with, damping, quantum, keep
        self.options = multi_options
        self.weights: tuple[float, ...] = tuple(1.0 / len(gpus) for _ in gpus)
        self.rows = quantize(self.weights, self.height, quantum)
        self.cache: OrderedDict[tuple[int, ...], Any] = OrderedDict()
        self.loads = 0
        self.frames = 0
        self.history: list[tuple[float, ...]] = []  # shares before each frame
        self.layouts: list[tuple[int, ...]] = []  # rows per band of each frame
        self.current: Any = None
        self._first = first

    def _executable(self) -> Any:
        from rgraph.vk.multi.run import MultiExecutable

        if self.rows in self.cache:
            self.cache.move_to_end(self.rows)
            return self.cache[self.rows]
        plan = self._first if self.loads == 0 else self.compile_with(tuple(float(r) for r in self.rows))
        if self.loads == 0 and [r for _y, r in plan.multi_device["bands"]] != list(self.rows):
            plan = self.compile_with(tuple(float(r) for r in self.rows))
        multi = MultiExecutable(self.gpus, plan, **self.options)
        self.loads += 1
        self.cache[self.rows] = multi
        while len(self.cache) > self.keep:
            _rows, old = self.cache.popitem(last=False)
            old.close()
        return multi

    def run(self, frames: int = 1) -> Any:
        """``frames`` frames, re-balancing after each; the last frame's ``MultiSummary``."""
        summary = None
        for _ in range(frames):
            self.history.append(self.weights)
            self.layouts.append(self.rows)
            multi = self.current = self._executable()
            multi.seek(self.frames)
            summary = multi.run(1)
            self.frames += 1
            times = tile_times(multi.plan, summary.device_passes)
            if all(t > 0 for t in times):
                self.weights = rebalance(self.weights, times, self.damping)
                self.rows = quantize(self.weights, self.height, self.quantum)
        return summary

    @property
    def plan(self) -> Any:
        return self.current.plan

    @property
    def plans(self) -> list[dict]:
        return self.current.plans

    def read_back(self) -> dict[tuple, bytes]:
        return self.current.read_back()

    def close(self) -> None:
        for multi in self.cache.values():
            multi.close()
        self.cache.clear()


def run_balanced(gpus: list[Any], compile_with: Callable[[tuple[float, ...] | None], Any], frames: int,
                 damping: float = 0.5, **multi_options: Any) -> tuple[DynamicBalance, Any, list[tuple[float, ...]]]:
    """``frames`` frames of ``DynamicBalance``: (the balancer, the last summary, shares per frame).
    ``compile_with(weights)`` compiles the split plan for those shares (None: equal);
    ``multi_options``: ``MultiExecutable``'s (transfer, pipelined)."""
    balance = DynamicBalance(gpus, compile_with, damping=damping, **multi_options)
    summary = balance.run(frames)
    return balance, summary, balance.history
