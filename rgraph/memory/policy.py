"""Placement policies and their textual names (``aliased``, ``blocks:64MiB``, ...)."""

from __future__ import annotations

import re
from dataclasses import dataclass

from rgraph.errors import quote

MIB = 1 << 20
BLOCK_SIZES_MIB = (4, 16, 64, 256)
POLICY_NAMES = ("dedicated", "aliased", "optimal", "tlsf", "blocks:SIZE")
VALID_POLICIES_TEXT = (
    "dedicated, aliased, optimal, tlsf, blocks:SIZE with SIZE one of "
    + ", ".join(f"{m}MiB" for m in BLOCK_SIZES_MIB)
)


@dataclass(frozen=True)
class Policy:
    kind: str  # dedicated | aliased | optimal | tlsf | blocks
    block_bytes: int = 0  # blocks only

    def __str__(self) -> str:
        return f"blocks:{self.block_bytes // MIB}MiB" if self.kind == "blocks" else self.kind


_BLOCKS = re.compile(r"^blocks:(\d+)\s*(mib|mb|m)?$", re.IGNORECASE)


def parse_policy(text: str | Policy) -> Policy:
    """Parse a policy name; raise ValueError naming the valid policies if it is not one."""
    if isinstance(text, Policy):
        return text
    cleaned = text.strip()
    lowered = cleaned.lower()
    if lowered in ("dedicated", "aliased", "optimal", "tlsf"):
        return Policy(lowered)
    match = _BLOCKS.match(lowered)
    if match:
        mib = int(match.group(1))
        if mib in BLOCK_SIZES_MIB:
            return Policy("blocks", mib * MIB)
        raise ValueError(
            f"unknown block size in policy {quote(text)}: valid block sizes are "
            + ", ".join(f"{m}MiB" for m in BLOCK_SIZES_MIB)
        )
    raise ValueError(f"unknown placement policy {quote(text)}; valid policies: {VALID_POLICIES_TEXT}")
