"""What the render thread does per frame, counted (issue 18): Python bytecodes of the frame
loop by function (``sys.settrace`` opcode events on the render thread, between a frame's
start and the end of its submits; the logic thread is not traced) and the submit's structure
(vkQueueSubmit2 calls, VkSubmitInfo2, command buffers, semaphore infos, fences per frame).
As in ``benchmarks.vr_tests``: one VkQueue, draw.mode=gpu, a logic thread, timestamps read in
one frame of 4, the loop's timing marks on (they are part of the count).

Counts, not times: the same on any machine and load, so they compare two paths exactly
(``RGRAPH_BATCH_CUTS=plan RGRAPH_FRAME_UPDATE=method``: the render path before session 11).

    python3 -m benchmarks.frame_ops [--tests skinned,lighting] [--views 1,2] [--size 32x18] [--frames 16]
"""

from __future__ import annotations

import argparse
import collections
import inspect
import sys
from typing import Any

from rgraph.resources import builtin_passes

builtin_passes()


def submit_structure(ex: Any) -> dict[str, int]:
    """Per frame (set 0): the submit calls and what their VkSubmitInfo2 carry."""
    calls = ex.submit_calls[0]
    infos = [c.infos[j] for c in calls for j in range(c.count)]
    return {"batches": len(ex.recording.batches), "vkQueueSubmit2": len(calls), "VkSubmitInfo2": len(infos),
            "command_buffers": sum(i.commandBufferInfoCount for i in infos),
            "wait_semaphores": sum(i.waitSemaphoreInfoCount for i in infos),
            "signal_semaphores": sum(i.signalSemaphoreInfoCount for i in infos),
            "fences": len(ex.fences[0]), "value_slots": len(ex.value_slots[0])}


def count_frames(exe: Any, frames: int) -> tuple[collections.Counter, collections.Counter]:
    """(bytecodes, calls) by ``file:function`` over ``frames`` timed frames of the loop body."""
    import rgraph.vk.runtime.frames as frames_module

    loop = frames_module.run_frames.__code__
    src, first = inspect.getsourcelines(frames_module.run_frames)
    lo = first + next(i for i, line in enumerate(src) if "for local in range(frames)" in line)
    hi = first + next(i for i, line in enumerate(src) if "cpu_s[local] = perf() - t0" in line)
    ops: collections.Counter = collections.Counter()
    calls: collections.Counter = collections.Counter()
    inside = [False]

    def tracer(frame: Any, event: str, _arg: Any) -> Any:
        frame.f_trace_opcodes = True
        name = f"{frame.f_code.co_filename.rsplit('/', 1)[-1]}:{frame.f_code.co_name}"
        is_loop = frame.f_code is loop
        if event == "call" and inside[0] and not is_loop:
            calls[name] += 1

        def local(frame: Any, event: str, _arg: Any) -> Any:
            if is_loop and event == "line":
                inside[0] = lo < frame.f_lineno <= hi
            if event == "opcode" and inside[0]:
                ops[name] += 1
            return local

        return local

    marks: list[float] = []
    sys.settrace(tracer)
    try:
        exe.run(frames, marks=marks)
    finally:
        sys.settrace(None)
    return ops, calls


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--tests", default="skinned,lighting")
    parser.add_argument("--views", default="1,2")
    parser.add_argument("--size", default="32x18")
    parser.add_argument("--frames", type=int, default=16)
    parser.add_argument("--logic-hz", dest="logic_hz", type=float, default=60.0)
    args = parser.parse_args(argv)
    import rgraph
    from benchmarks.vr_tests import GRAPH, SCENES, TESTS
    from rgraph.compiler.pipeline import compile_graph

    size = tuple(int(x) for x in args.size.lower().split("x"))
    with rgraph.open_device(validate=False, verbose=False, one_queue=True) as gpu:
        for test in args.tests.split(","):
            for views in args.views.split(","):
                plan = compile_graph(GRAPH, scene_path=SCENES / TESTS[test], size=size,
                                     params={"views": views, "draw.mode": "gpu"}, memory=gpu.memory_requirements())
                with gpu.load(plan, logic_hz=args.logic_hz) as exe:
                    exe.executor.timestamp_every = 4  # as vr_tests: one frame's timestamps read in 4
                    exe.run(4)
                    ops, calls = count_frames(exe, args.frames)
                    structure = submit_structure(exe.executor)
                n = args.frames
                print(f"{test} views={views}: {sum(ops.values()) / n:.0f} bytecodes per frame, "
                      f"{sum(calls.values()) / n:.0f} Python calls; per frame: "
                      + ", ".join(f"{k} {v}" for k, v in structure.items()))
                for name, count in ops.most_common():
                    print(f"    {name:45s} {count / n:7.1f} bytecodes  {calls[name] / n:5.2f} calls")
    return 0


if __name__ == "__main__":
    sys.exit(main())
