"""Barrier generation rules (DESIGN.md invariants), on small graphs."""

from __future__ import annotations

from compile_helpers import barriers_of, compile_text, pass_named

CHAIN = """
rgraph: 1
resources:
  depth: {kind: image, format: d32_sfloat, size: output}
  a: {kind: image, format: r16g16b16a16_sfloat, size: output}
  b: {kind: image, format: r16g16b16a16_sfloat, size: output}
  out: {kind: image, format: r8g8b8a8_unorm, size: output}
passes:
  prepass: {kind: raster, writes: {depth: depth_attachment}}
  lit: {kind: raster, reads: {depth: depth_read}, writes: {a: color_attachment}}
  ssao: {kind: compute, reads: {depth: sampled}, writes: {b: storage_write}}
  blur1: {kind: compute, reads: {a: sampled}, writes: {b: storage_rw}}
  blur2: {kind: raster, reads: {a: sampled, b: sampled}, writes: {out: color_attachment}}
outputs: [out]
"""


def test_first_use_transitions_from_undefined_with_no_src(tmp_path):
    plan = compile_text(tmp_path, CHAIN)
    (b,) = barriers_of(plan, "prepass")
    assert b["src"] == {"stages": [], "access": [], "layout": "UNDEFINED", "queue": "graphics"}
    assert b["dst"]["layout"] == "DEPTH_ATTACHMENT_OPTIMAL"
    assert b["dst"]["access"] == ["DEPTH_STENCIL_ATTACHMENT_READ", "DEPTH_STENCIL_ATTACHMENT_WRITE"]


def test_src_access_holds_writes_only(tmp_path):
    plan = compile_text(tmp_path, CHAIN)
    for p in plan["passes"]:
        for b in p["barriers"]:
            assert not [a for a in b["src"]["access"] if a.endswith("_READ") or a.endswith("READ_KHR")], b


def test_depth_read_and_sampled_share_one_read_only_layout(tmp_path):
    plan = compile_text(tmp_path, CHAIN)
    (to_read,) = [b for b in barriers_of(plan, "lit") if b["resource"] == "depth"]
    assert to_read["dst"]["layout"] == "DEPTH_READ_ONLY_OPTIMAL"
    # the later sampled read in the compute pass shares the barrier: no second transition
    assert "COMPUTE_SHADER" in to_read["dst"]["stages"]
    assert "SHADER_SAMPLED_READ" in to_read["dst"]["access"]
    assert not [b for b in barriers_of(plan, "ssao") if b["resource"] == "depth"]


def test_reads_between_writes_share_one_barrier_and_no_read_after_read(tmp_path):
    plan = compile_text(tmp_path, CHAIN)
    a_barriers = [(p["name"], b) for p in plan["passes"] for b in p["barriers"] if b["resource"] == "a"]
    names = [n for n, _ in a_barriers]
    assert names == ["lit", "blur1"]  # UNDEFINED->COLOR, then one barrier for both sampled reads
    dst = a_barriers[1][1]["dst"]
    assert set(dst["stages"]) == {"COMPUTE_SHADER", "FRAGMENT_SHADER"}


def test_write_after_write_and_read_write_usage(tmp_path):
    plan = compile_text(tmp_path, CHAIN)
    (b,) = [b for b in barriers_of(plan, "blur1") if b["resource"] == "b"]
    assert b["src"]["access"] == ["SHADER_STORAGE_WRITE"]
    assert b["dst"]["access"] == ["SHADER_STORAGE_READ", "SHADER_STORAGE_WRITE"]
    assert b["src"]["layout"] == b["dst"]["layout"] == "GENERAL"


def test_write_after_read_is_an_execution_dependency(tmp_path):
    text = """
    rgraph: 1
    resources:
      a: {kind: image, format: r32_sfloat, size: output}
      o1: {kind: image, format: r32_sfloat, size: output}
      o2: {kind: image, format: r32_sfloat, size: output}
    passes:
      w1: {kind: compute, writes: {a: storage_write}}
      r: {kind: compute, reads: {a: storage_read}, writes: {o1: storage_write}}
      w2: {kind: compute, writes: {a: storage_write}}
      r2: {kind: compute, reads: {a: storage_read}, writes: {o2: storage_write}}
    outputs: [o1, o2]
    """
    plan = compile_text(tmp_path, text)
    (war,) = [b for b in barriers_of(plan, "w2") if b["resource"] == "a"]
    assert war["src"]["access"] == [] and war["src"]["stages"] == ["COMPUTE_SHADER"]
    assert war["dst"]["access"] == ["SHADER_STORAGE_WRITE"]


