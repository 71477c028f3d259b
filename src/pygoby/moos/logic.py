"""MOOS-IvP logic conditions (`CONDITION = (DEPLOY = true) and (NAV_DEPTH > 5)`), as
lib_logic's LogicCondition evaluates them.

* `VAR op VALUE` with op one of `= == != < <= > >=`; VALUE is a number, a string (quoted or
  bare) or `$(OTHER_VAR)`. `==` compares strings without regard to case, `=` exactly. A string
  compared with a number must read as a number, else the relation is false; an unknown
  variable makes its relation false.
* `(A) and (B)`, `(A) or (B)` (the operands in parentheses), `!(A)`. The expression is split
  at its first top-level operator, left to right, as MOOS-IvP does (no precedence).
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from pygoby.errors import ConfigError

_RELATIONS = ("==", "!=", "<=", ">=", "=", "<", ">")
_VARIABLE = re.compile(r"[A-Za-z0-9_.:\-\[\]]+")
_RIGHT_VARIABLE = re.compile(r"\$\(([A-Za-z0-9_.:\-]+)\)")

Value = float | str


def _is_number(text: str) -> bool:
    return re.fullmatch(r"[+-]?([0-9]+\.?[0-9]*|\.[0-9]+)([eE][+-]?[0-9]+)?", text) is not None


def _unquote(text: str) -> str:
    return text[1:-1] if len(text) >= 2 and text[0] == text[-1] == '"' else text


def _strip_parens(text: str) -> str:
    """Remove parentheses enclosing the whole text (repeatedly)."""
    text = text.strip()
    while text.startswith("(") and text.endswith(")") and _closing(text, 0) == len(text) - 1:
        text = text[1:-1].strip()
    return text


def _closing(text: str, start: int) -> int:
    depth = 0
    for i in range(start, len(text)):
        depth += {"(": 1, ")": -1}.get(text[i], 0)
        if depth == 0:
            return i
    return -1


@dataclass
class _Node:
    kind: str  # "and", "or", "not", or a relation
    left: Any = None  # a _Node, or the variable name of a relation
    right: Any = None  # a _Node, or a relation's ("variable" | "string" | ..., value)


class LogicCondition:
    def __init__(self, text: str) -> None:
        self.text = text
        self.variables: list[str] = []
        self.root = self._parse(text)

    def _error(self, why: str) -> ConfigError:
        return ConfigError(f"condition {self.text!r}: {why}")

    def _parse(self, text: str):
        if text.count("(") != text.count(")") or _closing_balance(text) < 0:
            raise self._error("unbalanced parentheses")
        body = _strip_parens(text)
        if not body:
            raise self._error("empty condition")
        if body.startswith("!"):
            rest = body[1:].strip()
            if rest.startswith("(") and _closing(rest, 0) == len(rest) - 1:
                return _Node("not", self._parse(rest))
        depth = 0
        for i, c in enumerate(body):
            depth += {"(": 1, ")": -1}.get(c, 0)
            if depth:
                continue
            for word in ("or", "and"):
                tail = body[i : i + len(word) + 2].lower()
                if i > 0 and tail == f" {word} ":
                    return _Node(
                        word, self._parse(body[:i]), self._parse(body[i + len(word) + 2 :])
                    )
            for relation in _RELATIONS:
                if body.startswith(relation, i):
                    return self._relation(
                        body[:i].strip(), relation, body[i + len(relation) :].strip()
                    )
        raise self._error(f"{body!r} is not a relation (VAR = value) or a combination of them")

    def _relation(self, left: str, relation: str, right: str):
        if not _VARIABLE.fullmatch(left):
            raise self._error(f"{left!r} is not a variable name")
        if not right:
            raise self._error(f"nothing to compare {left} with")
        self.variables.append(left)
        match = _RIGHT_VARIABLE.fullmatch(right)
        if match:
            self.variables.append(match.group(1))
            return _Node(relation, left, ("variable", match.group(1)))
        if _is_number(right):
            return _Node(relation, left, ("double", float(right)))
        return _Node(relation, left, ("string", _unquote(right)))

    def evaluate(self, values: Mapping[str, Value]) -> bool:
        return self._evaluate(self.root, values)

    def _evaluate(self, node: _Node, values: Mapping[str, Value]) -> bool:
        if node.kind == "not":
            return not self._evaluate(node.left, values)
        if node.kind in ("and", "or"):
            left, right = self._evaluate(node.left, values), self._evaluate(node.right, values)
            return (left and right) if node.kind == "and" else (left or right)
        lhs = values.get(node.left)
        kind, raw = node.right
        rhs = values.get(raw) if kind == "variable" else raw
        if lhs is None or rhs is None:
            return False
        return _compare(node.kind, lhs, rhs)


def _closing_balance(text: str) -> int:
    depth = 0
    for c in text:
        depth += {"(": 1, ")": -1}.get(c, 0)
        if depth < 0:
            return -1
    return depth


def _compare(relation: str, left: Value, right: Value) -> bool:
    if isinstance(left, str) and isinstance(right, str):
        a, b = _unquote(left), _unquote(right)
        if relation == "==":
            return a.lower() == b.lower()
    else:
        if isinstance(left, str) or isinstance(right, str):
            text = _unquote(left if isinstance(left, str) else right)  # type: ignore[arg-type]
            if not _is_number(text):
                return False
        a, b = float(left), float(right)  # type: ignore[assignment]
        if relation == "==":
            return a == b
    return {
        "=": a == b,
        "!=": a != b,
        "<": a < b,
        "<=": a <= b,
        ">": a > b,
        ">=": a >= b,
    }[relation]
