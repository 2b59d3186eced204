"""The ``${...}`` value expressions of graph files (FORMAT.md section 1), parsed by hand.

Grammar (whitespace is free between tokens)::

    expr    := term (("+" | "-") term)*
    term    := unary (("*" | "/" | "//" | "%") unary)*
    unary   := ("-" | "+") unary | primary
    primary := NUMBER | REF | FUNC "(" expr ("," expr)* ")" | "(" expr ")" | "${" expr "}"
    REF     := ("params" | "scene") ("." SEGMENT)+        e.g. params.shadow.size
             | LOOPVAR                                  a repeated pass's variable, e.g. i
    FUNC    := "min" | "max" (2+ arguments) | "ceil" | "floor" (1 argument)

Numbers are ``12``, ``1.5``, ``.5``, ``2e3``; a literal with ``.`` or an exponent is a float.
Semantics follow Python: ints stay ints under ``+ - * // %``, ``/`` gives a float, ``ceil``
and ``floor`` give ints, booleans in the environment count as 0/1. Integers must fit in a
signed 64-bit range and floats must stay finite, otherwise "value out of range".

Nothing here calls eval, exec or compile. Every error is an ``ExprError`` carrying the
0-based offset of the offending token in the source string.

``parse(text)`` takes the inside of one ``${...}``. ``parse_value(text)`` takes a whole YAML
string: a string without ``${`` is not an expression (None); otherwise the whole string is one
expression in which each ``${...}`` is a parenthesised group, and references to ``params.*``
and ``scene.*`` may appear only inside such groups, so ``"${scene.lights} * 64"`` and
``"max(${params.a}, 2) + 1"`` are expressions while ``"scene.lights * 64"`` is not.
"""

from __future__ import annotations

import difflib
import math
import numbers
from collections.abc import Collection, Iterator, Mapping
from dataclasses import dataclass, field

MAX_LENGTH = 4096
MAX_DEPTH = 64
INT_MIN = -(2**63)
INT_MAX = 2**63 - 1
NAMESPACES = ("params", "scene")
FUNCTIONS = {"min": (2, None), "max": (2, None), "ceil": (1, 1), "floor": (1, 1)}

Number = int | float


class ExprError(Exception):
    """A malformed or unevaluable expression; ``offset`` is 0-based into the source string."""

    def __init__(self, message: str, offset: int) -> None:
        super().__init__(message)
        self.message = message
        self.offset = offset

    def __str__(self) -> str:
        return self.message


# ---------------------------------------------------------------------------- tokens

@dataclass(frozen=True)
class Token:
    kind: str  # "num", "name", "op", "end"; ops include "${" and "}"
    text: str
    offset: int
    value: Number | None = None
    in_group: bool = True  # inside ${...} (always true for parse())


_OPERATORS = ("${", "//", "+", "-", "*", "/", "%", "(", ")", ",", "}")


def _is_ident_start(ch: str) -> bool:
    return ch == "_" or ("a" <= ch <= "z") or ("A" <= ch <= "Z")


def _is_ident_char(ch: str) -> bool:
    return _is_ident_start(ch) or ("0" <= ch <= "9")


def _is_digit(ch: str) -> bool:
    return "0" <= ch <= "9"


def _scan_digits(text: str, i: int) -> int:
    while i < len(text) and _is_digit(text[i]):
        i += 1
    return i


def _scan_number(text: str, start: int) -> Token:
    i = _scan_digits(text, start)
    is_float = False
    if i < len(text) and text[i] == ".":
        is_float = True
        i = _scan_digits(text, i + 1)
    if i < len(text) and text[i] in "eE":
        j = i + 1
        if j < len(text) and text[j] in "+-":
            j += 1
        k = _scan_digits(text, j)
        if k > j:
            is_float = True
            i = k
    literal = text[start:i]
    if i < len(text) and (_is_ident_char(text[i]) or text[i] == "."):
        end = i
        while end < len(text) and (_is_ident_char(text[end]) or text[end] == "."
                                   or (text[end] in "+-" and text[end - 1] in "eE")):
            end += 1
        raise ExprError(f"malformed number {text[start:end]!r}", start)
    if is_float:
        value: Number = float(literal)
        if not math.isfinite(value):
            raise ExprError(f"value out of range: {literal}", start)
    else:
        value = int(literal)
        if value > INT_MAX:
            raise ExprError(f"value out of range: {literal}", start)
    return Token("num", literal, start, value)


