"""A lost device must not turn the error that lost it into a traceback at teardown."""

from __future__ import annotations

from types import SimpleNamespace

import pytest

import rgraph.vk.device as device_module


class _Lost(Exception):
    pass


class _OutOfMemory(Exception):
    pass


def _fake_vk(error: type[Exception]) -> SimpleNamespace:
    def wait_idle(handle: object) -> None:
        raise error()

    return SimpleNamespace(VkErrorDeviceLost=_Lost, vkDeviceWaitIdle=wait_idle)


def test_lost_device_counts_as_idle(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(device_module, "vk", lambda: _fake_vk(_Lost))
    device_module.wait_idle_for_teardown(object())  # no exception


def test_other_wait_errors_still_raise(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(device_module, "vk", lambda: _fake_vk(_OutOfMemory))
    with pytest.raises(_OutOfMemory):
        device_module.wait_idle_for_teardown(object())
