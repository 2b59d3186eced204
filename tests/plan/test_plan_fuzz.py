"""Any edit of a valid plan either loads or gives one located RGraphError line, never a crash."""

from __future__ import annotations

import json

from hypothesis import given, settings
from hypothesis import strategies as st
from locations import TESTS

from rgraph import plan as rplan
from rgraph.errors import RGraphError

DOC = json.loads((TESTS / "plans" / "async_compute.json").read_text())

JSON_VALUES = st.recursive(
    st.none() | st.booleans() | st.integers(-(2**70), 2**70) | st.floats(allow_nan=False) | st.text(max_size=8),
    lambda inner: st.lists(inner, max_size=3) | st.dictionaries(st.text(max_size=6), inner, max_size=3),
    max_leaves=6,
)


def _paths(value, prefix=()):
    yield prefix
    if isinstance(value, dict):
        for k, v in value.items():
            yield from _paths(v, (*prefix, k))
    elif isinstance(value, list):
        for i, v in enumerate(value):
            yield from _paths(v, (*prefix, i))


PATHS = [p for p in _paths(DOC) if p]


@settings(max_examples=80, deadline=None)
@given(path=st.sampled_from(PATHS), value=JSON_VALUES, delete=st.booleans())
def test_edits_load_or_fail_with_one_line(path, value, delete):
    doc = json.loads(json.dumps(DOC))
    parent = doc
    for part in path[:-1]:
        parent = parent[part]
    if delete:
        del parent[path[-1]]
    else:
        parent[path[-1]] = value
    text = json.dumps(doc, indent=1)
    try:
        plan = rplan.parse(text, "p.json")
    except RGraphError as exc:
        message = str(exc)
        assert message.startswith("p.json:") and "\n" not in message and ": error: " in message
        return
    assert rplan.load(rplan.dump(plan)) == plan