def _scan_name(text: str, start: int) -> int:
    i = start
    while i < len(text) and _is_ident_char(text[i]):
        i += 1
    while i < len(text) and text[i] == ".":
        j = i + 1
        while j < len(text) and _is_ident_char(text[j]):
            j += 1
        if j == i + 1:
            raise ExprError(f"expected a name segment after '.' in {text[start:i + 1]!r}", i)
        i = j
    return i


def tokenize(text: str, template: bool) -> Iterator[Token]:
    """Yield the tokens of ``text``, lazily (so the first error in the text is the one reported).

    In template mode ``${`` and ``}`` delimit groups; the last token has kind "end".
    """
    group_start: int | None = None  # offset of the open "${" in template mode
    i = 0
    n = len(text)
    while i < n:
        ch = text[i]
        in_group = not template or group_start is not None
        if ch in " \t\r\n":
            i += 1
        elif _is_digit(ch) or (ch == "." and i + 1 < n and _is_digit(text[i + 1])):
            tok = _scan_number(text, i)
            yield Token("num", tok.text, i, tok.value, in_group)
            i += len(tok.text)
        elif _is_ident_start(ch):
            end = _scan_name(text, i)
            yield Token("name", text[i:end], i, None, in_group)
            i = end
        else:
            op = next((o for o in _OPERATORS if text.startswith(o, i)), None)
            if text.startswith("**", i):
                raise ExprError("there is no power operator '**'", i)
            if op == "${" and not template:
                raise ExprError("'${' inside '${...}'", i)
            if op is None or (op == "}" and not template):
                raise ExprError(f"unexpected character {ch!r}", i)
            if op == "${":
                if group_start is not None:
                    raise ExprError(f"'${{' inside the '${{...}}' opened at offset {group_start}", i)
                group_start = i
            elif op == "}":
                if group_start is None:
                    raise ExprError("'}' without a matching '${'", i)
                group_start = None
            yield Token("op", op, i, None, in_group)
            i += len(op)
    if group_start is not None:
        raise ExprError("unterminated '${': expected '}'", group_start)
    yield Token("end", "", n)


# ---------------------------------------------------------------------------- AST

@dataclass(frozen=True)
class Num:
    value: Number
    offset: int


@dataclass(frozen=True)
class Ref:
    name: str  # "params.shadow.size"
    offset: int


@dataclass(frozen=True)
class Unary:
    op: str  # "-" or "+"
    operand: Node
    offset: int


@dataclass(frozen=True)
class Chain:
    """A left-associative run ``first op1 x1 op2 x2 ...`` of one precedence level (kept flat)."""

    first: Node
    rest: tuple[tuple[str, int, Node], ...]  # (operator, operator offset, operand)


@dataclass(frozen=True)
class Call:
    func: str
    args: tuple[Node, ...]
    offset: int


Node = Num | Ref | Unary | Chain | Call

_PRECEDENCE = {"+": 1, "-": 1, "*": 2, "/": 2, "//": 2, "%": 2}


def _render(node: Node) -> str:
    """Canonical text with the parentheses precedence requires (and no others)."""
    if isinstance(node, Num):
        return repr(node.value)
    if isinstance(node, Ref):
        return node.name
    if isinstance(node, Unary):
        inner = _render(node.operand)
        return f"{node.op}({inner})" if isinstance(node.operand, Chain) else f"{node.op}{inner}"
    if isinstance(node, Call):
        return f"{node.func}({', '.join(_render(a) for a in node.args)})"
    level = _PRECEDENCE[node.rest[0][0]]
    parts = [_render_operand(node.first, level)]
    for op, _, operand in node.rest:
        parts.append(f" {op} {_render_operand(operand, level + 1)}")
    return "".join(parts)


def _render_operand(node: Node, min_level: int) -> str:
    text = _render(node)
    if isinstance(node, Chain) and _PRECEDENCE[node.rest[0][0]] < min_level:
        return f"({text})"
    return text


# ---------------------------------------------------------------------------- parser

