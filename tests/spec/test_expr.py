"""Tests of the ${...} expression parser (rgraph.spec.expr)."""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from rgraph.spec import expr as expr_module
from rgraph.spec.expr import ExprError, parse, parse_value

ENV = {
    "params.shadow.size": 2048,
    "params.hbao.directions": 8,
    "params.scale": 0.25,
    "params.enabled": True,
    "params.off": False,
    "params.zero": 0,
    "scene.lights": 3,
    "scene.shadow_lights": 1,
    "scene.large_world": False,
}


def value(text: str, env=ENV):
    return parse(text).evaluate(env)


def error(text: str, env=ENV, *, template: bool = False) -> ExprError:
    with pytest.raises(ExprError) as info:
        parsed = parse_value(text) if template else parse(text)
        assert parsed is not None
        parsed.evaluate(env)
    return info.value


# ----------------------------------------------------------------------------- values

@pytest.mark.parametrize(("text", "expected"), [
    ("1", 1),
    ("  42  ", 42),
    ("1.5", 1.5),
    (".5", 0.5),
    ("5.", 5.0),
    ("2e3", 2000.0),
    ("2.5E-1", 0.25),
    ("1e+2", 100.0),
    ("1 + 2 * 3", 7),
    ("(1 + 2) * 3", 9),
    ("10 - 4 - 3", 3),
    ("100 / 10 / 5", 2.0),
    ("7 / 2", 3.5),
    ("8 / 2", 4.0),
    ("7 // 2", 3),
    ("-7 // 2", -4),
    ("7 // -2", -4),
    ("-7 % 3", 2),
    ("7 % -3", -2),
    ("7.5 // 2", 3.0),
    ("7.5 % 2", 1.5),
    ("-3", -3),
    ("--3", 3),
    ("- - 3", 3),
    ("+3", 3),
    ("-(1 + 2)", -3),
    ("2 * -3", -6),
    ("2 - -3", 5),
    ("-2 * 3 + 1", -5),
    ("min(3, 1, 2)", 1),
    ("max(3, 1, 2)", 3),
    ("max(1, 2.5)", 2.5),
    ("ceil(1.2)", 2),
    ("floor(-1.2)", -2),
    ("ceil(7 / 2)", 4),
    ("floor(7)", 7),
    ("params.shadow.size", 2048),
    ("params.shadow.size // 4", 512),
    ("params.hbao.directions * 2 + scene.lights", 19),
    ("ceil(params.shadow.size * params.scale)", 512),
    ("params.enabled + 1", 2),
    ("params.off * 5", 0),
    ("max(scene.shadow_lights, 1) * 6", 6),
    ("9223372036854775807", 2**63 - 1),
    ("-9223372036854775807 - 1", -(2**63)),
])
def test_values(text, expected):
    result = value(text)
    assert result == expected
    assert type(result) is type(expected)


def test_int_float_typing():
    assert type(value("3 + 4")) is int
    assert type(value("3 * 4 // 2 % 5")) is int
    assert type(value("4 / 2")) is float
    assert type(value("3 + 0.5")) is float
    assert type(value("ceil(2.0)")) is int
    assert type(value("floor(params.scale)")) is int
    assert type(value("params.enabled")) is int


def test_names_and_source():
    parsed = parse("params.shadow.size * max(scene.lights, params.shadow.size) + params.hbao.directions")
    assert parsed.names == frozenset({"params.shadow.size", "scene.lights", "params.hbao.directions"})
    assert parse("1 + 2").names == frozenset()
    assert parsed.source.startswith("params.shadow.size")


def test_names_may_contain_digits_and_underscores():
    env = {"params.lod_0.bias_2": 5, "params.mip.0": 2}
    assert value("params.lod_0.bias_2 + params.mip.0", env) == 7


def test_canonical_text_roundtrip():
    parsed = parse("((1+2))*-(3 - params.scale)//max(1,2)")
    text = str(parsed)
    assert text == "(1 + 2) * -(3 - params.scale) // max(1, 2)"
    assert parse(text).evaluate(ENV) == parsed.evaluate(ENV)


