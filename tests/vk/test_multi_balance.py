"""Dynamic sort-first balance (pure): damped shares from per-device times."""

from __future__ import annotations

import pytest

from rgraph.vk.multi.balance import MIN_SHARE, rebalance


def test_equal_speeds_keep_equal_shares():
    assert rebalance((0.5, 0.5), (10.0, 10.0)) == pytest.approx((0.5, 0.5))


def test_a_device_twice_as_fast_converges_to_two_thirds():
    w = (0.5, 0.5)
    for _ in range(30):
        # device 0 takes 1 ms per share unit, device 1 takes 2 ms
        w = rebalance(w, (w[0] * 1.0, w[1] * 2.0), damping=0.5)
    assert w == pytest.approx((2 / 3, 1 / 3), abs=1e-3)


def test_damping_moves_part_of_the_way():
    w = rebalance((0.5, 0.5), (1.0, 3.0), damping=0.5)  # target 0.75/0.25
    assert w == pytest.approx((0.625, 0.375))


def test_a_very_slow_device_keeps_a_sliver():
    w = rebalance((0.5, 0.5), (1.0, 1e6), damping=1.0)
    assert min(w) >= MIN_SHARE / (1 + MIN_SHARE) and sum(w) == pytest.approx(1.0)


def test_quantized_bands_cover_the_height_in_steps():
    from rgraph.vk.multi.balance import quantize

    assert quantize((0.5, 0.5), 64, 8) == (32, 32)
    assert quantize((0.7, 0.3), 64, 8) == (48, 16)  # 44.8 rows -> 48
    assert quantize((0.99, 0.01), 64, 8) == (56, 8)  # every band keeps a step
    assert quantize((1.0, 1.0, 1.0), 50, 8) == (16, 16, 18)
    assert sum(quantize((0.3, 0.2, 0.5), 1080, 8)) == 1080


def test_settled_shares_stop_changing_the_layout():
    """Shares converging (a device 3x faster): the quantized layout changes a few times, then never."""
    from rgraph.vk.multi.balance import quantize

    w, layouts = (0.5, 0.5), []
    for _ in range(40):
        layouts.append(quantize(w, 1080, 8))
        w = rebalance(w, (w[0] * 1.0, w[1] * 3.0), damping=0.5)
    changes = sum(1 for a, b in zip(layouts, layouts[1:], strict=False) if a != b)
    assert changes <= 8 and len(set(layouts[-20:])) == 1
    assert layouts[-1] == (808, 272)  # 3/4 of 1080 = 810 rows -> 808