class _Parser:
    def __init__(self, text: str, template: bool, local_names: Collection[str] = ()) -> None:
        self.text = text
        self.local_names = frozenset(local_names)
        self.tokens = tokenize(text, template)
        self.tok = next(self.tokens)
        self.depth = 0
        self.refs: list[Ref] = []

    def advance(self) -> Token:
        tok = self.tok
        if tok.kind != "end":
            self.tok = next(self.tokens)
        return tok

    def at_op(self, *ops: str) -> bool:
        return self.tok.kind == "op" and self.tok.text in ops

    def enter(self, tok: Token) -> None:
        self.depth += 1
        if self.depth > MAX_DEPTH:
            raise ExprError(f"expression nested too deeply (more than {MAX_DEPTH} levels)", tok.offset)

    def describe(self, tok: Token) -> str:
        return "end of expression" if tok.kind == "end" else repr(tok.text)

    def parse(self) -> Node:
        if self.tok.kind == "end":
            raise ExprError("empty expression", 0)
        node = self.expr()
        if self.tok.kind != "end":
            raise ExprError(f"expected an operator or end of expression, found {self.describe(self.tok)}",
                            self.tok.offset)
        return node

    def chain(self, ops: tuple[str, ...], operand) -> Node:
        first = operand()
        rest = []
        while self.at_op(*ops):
            op_tok = self.advance()
            rest.append((op_tok.text, op_tok.offset, operand()))
        return Chain(first, tuple(rest)) if rest else first

    def expr(self) -> Node:
        return self.chain(("+", "-"), self.term)

    def term(self) -> Node:
        return self.chain(("*", "/", "//", "%"), self.unary)

    def unary(self) -> Node:
        if self.at_op("-", "+"):
            op_tok = self.advance()
            self.enter(op_tok)
            operand = self.unary()
            self.depth -= 1
            return Unary(op_tok.text, operand, op_tok.offset)
        return self.primary()

    def closing(self, open_tok: Token, close: str) -> None:
        if not self.at_op(close):
            raise ExprError(
                f"expected '{close}' to close '{open_tok.text}' at offset {open_tok.offset}, "
                f"found {self.describe(self.tok)}", self.tok.offset)
        self.advance()

    def primary(self) -> Node:
        tok = self.tok
        if tok.kind == "num":
            self.advance()
            return Num(tok.value, tok.offset)
        if tok.kind == "name":
            # Decide call or reference from the raw text, so that a bad token after a bad name
            # does not hide the name's own error.
            if self.text[tok.offset + len(tok.text):].lstrip(" \t\r\n").startswith("("):
                return self.call(tok)
            node = self.reference(tok)
            self.advance()
            return node
        if self.at_op("(", "${"):
            self.advance()
            self.enter(tok)
            inner = self.expr()
            self.closing(tok, ")" if tok.text == "(" else "}")
            self.depth -= 1
            return inner
        raise ExprError(f"expected a number, a name, '(' or '-', found {self.describe(tok)}", tok.offset)

    def call(self, name_tok: Token) -> Node:
        func = name_tok.text
        if func not in FUNCTIONS:
            raise ExprError(f"unknown function '{func}'{_suggest(func, FUNCTIONS)}; "
                            f"functions are {', '.join(sorted(FUNCTIONS))}", name_tok.offset)
        self.advance()
        open_tok = self.advance()
        self.enter(open_tok)
        args: list[Node] = []
        if not self.at_op(")"):
            args.append(self.expr())
            while self.at_op(","):
                self.advance()
                args.append(self.expr())
        self.closing(open_tok, ")")
        self.depth -= 1
        low, high = FUNCTIONS[func]
        if len(args) < low or (high is not None and len(args) > high):
            wanted = f"exactly {low}" if high == low else f"at least {low}"
            plural = "" if low == 1 else "s"
            raise ExprError(f"{func}() takes {wanted} argument{plural} ({len(args)} given)", name_tok.offset)
        return Call(func, tuple(args), name_tok.offset)

    def reference(self, tok: Token) -> Node:
        name = tok.text
        head, dot, _ = name.partition(".")
        if name in FUNCTIONS:
            raise ExprError(f"'{name}' is a function: call it as {name}(...)", tok.offset)
        if name in self.local_names and tok.in_group:  # a loop variable of a repeated pass
            ref = Ref(name, tok.offset)
            self.refs.append(ref)
            return ref
        if head not in NAMESPACES or not dot:
            hint = ""
            if dot:
                close = difflib.get_close_matches(head, NAMESPACES, n=1)
                if close:
                    hint = f"; did you mean '{close[0]}.{name.partition('.')[2]}'?"
            raise ExprError(f"unknown name '{name}': names are params.NAME or scene.NAME{hint}", tok.offset)
        if not tok.in_group:
            raise ExprError(f"'{name}' must be written inside '${{...}}'", tok.offset)
        ref = Ref(name, tok.offset)
        self.refs.append(ref)
        return ref


def _suggest(word: str, choices: Collection[str]) -> str:
    close = difflib.get_close_matches(word, list(choices), n=1)
    return f" (did you mean '{close[0]}'?)" if close else ""


# ---------------------------------------------------------------------------- evaluation