def test_evaluate_is_repeatable_and_env_specific():
    parsed = parse("params.shadow.size // 2")
    assert parsed.evaluate(ENV) == 1024
    assert parsed.evaluate({"params.shadow.size": 512}) == 256
    assert parsed.evaluate(ENV) == 1024


def test_evaluate_accepts_numpy_numbers():
    np = pytest.importorskip("numpy")
    env = {"params.a": np.int64(6), "params.b": np.float32(0.5)}
    assert value("params.a // 4", env) == 1 and type(value("params.a", env)) is int
    assert value("params.a * params.b", env) == 3.0


# ----------------------------------------------------------------------------- parse_value

def test_parse_value_plain_strings_are_not_expressions():
    assert parse_value("abc") is None
    assert parse_value("output") is None
    assert parse_value("3 * 4") is None
    assert parse_value("$ {x}") is None
    assert parse_value(42) is None
    assert parse_value(None) is None


def test_parse_value_single_group():
    parsed = parse_value("${params.shadow.size} ")
    assert parsed is not None
    assert parsed.evaluate(ENV) == 2048
    assert parsed.names == frozenset({"params.shadow.size"})
    assert parse_value("  ${ scene.lights * 64 }").evaluate(ENV) == 192


def test_parse_value_mixed_with_numbers_and_operators():
    assert parse_value("${scene.lights} * 64").evaluate(ENV) == 192  # FORMAT.md example
    assert parse_value("${params.shadow.size} // ${params.hbao.directions}").evaluate(ENV) == 256
    assert parse_value("max(${scene.lights}, 8) + 1").evaluate(ENV) == 9
    # A group is parenthesised: precedence does not leak across the braces.
    assert parse_value("${1 + 2} * 3").evaluate({}) == 9


def test_parse_value_offsets_are_into_the_whole_string():
    err = error("${scene.lights} * ${params.shadow.sise}", template=True)
    assert err.offset == 20
    err = error("64 * ${1 / 0}", template=True)
    assert err.offset == 9


@pytest.mark.parametrize(("text", "offset", "fragment"), [
    ("scene.lights * ${1}", 0, "must be written inside"),
    ("${1", 0, "unterminated"),
    ("  ${1 + ${2}}", 8, "inside the"),
    ("${1}}", 4, "without a matching"),
    ("x${1}", 0, "unknown name 'x'"),
    ("${1} 2", 5, "expected an operator"),
    ("${}", 2, "expected a number"),
    ("${1} $", 5, "unexpected character '$'"),
    ("${(1}", 4, "expected ')' to close '('"),
    ("(${1)}", 4, "expected '}' to close '${'"),
])
def test_parse_value_errors(text, offset, fragment):
    err = error(text, template=True)
    assert err.offset == offset, err.message
    assert fragment in err.message


# ----------------------------------------------------------------------------- errors

