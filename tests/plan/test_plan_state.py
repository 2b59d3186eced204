"""rgraph.plan.state.carries_state on hand-made plans."""

from __future__ import annotations

from rgraph.plan.state import carries_state


def _plan(lifetime: str, *accesses: tuple[str, bool]) -> dict:
    passes = [{"accesses": [{"resource": "h", "access": list(access.split("|")), "write": write}]}
              for access, write in accesses]
    return {"resources": [{"name": "h", "lifetime": lifetime}], "passes": passes}


def test_history_read_before_written_carries_state() -> None:
    assert carries_state(_plan("persistent", ("SHADER_SAMPLED_READ", False), ("SHADER_STORAGE_WRITE", True)))
    assert carries_state(_plan("persistent", ("COLOR_ATTACHMENT_READ|COLOR_ATTACHMENT_WRITE", True)))


def test_written_first_or_read_only_carries_none() -> None:
    assert not carries_state(_plan("persistent", ("SHADER_STORAGE_WRITE", True), ("SHADER_SAMPLED_READ", False)))
    assert not carries_state(_plan("imported", ("SHADER_SAMPLED_READ", False)))
    assert not carries_state(_plan("transient", ("SHADER_SAMPLED_READ", False), ("SHADER_STORAGE_WRITE", True)))
