"""Shared by the multi-device tests (tests/vk/test_multi_*.py): two validated logical devices
of one physical device, and the probe's data check of a composited frame."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

from rgraph.api import open_device
from rgraph.probe.check import check_outputs


def validated_pair(count: int = 2) -> Iterator[list[Any]]:
    """Body of a module fixture: ``count`` logical devices on device 0, validation on; every
    one must close without a message."""
    devices = [open_device(validate=True, device=0, verbose=False) for _ in range(count)]
    yield devices
    for g in devices:
        assert g.close() == [], "validation messages"


def assert_data_ok(reference: dict, data: dict, frames: int) -> None:
    """The probe's data check of device 0's own resources (not the received buffers) against
    the one-device plan ``reference`` after ``frames`` frames."""
    known = {r["name"] for r in reference["resources"]}
    verdict = check_outputs(reference, {k: v for k, v in data.items() if k[0] in known}, frames)
    assert verdict.ok is True, [str(m) for m in verdict.mismatches]