@pytest.mark.parametrize(("text", "offset", "fragment"), [
    # syntax
    ("", 0, "empty expression"),
    ("   ", 0, "empty expression"),
    ("1 +", 3, "found end of expression"),
    ("1 2", 2, "expected an operator or end of expression, found '2'"),
    ("(1 + 2", 6, "expected ')' to close '(' at offset 0"),
    ("1 + 2)", 5, "expected an operator or end of expression, found ')'"),
    ("()", 1, "expected a number"),
    ("* 2", 0, "expected a number"),
    ("1 + * 2", 4, "expected a number"),
    ("2 ** 3", 2, "no power operator"),
    ("2 ^ 3", 2, "unexpected character '^'"),
    ("1 $ 2", 2, "unexpected character '$'"),
    ("a == b", 0, "unknown name 'a'"),
    ("1 # c", 2, "unexpected character '#'"),
    ("1 + ${2}", 4, "'${' inside '${...}'"),
    ("1 }", 2, "unexpected character '}'"),
    ("x = 1", 0, "unknown name 'x'"),
    ("1 2 $", 2, "expected an operator"),  # the first error wins, not a later bad character
    # numbers
    ("1..2", 0, "malformed number '1..2'"),
    ("1.2.3", 0, "malformed number '1.2.3'"),
    ("1 + 2x", 4, "malformed number '2x'"),
    ("1e", 0, "malformed number '1e'"),
    ("3 * 1e+", 4, "malformed number '1e+'"),
    ("1_000", 0, "malformed number"),
    ("9223372036854775808", 0, "value out of range"),
    ("1 + 1e999", 4, "value out of range"),
    # names
    ("foo", 0, "names are params.NAME or scene.NAME"),
    ("1 + param.shadow.size", 4, "did you mean 'params.shadow.size'"),
    ("params", 0, "names are params.NAME or scene.NAME"),
    ("params.", 6, "expected a name segment after '.'"),
    ("params..x", 6, "expected a name segment after '.'"),
    ("min", 0, "'min' is a function"),
    # functions
    ("mn(1, 2)", 0, "unknown function 'mn' (did you mean 'min'?)"),
    ("1 + sqrt(4)", 4, "unknown function 'sqrt'"),
    ("params.f(1)", 0, "unknown function 'params.f'"),
    ("min(1)", 0, "min() takes at least 2 arguments (1 given)"),
    ("max()", 0, "max() takes at least 2 arguments (0 given)"),
    ("2 * ceil(1, 2)", 4, "ceil() takes exactly 1 argument (2 given)"),
    ("floor()", 0, "floor() takes exactly 1 argument (0 given)"),
    ("min(1, )", 7, "expected a number"),
    ("min(1 2)", 6, "expected ')' to close '(' at offset 3"),
    ("min(1, 2", 8, "expected ')' to close '(' at offset 3"),
    # evaluation
    ("1 / 0", 2, "division by zero"),
    ("1 // (2 - 2)", 2, "division by zero"),
    ("1 % 0", 2, "modulo by zero"),
    ("1.5 / 0.0", 4, "division by zero"),
    ("10 / params.zero", 3, "division by zero"),
    ("1 + 5 % params.off", 6, "modulo by zero"),
    ("4611686018427387904 * 2", 20, "value out of range"),
    ("9223372036854775807 + 1", 20, "value out of range"),
    ("-9223372036854775807 - 2", 21, "value out of range"),
    ("-(-9223372036854775807 - 1)", 0, "value out of range"),
    ("1e308 * 10", 6, "value out of range"),
    ("1 + ceil(1e300)", 4, "value out of range"),
    ("params.shadow.sise + 1", 0, "did you mean 'params.shadow.size'"),
    ("2 * scene.light", 4, "did you mean 'scene.lights'"),
])
def test_errors_with_offsets(text, offset, fragment):
    err = error(text)
    assert err.offset == offset, f"{text!r}: {err.message}"
    assert fragment in err.message, err.message


def test_unknown_name_lists_known_names_of_its_namespace():
    err = error("scene.lihgts")
    assert "known scene names: scene.large_world, scene.lights, scene.shadow_lights" in err.message
    assert "params." not in err.message
    err = error("params.x", {"scene.lights": 1})
    assert "there are no params names" in err.message


def test_non_numeric_environment_value():
    err = error("1 + params.name", {"params.name": "hello"})
    assert err.offset == 4 and "not a number" in err.message
    err = error("params.big", {"params.big": 2**70})
    assert err.offset == 0 and "value out of range" in err.message
    err = error("params.nan", {"params.nan": math.nan})
    assert "value out of range" in err.message


def test_check_names():
    parsed = parse("params.a + scene.lights + params.b")
    parsed.check_names({"params.a", "params.b"}, namespace="params")
    with pytest.raises(ExprError) as info:
        parsed.check_names({"params.a", "params.bb"}, namespace="params")
    assert info.value.offset == 26 and "did you mean 'params.bb'" in info.value.message
    with pytest.raises(ExprError) as info:
        parsed.check_names({"params.a", "params.b"})
    assert info.value.offset == 11


def test_error_str_is_message():
    err = error("1 / 0")
    assert str(err) == err.message == "division by zero"


# ----------------------------------------------------------------------------- limits

