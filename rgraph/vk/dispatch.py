"""Workgroup counts for one-dimensional work over more groups than one dispatch dimension holds.

``maxComputeWorkGroupCount[0]`` is only guaranteed to be 65,535 (lavapipe's and many GPUs'
value): a cull pass of 256 threads per group stops at 16,776,960 instances, light setup (64)
at 4,194,240 lights. :func:`groups_2d` folds the groups into rows of at most
:data:`MAX_GROUPS_X`; shaders number their group ``gl_WorkGroupID.y * gl_NumWorkGroups.x +
gl_WorkGroupID.x`` and drop threads past the count (the last row may be partly empty).
"""

from __future__ import annotations

MAX_GROUPS_X = 65535  # the minimum of maxComputeWorkGroupCount[0..2] every device supports
MAX_GROUPS_Y = 65535


def groups_2d(items: int, group: int) -> tuple[int, int]:
    """``(x, y)`` workgroups covering ``items`` threads in groups of ``group`` (at least one group),
    with ``x <= MAX_GROUPS_X`` and ``y <= MAX_GROUPS_Y``."""
    groups = max(1, -(-items // group))
    x = min(groups, MAX_GROUPS_X)
    y = -(-groups // x)
    if y > MAX_GROUPS_Y:
        raise ValueError(f"{items:,} items in groups of {group} need {groups:,} workgroups, "
                         f"over {MAX_GROUPS_X} x {MAX_GROUPS_Y}")
    return x, y