def test_subresource_ranges_are_tracked_separately(tmp_path):
    text = """
    rgraph: 1
    resources:
      arr: {kind: image, format: r32_sfloat, size: output, layers: 4}
      out: {kind: image, format: r32_sfloat, size: output}
    passes:
      w0: {kind: compute, writes: {"arr[layer=0]": storage_write}}
      w123: {kind: compute, writes: {"arr[layer=1:4]": storage_write}}
      r: {kind: compute, reads: {"arr[layer=1:4]": sampled}, writes: {out: storage_write}}
      r0: {kind: compute, reads: {"arr[layer=0]": sampled}, writes: {out: storage_rw}}
    outputs: [out]
    """
    plan = compile_text(tmp_path, text)
    (first,) = barriers_of(plan, "w123")
    assert first["subresource"] == {"mips": [0, 1], "layers": [1, 4]}
    assert first["src"]["layout"] == "UNDEFINED"  # not a dependency on w0's layer 0
    (rb,) = [b for b in barriers_of(plan, "r") if b["resource"] == "arr"]
    assert rb["subresource"]["layers"] == [1, 4]
    (rb0,) = [b for b in barriers_of(plan, "r0") if b["resource"] == "arr"]
    assert rb0["subresource"]["layers"] == [0, 1]


def test_async_compute_gets_semaphores_and_ownership_transfers(tmp_path):
    text = """
    rgraph: 1
    resources:
      depth: {kind: image, format: d32_sfloat, size: output}
      ao: {kind: image, format: r8_unorm, size: output}
      out: {kind: image, format: r8g8b8a8_unorm, size: output}
    passes:
      prepass: {kind: raster, writes: {depth: depth_attachment}}
      hbao: {kind: compute, queue: compute, reads: {depth: sampled}, writes: {ao: storage_write}}
      lit: {kind: raster, reads: {ao: sampled, depth: depth_read}, writes: {out: color_attachment}}
    outputs: [out]
    """
    plan = compile_text(tmp_path, text)
    prepass, hbao, lit = (pass_named(plan, n) for n in ("prepass", "hbao", "lit"))
    assert prepass["signals"] == [{"queue": "graphics", "value": 1, "stages": ["ALL_COMMANDS"]}]
    assert [w["queue"] for w in hbao["waits"]] == ["graphics"] and hbao["waits"][0]["value"] == 1
    (release,) = prepass["releases"]
    assert release["src"]["queue"] == "graphics" and release["dst"]["queue"] == "compute"
    assert release in hbao["barriers"]  # the acquire is the same barrier
    assert lit["waits"][0]["queue"] == "compute"
    assert plan["queues"] == ["graphics", "compute"]


def test_persistent_history_waits_for_previous_frame(tmp_path):
    text = """
    rgraph: 1
    resources:
      history: {kind: image, format: r16g16b16a16_sfloat, size: output, lifetime: persistent}
      out: {kind: image, format: r16g16b16a16_sfloat, size: output}
    passes:
      taa: {kind: compute, reads: {history: sampled}, writes: {out: storage_write}}
      save: {kind: compute, reads: {out: sampled}, writes: {history: storage_write}}
    outputs: [out]
    """
    plan = compile_text(tmp_path, text)
    (b,) = [b for b in barriers_of(plan, "taa") if b["resource"] == "history"]
    assert b["src"]["layout"] == "GENERAL" and b["src"]["access"] == ["SHADER_STORAGE_WRITE"]
    assert b["dst"]["layout"] == "SHADER_READ_ONLY_OPTIMAL"
    res = next(r for r in plan["resources"] if r["name"] == "history")
    assert res["initial"] == res["final"]
    assert res["final"]["layout"] == "GENERAL"


def test_buffers_have_no_layouts_and_first_write_needs_no_barrier(tmp_path):
    text = """
    rgraph: 1
    resources:
      args: {kind: buffer, bytes: 64}
      out: {kind: buffer, bytes: 64}
    passes:
      gen: {kind: compute, writes: {args: storage_write}}
      use: {kind: compute, reads: {args: indirect}, writes: {out: storage_write}}
    outputs: [out]
    """
    plan = compile_text(tmp_path, text)
    assert barriers_of(plan, "gen") == []
    (b,) = barriers_of(plan, "use")
    assert b["subresource"] is None and b["src"]["layout"] is None
    assert b["dst"]["stages"] == ["DRAW_INDIRECT"] and b["dst"]["access"] == ["INDIRECT_COMMAND_READ"]