def test_length_limit():
    ok = "1" + " + 1" * ((expr_module.MAX_LENGTH - 1) // 4)
    assert len(ok) <= expr_module.MAX_LENGTH
    assert value(ok) == ok.count("1")  # a long flat chain evaluates without deep recursion
    err = error(ok + " + 1")
    assert err.offset == expr_module.MAX_LENGTH and "too long" in err.message


def test_depth_limit_parentheses():
    depth = expr_module.MAX_DEPTH
    assert value("(" * depth + "1" + ")" * depth) == 1
    err = error("(" * (depth + 1) + "1" + ")" * (depth + 1))
    assert err.offset == depth and "nested too deeply" in err.message


def test_depth_limit_unary_and_calls():
    depth = expr_module.MAX_DEPTH
    assert value("-" * depth + "1") == 1
    err = error("-" * (depth + 1) + "1")
    assert err.offset == depth
    nested = "min(" * depth + "1" + ", 1)" * depth
    assert value(nested) == 1
    err = error("min(" * (depth + 1) + "1" + ", 1)" * (depth + 1))
    assert err.offset == 4 * depth + 3


def test_never_uses_eval():
    source = open(expr_module.__file__).read()
    assert not re.search(r"(?<![\w.])(eval|exec|compile|__import__)\(", source)
    # Python syntax that is not in the grammar is rejected, not executed.
    for text in ("__import__('os')", "[1][0]", "1 if 1 else 2", "lambda: 1", "'a'"):
        with pytest.raises(ExprError):
            parse(text)


# ----------------------------------------------------------------------------- property tests

@dataclass(frozen=True)
class Lit:
    value: int | float


@dataclass(frozen=True)
class Var:
    name: str


@dataclass(frozen=True)
class Neg:
    operand: object


@dataclass(frozen=True)
class Bin:
    op: str
    left: object
    right: object


@dataclass(frozen=True)
class Fn:
    name: str
    args: tuple


class RefError(Exception):
    """The reference evaluator's failure (division by zero, out of range)."""


TREE_ENV = {
    "params.a": 7,
    "params.b.c": -3,
    "params.f": 2.5,
    "params.flag": True,
    "scene.lights": 0,
    "scene.big": 2**40,
}
LEVEL = {"+": 1, "-": 1, "*": 2, "/": 2, "//": 2, "%": 2}


def ref_check(v):
    if isinstance(v, int):
        if not -(2**63) <= v <= 2**63 - 1:
            raise RefError("range")
    elif not math.isfinite(v):
        raise RefError("range")
    return v


def ref_eval(node):
    """Reference semantics over the generated tree (independent of the parser)."""
    if isinstance(node, Lit):
        return node.value
    if isinstance(node, Var):
        v = TREE_ENV[node.name]
        return int(v) if isinstance(v, bool) else v
    if isinstance(node, Neg):
        return ref_check(-ref_eval(node.operand))
    if isinstance(node, Fn):
        args = [ref_eval(a) for a in node.args]
        if node.name == "min":
            return min(args)
        if node.name == "max":
            return max(args)
        return ref_check(math.ceil(args[0]) if node.name == "ceil" else math.floor(args[0]))
    a, b = ref_eval(node.left), ref_eval(node.right)
    if node.op in ("/", "//", "%") and b == 0:
        raise RefError("zero")
    result = {
        "+": lambda: a + b, "-": lambda: a - b, "*": lambda: a * b,
        "/": lambda: a / b, "//": lambda: a // b, "%": lambda: a % b,
    }[node.op]()
    return ref_check(result)


def ref_names(node) -> set[str]:
    if isinstance(node, Var):
        return {node.name}
    if isinstance(node, Neg):
        return ref_names(node.operand)
    if isinstance(node, Bin):
        return ref_names(node.left) | ref_names(node.right)
    if isinstance(node, Fn):
        return set().union(*(ref_names(a) for a in node.args))
    return set()


def render(node, data) -> str:
    """Text for the tree: parentheses where precedence needs them, plus random extra ones and spaces."""
    def space() -> str:
        return data.draw(st.sampled_from(["", " ", "  ", "\t"]))

    def wrap(text: str, needed: bool) -> str:
        extra = data.draw(st.integers(0, 1)) if not needed else 0
        if needed or extra:
            return f"({space()}{text}{space()})"
        return text

    if isinstance(node, Lit):
        return repr(node.value)
    if isinstance(node, Var):
        return node.name
    if isinstance(node, Neg):
        inner = render(node.operand, data)
        return "-" + space() + wrap(inner, isinstance(node.operand, Bin))
    if isinstance(node, Fn):
        return node.name + "(" + ",".join(space() + render(a, data) + space() for a in node.args) + ")"
    level = LEVEL[node.op]
    left = render(node.left, data)
    right = render(node.right, data)
    left = wrap(left, isinstance(node.left, Bin) and LEVEL[node.left.op] < level)
    right = wrap(right, isinstance(node.right, Bin) and LEVEL[node.right.op] <= level)
    # A space keeps "a - -b" from reading as one token, and "- -" from "--": both are fine anyway.
    return f"{left}{space()}{node.op} {right}"


def nesting(text: str) -> int:
    """Upper bound on the parser's nesting depth for ``text`` (parens plus unary minus signs)."""
    depth = best = 0
    for ch in text:
        if ch in "(-":
            depth += 1
            best = max(best, depth)
        elif ch == ")":
            depth -= 1
    return best + text.count("-")


leaves = st.one_of(
    st.integers(0, 10**6).map(Lit),
    st.sampled_from([0, 1, 2, 3, 2**62, 2**63 - 1]).map(Lit),
    st.floats(0, 1e6, allow_nan=False, allow_infinity=False).map(Lit),
    st.sampled_from([0.0, 0.5, 1e-5, 1e300]).map(Lit),
    st.sampled_from(sorted(TREE_ENV)).map(Var),
)


def extend(children):
    forms = {
        "binary": st.builds(Bin, st.sampled_from(sorted(LEVEL)), children, children),
        "minmax": st.builds(Fn, st.sampled_from(["min", "max"]),
                            st.lists(children, min_size=2, max_size=3).map(tuple)),
        "round": st.builds(Fn, st.sampled_from(["ceil", "floor"]), children.map(lambda c: (c,))),
        "neg": children.map(Neg),
    }
    # Weighted by hand: left to itself hypothesis favours the cheapest form (unary minus).
    kinds = ["binary"] * 6 + ["minmax", "round", "neg"]
    return st.sampled_from(kinds).flatmap(forms.__getitem__)


trees = st.recursive(leaves, extend, max_leaves=20)


@settings(max_examples=400, deadline=None)
@given(tree=trees, data=st.data())
def test_roundtrip_against_reference(tree, data):
    text = render(tree, data)
    assume(len(text) <= expr_module.MAX_LENGTH and nesting(text) < expr_module.MAX_DEPTH)
    parsed = parse(text)
    assert parsed.names == frozenset(ref_names(tree))
    try:
        expected = ref_eval(tree)
    except RefError:
        with pytest.raises(ExprError):
            parsed.evaluate(TREE_ENV)
        return
    got = parsed.evaluate(TREE_ENV)
    assert type(got) is type(expected), text
    assert got == expected, text
    # The canonical rendering parses back to the same value.
    again = parse(str(parsed))
    assert again.evaluate(TREE_ENV) == got
    assert again.names == parsed.names
    # And the same text works as a YAML value inside ${...}.
    assert parse_value("${" + text + "}").evaluate(TREE_ENV) == got


@settings(max_examples=300, deadline=None)
@given(st.text(alphabet="0123456789.eE+-*/%(),$ {}_abcdmnxpsrl", max_size=40))
def test_arbitrary_text_never_crashes(text):
    """Any input either parses or raises ExprError with an offset inside (or at the end of) the text."""
    for entry in (parse, parse_value):
        try:
            parsed = entry(text)
            if parsed is not None:
                parsed.evaluate(TREE_ENV)
        except ExprError as err:
            assert 0 <= err.offset <= len(text)
            assert err.message
