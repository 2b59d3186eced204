"""A modest run of the hostile-input fuzzer (make fuzz runs thousands): every class of issue 14
gets a clean answer -- exit 2 (or 0/1 where the input is legal), located one-line errors, no
traceback, no control characters on the terminal, within the time and memory limits."""

from __future__ import annotations

import os

from rgraph.fuzz_cases import GENERATORS
from rgraph.fuzz_hostile import run_all

CASES = int(os.environ.get("RGRAPH_HOSTILE_CASES", 10 * len(GENERATORS)))


def test_hostile_inputs_get_clean_answers() -> None:
    outcomes = run_all(CASES, seed=int(os.environ.get("RGRAPH_HOSTILE_SEED", "14")))
    failed = [o.summary() for o in outcomes if o.problems]
    assert not failed, "\n".join(failed)
    assert len({o.case.name for o in outcomes}) == len(GENERATORS)  # every class ran
