"""Generators of hostile command-line cases (files + argv) for :mod:`rgraph.fuzz_hostile`.

Each generator takes a seeded ``Random`` and returns one :class:`Case` of its class; the
class name prefixes the case name. Files are written into a fresh folder that is the
child's working directory, so relative names stay inside it.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import cache
from random import Random

GRAPH = (
    "rgraph: 1\nparams: {q: 2}\n"
    "resources:\n  color: {kind: image, format: r8g8b8a8_unorm, size: output, lifetime: output}\n"
    "passes:\n  p: {kind: raster, writes: {color: color_attachment}}\noutputs: [color]\n"
)
HUGE = "9" * 5000


@dataclass
class Case:
    name: str
    argv: list[str]
    files: dict[str, bytes] = field(default_factory=dict)
    fifos: list[str] = field(default_factory=list)
    codes: frozenset[int] = frozenset({2})
    max_errors: int = 50
    seed: int = 0


def _graph(name: str, text: str, *extra: str, command: str = "validate", **kw) -> Case:
    return Case(name, [command, "g.yaml", *extra], {"g.yaml": text.encode("utf-8", "surrogatepass")}, **kw)


def numbers(r: Random) -> Case:
    big = r.choice([HUGE, "-" + HUGE, "0x" + "f" * 2000, "1" + "0" * 30, "18446744073709551616"])
    place = r.choice([
        "params: {{a: {v}}}\n", "resources: {{b: {{kind: buffer, bytes: {v}}}}}\n",
        "resources: {{i: {{kind: image, format: r8_unorm, size: [{v}, 4]}}}}\n",
        "resources: {{i: {{kind: image, format: r8_unorm, size: output, layers: {v}}}}}\n",
        'resources: {{b: {{kind: buffer, bytes: "${{{v} * 2}}"}}}}\n',
        "passes: {{p: {{kind: compute, reads: {{'color[layer=0:{v}]': sampled}}}}}}\n",
    ])
    return _graph("numbers", "rgraph: 1\n" + place.format(v=big))


def depth(r: Random) -> Case:
    n = r.choice([65, 200, 3000, 100_000])
    kind = r.randrange(4)
    if kind == 0:
        body = "x: " + "[" * n + "]" * n + "\n"
    elif kind == 1:
        body = "x: " + "{a: " * n + "1" + "}" * n + "\n"
    elif kind == 2:
        body = "x:\n" + "".join(" " * i + "-\n" for i in range(min(n, 3000)))
    else:
        body = "x:\n" + "".join(" " * i + "a:\n" for i in range(min(n, 3000)))
    return _graph("depth", "rgraph: 1\n" + body)


def aliases(r: Random) -> Case:
    kind = r.randrange(3)
    if kind == 0:
        return _graph("aliases", "rgraph: 1\nparams: &a {x: *a}\n")
    if kind == 1:
        return _graph("aliases", "rgraph: 1\nparams: {x: *nowhere}\n")
    fan, levels = r.randint(8, 12), r.randint(6, 9)
    lines = ["rgraph: 1", "a0: &a0 [" + ",".join(["x"] * fan) + "]"]
    lines += [f"a{i}: &a{i} [" + ",".join([f"*a{i - 1}"] * fan) + "]" for i in range(1, levels)]
    return _graph("aliases", "\n".join(lines) + "\n")


def tags(r: Random) -> Case:
    tag = r.choice(["!!float abc", "!!int 0x_", "!!int abc", "!!bool maybe", "!!str 5", "!foo x",
                    "!!python/object:os.system {}", "!!binary aGk=", "!!timestamp 2001-01-01", "!<tag:x> 1",
                    "!!set {a}", "!!omap [a: 1]"])
    if r.random() < 0.3:
        return _graph("tags", "%YAML 1.1\n---\nrgraph: 1\nparams: {a: " + r.choice(["1:30", "yes", "on", "0777"]) + "}\n")
    if r.random() < 0.2:
        return _graph("tags", "%TAG !e! tag:example.com,2000:\n---\nrgraph: 1\nname: !e!x y\n")
    return _graph("tags", "rgraph: 1\nparams: {a: " + tag + "}\n")


def text(r: Random) -> Case:
    evil = r.choice(["r8\\n/x.yaml:1:1: error: fake", "\\e[31mred\\e[0m", "\\ud800", "a\\x00b", "\\u202e" * 3,
                     "x" * 100_000])
    where = r.choice(["name: \"{e}\"\n", "resources: {{a: {{kind: image, format: \"{e}\", size: output}}}}\n",
                      "params: {{\"{e}\": 1}}\n", "passes: {{p: {{kind: \"{e}\"}}}}\n", "outputs: [\"{e}\"]\n"])
    either = frozenset({0, 2})  # a strange name is still a name: what matters is how it is echoed
    if r.random() < 0.3:
        return Case("text", ["validate", "g.yaml"],
                    {"g.yaml": b"rgraph: 1\nname: a" + bytes([r.choice([1, 7, 27, 0x7f])]) + b"b\n" if r.random() < 0.5
                     else b"rgraph: 1\nname: \xff\xfe\n"}, codes=either)
    return _graph("text", "rgraph: 1\n" + where.format(e=evil), codes=either)


def includes(r: Random) -> Case:
    kind = r.randrange(7)
    if kind == 0:
        return _graph("includes", 'rgraph: 1\ninclude: ["a\\0b.yaml"]\n')
    if kind == 1:
        return _graph("includes", "rgraph: 1\ninclude: [" + "x" * r.choice([256, 5000]) + ".yaml]\n")
    if kind == 2:
        return _graph("includes", "rgraph: 1\ninclude: [" + r.choice(["../g.yaml", "/etc/passwd", "/dev/zero"]) + "]\n")
    if kind == 3:  # fan-out: each level includes the next twice
        files = {f"f{i}.yaml": f"rgraph: 1\ninclude: [f{i + 1}.yaml, f{i + 1}.yaml]\n".encode() for i in range(30)}
        files["f30.yaml"] = b"rgraph: 1\n"
        files["g.yaml"] = b"rgraph: 1\ninclude: [f0.yaml]\n"
        return Case("includes", ["validate", "g.yaml"], files, codes=frozenset({0}))
    if kind == 4:
        return Case("includes", ["validate", "g.yaml"], {"g.yaml": b"rgraph: 1\ninclude: [p.yaml]\n"}, fifos=["p.yaml"])
    if kind == 5:
        return Case("includes", ["validate", "g.yaml"],
                    {"g.yaml": b"rgraph: 1\n\ninclude: [c.yaml]\n", "c.yaml": b"rgraph: 1\nresources: {x: {kind: imag}}\n"})
    return _graph("includes", "rgraph: 1\nscene: " + r.choice(["../s.yaml", "/dev/zero", "/etc/hostname"]) + "\n")


def special_files(r: Random) -> Case:
    kind = r.randrange(5)
    if kind == 0:
        return Case("files", ["validate", "g.yaml", "--scene", "/dev/zero"], {"g.yaml": GRAPH.encode()})
    if kind == 1:
        return Case("files", ["validate", "g.yaml", "--scene", "s.yaml"], {"g.yaml": GRAPH.encode()}, fifos=["s.yaml"])
    if kind == 2:
        return Case("files", ["validate", "g.yaml"], fifos=["g.yaml"])
    if kind == 3:
        return Case("files", ["validate", "d.yaml"], {"d.yaml/x": b""})
    return Case("files", ["validate", "g.yaml"], {"g.yaml": b"rgraph: 1\n" + b"# padding\n" * 500_000})


def many_keys(r: Random) -> Case:
    n = 21_000 if r.random() < 0.02 else r.choice([200, 1_000])
    body = "".join(f"  k{i}: {i}\n" for i in range(n))
    return _graph("keys", "rgraph: 1\nparams:\n" + body, codes=frozenset({0, 2}))


def locations(r: Random) -> Case:
    choice = r.randrange(4)
    if choice == 0:
        return _graph("locations", 'rgraph: 1\nmemory_policy: "' + r.choice(["blocks:0", "blocks:3MiB", "bogus", ""]) + '"\n')
    if choice == 1:
        return _graph("locations", GRAPH.replace("kind: raster,", "kind: raster, writez: {}, "))
    if choice == 2:
        return _graph("locations", GRAPH + "params: {}\n")
    return _graph("locations", GRAPH.replace("size: output", "size: {scale: 1, scal: 2}"))


def scenes(r: Random) -> Case:
    camera = r.choice(["camera: {position: [.nan, 0, 1]}", "camera: {position: [.inf, 0, 1]}",
                       "camera: {position: [1, 1, 1], look_at: [1, 1, 1]}", "camera: {fov_y: 1e308}",
                       "camera: {near: -1}", "camera: {up: [0, 0, 0]}"])
    mesh = r.choice(["{shape: box, material: m, instances: {grid: [100000, 100000, 100000]}}",
                     "{shape: sphere, material: m, params: {segments: 1000000000}}",
                     "{shape: segments, material: m, params: {count: 100000000}}",
                     "{shape: sphere, material: m, params: {segments: 4000, rings: 4000}}",
                     "{shape: sphere, material: m, params: {radius: .inf}}",
                     "{shape: sphere, material: m, params: {segments: abc}}",
                     "{shape: box, material: m, instances: {grid: [0, -1, 2]}}"])
    body = camera if r.random() < 0.4 else "materials: {m: {}}\nmeshes: [" + mesh + "]"
    return Case("scenes", ["validate", "g.yaml", "--scene", "s.yaml"],
                {"g.yaml": GRAPH.encode(), "s.yaml": ("scene: 1\n" + body + "\n").encode()})


@cache
def _base_plan() -> str:
    from rgraph.compiler.pipeline import compile_graph
    from rgraph.plan import dumps_json

    return dumps_json(compile_graph("surgery", size=(32, 32)))


_HOSTILE_VALUES: list[object] = ["x", "", None, True, [], {}, [1, 2], {"a": 1}, -1, 2**62, -(2**62),
                                 1e308, 0.5, "\u001b[31m", "a\nb", 3]


def _paths(value: object, prefix: tuple = ()) -> list[tuple]:
    out = [prefix]
    if isinstance(value, dict):
        for k, v in value.items():
            out += _paths(v, (*prefix, k))
    elif isinstance(value, list):
        for i, v in enumerate(value):
            out += _paths(v, (*prefix, i))
    return out


def plans(r: Random) -> Case:
    command = r.choice([["check", "p.json"], ["inspect", "p.json", "--memory", "--barriers"], ["inspect", "p.json"],
                        ["inspect", "p.json", "--dot"], ["run", "p.json", "--frames", "0"]])
    kind = r.randrange(6)
    if kind == 0:
        n = r.choice([100, 100_000])
        text = "[" * n + "]" * n
    elif kind == 1:
        text = _base_plan().replace('"offset": 0', '"offset": ' + r.choice([HUGE, "NaN", "Infinity", "1e999"]), 1)
    else:
        plan = json.loads(_base_plan())
        for _ in range(r.randint(1, 3)):
            path = r.choice(_paths(plan)[1:])
            target = plan
            for part in path[:-1]:
                target = target[part]
            target[path[-1]] = r.choice(_HOSTILE_VALUES)
        text = json.dumps(plan)
    return Case("plans", command, {"p.json": text.encode()}, codes=frozenset({0, 1, 2}))


def traces(r: Random) -> Case:
    kind = r.randrange(6)
    head = "id,lower,upper,size\n"
    argv = ["place", "t.csv"]
    if kind == 0:
        body = head + f"a,0,2,{2**200}\n"
    elif kind == 1:
        body, argv = head + "a,0,2,5\n", ["place", "t.csv", "--budget", r.choice(["inf", "nan", "-1", "1e300"])]
    elif kind == 2:
        body = head + "x" * 1_000_000 + ",0,2,5\n"
    elif kind == 3:
        body = head + "".join(f"b{i},0,10,{100 + i}\n" for i in range(10_000))
        return Case("traces", argv, {"t.csv": body.encode()}, codes=frozenset({0}))
    elif kind == 4:
        body = head + 'a,"0,2,5\n'
    else:
        return Case("traces", ["place", "/dev/zero"])
    return Case("traces", argv, {"t.csv": body.encode()})


def arguments(r: Random) -> Case:
    bad_out = r.choice(["missing/x.png", ".", "/dev/full", "missing/"])
    choice = r.randrange(5)
    files = {"g.yaml": GRAPH.encode()}
    if choice == 0:
        return Case("arguments", ["run", "g.yaml", "--size", "16x16", r.choice(["--out", "--timings"]), bad_out], files)
    if choice == 1:
        return Case("arguments", ["compile", "g.yaml", "-o", bad_out], files)
    if choice == 2:
        return Case("arguments", ["run", "g.yaml", "--frames", r.choice(["1e20", "0", "-5", "10" * 30, "x"])], files)
    if choice == 3:
        param = r.choice(["hbao.directions=0", "hbao.directions=1e9", "sss.kernel=evil", "sss.samples=12",
                          "tonemap.exposure=nan", "bloom.direction=z"])
        return Case("arguments", ["run", "surgery", "--size", "16x16", "-p", param])
    return Case("arguments", ["validate", "g.yaml", "--size", r.choice(["0x0", "99999x1", "1e3x4", "x"])], files)


GENERATORS: list[Callable[[Random], Case]] = [
    numbers, depth, aliases, tags, text, includes, special_files, many_keys, locations, scenes, plans, traces,
    arguments,
]