def _checked(value: Number, offset: int) -> Number:
    if isinstance(value, int):
        if not INT_MIN <= value <= INT_MAX:
            raise ExprError("value out of range (integers must fit in 64 bits)", offset)
    elif not math.isfinite(value):
        raise ExprError("value out of range (not a finite number)", offset)
    return value


def _apply(op: str, left: Number, right: Number, offset: int) -> Number:
    if op == "+":
        return left + right
    if op == "-":
        return left - right
    if op == "*":
        return left * right
    if right == 0:
        raise ExprError("division by zero" if op != "%" else "modulo by zero", offset)
    if op == "/":
        return left / right
    if op == "//":
        return left // right
    return left % right


@dataclass(frozen=True)
class Expr:
    """A parsed expression: ``root`` is the AST, offsets are into ``source``."""

    source: str
    root: Node
    refs: tuple[Ref, ...] = field(default=(), repr=False)  # references in source order

    @property
    def names(self) -> frozenset[str]:
        """The referenced names, e.g. ``{"params.shadow.size", "scene.lights"}``."""
        return frozenset(r.name for r in self.refs)

    def __str__(self) -> str:
        """Canonical text (parseable by ``parse``)."""
        return _render(self.root)

    def check_names(self, known: Collection[str], namespace: str | None = None) -> None:
        """Raise ExprError for the first reference (in ``namespace`` if given) not in ``known``."""
        for ref in self.refs:
            if (namespace is None or ref.name.startswith(namespace + ".")) and ref.name not in known:
                raise _unknown_name(ref, known)

    def evaluate(self, env: Mapping[str, int | float | bool]) -> Number:
        """The value under ``env`` (full names such as ``"params.shadow.size"`` -> number)."""
        return self._eval(self.root, env)

    def _eval(self, node: Node, env: Mapping[str, int | float | bool]) -> Number:
        if isinstance(node, Num):
            return node.value
        if isinstance(node, Ref):
            return _lookup(node, env)
        if isinstance(node, Unary):
            value = self._eval(node.operand, env)
            return _checked(-value if node.op == "-" else value, node.offset)
        if isinstance(node, Call):
            args = [self._eval(a, env) for a in node.args]
            if node.func == "min":
                return min(args)
            if node.func == "max":
                return max(args)
            rounded = math.ceil(args[0]) if node.func == "ceil" else math.floor(args[0])
            return _checked(rounded, node.offset)
        value = self._eval(node.first, env)
        for op, offset, operand in node.rest:
            value = _checked(_apply(op, value, self._eval(operand, env), offset), offset)
        return value


def _unknown_name(ref: Ref, known: Collection[str]) -> ExprError:
    namespace = ref.name.partition(".")[0]
    same = sorted(k for k in known if k.startswith(namespace + "."))
    message = f"unknown name '{ref.name}'{_suggest(ref.name, same)}"
    if same:
        shown = ", ".join(same[:30]) + (", ..." if len(same) > 30 else "")
        message += f"; known {namespace} names: {shown}"
    else:
        message += f"; there are no {namespace} names"
    return ExprError(message, ref.offset)


def _lookup(ref: Ref, env: Mapping[str, int | float | bool]) -> Number:
    if ref.name not in env:
        raise _unknown_name(ref, env.keys())
    raw = env[ref.name]
    if isinstance(raw, bool):
        return int(raw)
    if isinstance(raw, numbers.Integral):
        return _checked(int(raw), ref.offset)
    if isinstance(raw, numbers.Real):
        return _checked(float(raw), ref.offset)
    raise ExprError(f"'{ref.name}' is {raw!r}, not a number", ref.offset)


# ---------------------------------------------------------------------------- entry points

def _parse(text: str, template: bool, local_names: Collection[str] = ()) -> Expr:
    if len(text) > MAX_LENGTH:
        raise ExprError(f"expression too long ({len(text)} characters; the limit is {MAX_LENGTH})", MAX_LENGTH)
    parser = _Parser(text, template, local_names)
    root = parser.parse()
    return Expr(text, root, tuple(parser.refs))


def parse(text: str, local_names: Collection[str] = ()) -> Expr:
    """Parse the inside of one ``${...}``; ``local_names`` are bare names allowed besides
    ``params.*``/``scene.*`` (a repeated pass's loop variable); raises ExprError."""
    return _parse(text, template=False, local_names=local_names)


def parse_value(text: object, local_names: Collection[str] = ()) -> Expr | None:
    """Parse a whole YAML value: None for a non-string or a string without ``${``; raises ExprError."""
    if not isinstance(text, str) or "${" not in text:
        return None
    return _parse(text, template=True, local_names=local_names)
