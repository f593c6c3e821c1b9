"""Weighted sums of model names: the text ``0.7*erf-play + 0.3*preisach`` read without ``eval``.

The grammar (whitespace anywhere between tokens, none needed)::

    expression := ['-'] term (('+' | '-') term)*
    term       := [number '*'] name  |  name ['*' number]
    number     := a Python decimal float literal without sign: 0.7, 3, .5, 2., 1e-3, 1_000.5
    name       := a spelling the caller accepts (the model registry's names and aliases)

A term's weight is its number (1 without one), negated after a ``-``. The expression stands for
the operator ``Σ_k w_k · M_k`` (:func:`hysteresis.algebra.weighted_sum`); the parser only reads
the text and knows nothing of operators, so it does not import the registry (the registry,
:mod:`analysis.experiments.models`, passes its spellings in).

Names contain ``-`` (``erf-play``), which is also the minus sign: a name is the longest accepted
spelling at its place, cut only at a ``-``, so ``erf-play-preisach`` reads as
``erf-play - preisach`` and ``preisach-gauss`` stays one name. A word that no accepted spelling
starts is an unknown name.

Refused, each with a one-line :class:`ModelExpressionError` (a ``ValueError``) whose message
starts with ``model``: an empty text or part (``play +``, ``+ play``, ``play + + relay``), a
number without a name (``0.5``, ``0.5 + play``), two weights on a term (``2*play*3``),
parentheses, any other character (``/``, ``^``, ``,``), a number glued to letters (``2play``,
``1j``), non-finite weights (``1e999``, ``inf``, ``nan``), a zero weight (the part would do
nothing; leave it out), an unknown name (the message lists the names) and a name given twice
(``play + play``: every part is built from the same parameters, so the two would be one operator
— write the weights' sum instead).

The canonical text (``str(expression)``) keeps the terms in the order given (the sum's outputs
are accumulated in that order, so the order can change the last bit), spells every name
canonically, writes every weight as its shortest round-trip decimal without a ``1*``, and puts
``' + '`` / ``' - '`` between terms: ``0.70*erf_play+.3*preisach`` becomes
``0.7*erf-play + 0.3*preisach``. Parsing the canonical text gives the same expression back.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping
from dataclasses import dataclass, field

__all__ = ["ModelExpression", "ModelExpressionError", "ModelTerm", "parse_model_expression"]

#: an unsigned Python decimal float literal (or decimal integer), underscores between digits
_NUMBER = re.compile(
    r"(?:\d(?:_?\d)*(?:\.(?:\d(?:_?\d)*)?)?|\.\d(?:_?\d)*)(?:[eE][+-]?\d(?:_?\d)*)?", re.ASCII
)
#: a word: letters, digits and '_', parts joined by '-' followed by a letter (so that
#: ``play-0.3*relay`` ends the word before ``-0.3``)
_WORD = re.compile(r"[A-Za-z_][A-Za-z0-9_]*(?:-[A-Za-z_][A-Za-z0-9_]*)*", re.ASCII)
#: what a number must not run into (``2play``, ``1j``, ``1.2.3``, ``1__0``)
_GLUED = re.compile(r"[A-Za-z0-9_.]+", re.ASCII)
_NON_FINITE = ("inf", "infinity", "nan")


class ModelExpressionError(ValueError):
    """A text that is not a weighted sum of model names.

    ``str(error)`` is ``"model ..."`` (the library's convention: the parameter first);
    :attr:`detail` is the same without the leading ``"model "``, for a caller that names the
    parameter itself (the command line: ``argument --model: ...``); :attr:`unknown` is the
    unknown name when that is the fault, else ``None``.
    """

    def __init__(self, detail: str, unknown: str | None = None) -> None:
        super().__init__(f"model {detail}")
        self.detail = detail
        self.unknown = unknown


@dataclass(frozen=True)
class ModelTerm:
    """One term ``weight * name`` (``name`` canonical; ``spelling`` as written)."""

    name: str
    weight: float
    spelling: str = field(default="", compare=False, repr=False)

    def __str__(self) -> str:
        """``"2*play"``, ``"-0.5*relay"``, ``"play"`` (weight 1), ``"-play"`` (weight -1)."""
        return f"-{_magnitude(self)}" if self.weight < 0 else _magnitude(self)


def _magnitude(term: ModelTerm) -> str:
    """The term without its sign: the shortest round-trip decimal of ``|weight|`` (no ``.0``,
    no ``1*``) joined to the name by ``*``."""
    w = abs(term.weight)
    if w == 1.0:
        return term.name
    text = repr(w)
    return f"{text[:-2] if text.endswith('.0') else text}*{term.name}"


@dataclass(frozen=True)
class ModelExpression:
    """A weighted sum ``Σ_k terms[k].weight · terms[k].name`` of model names (names distinct,
    weights finite and nonzero), in the order written."""

    terms: tuple[ModelTerm, ...]

    @property
    def names(self) -> tuple[str, ...]:
        """The canonical names, in order."""
        return tuple(t.name for t in self.terms)

    @property
    def weights(self) -> tuple[float, ...]:
        """The weights, in order."""
        return tuple(t.weight for t in self.terms)

    @property
    def plain(self) -> str | None:
        """The name when the expression is one name with weight 1 (``play``, ``1*play``), which
        stands for the model itself, not a sum; else ``None``."""
        if len(self.terms) == 1 and self.terms[0].weight == 1.0:
            return self.terms[0].name
        return None

    def __str__(self) -> str:
        """The canonical text: ``"0.7*erf-play - 0.3*preisach"`` (see the module docstring)."""
        first, *rest = self.terms
        out = str(first)
        for term in rest:
            out += f" {'-' if term.weight < 0 else '+'} {_magnitude(term)}"
        return out


@dataclass(frozen=True)
class _Token:
    kind: str  # "number", "name", "+", "-", "*"
    text: str
    column: int  # 1-based
    value: float | str | None = None


def _tokens(text: str, spellings: Mapping[str, str]) -> list[_Token]:
    """The tokens of ``text``; names resolved to the longest accepted spelling (see the module
    docstring), unknown words and stray characters refused."""
    out: list[_Token] = []
    i = 0
    while i < len(text):
        ch = text[i]
        col = i + 1
        if ch.isspace():
            i += 1
        elif ch in "+-*":
            out.append(_Token(ch, ch, col))
            i += 1
        elif ch in "()[]{}":
            raise ModelExpressionError(
                f"{text!r}: parentheses are not part of a model sum (column {col}); write the "
                "terms out, e.g. 0.35*play + 0.15*relay"
            )
        elif ch in "0123456789.":
            m = _NUMBER.match(text, i)
            end = i if m is None else m.end()
            glued = _GLUED.match(text, end)
            if m is None or glued is not None:
                stop = max(_GLUED.match(text, i).end(), glued.end() if glued else end)  # type: ignore[union-attr]
                word = text[i:stop]
                raise ModelExpressionError(
                    f"{text!r}: {word!r} at column {col} is not a number (a weight is a real "
                    "decimal number such as 0.7 or 3e-1, joined to its name by '*')"
                )
            value = float(m.group().replace("_", ""))
            if not math.isfinite(value):
                raise ModelExpressionError(
                    f"{text!r}: the weight {m.group()} at column {col} is not finite"
                )
            out.append(_Token("number", m.group(), col, value))
            i = m.end()
        else:
            m = _WORD.match(text, i)
            if m is None:
                raise ModelExpressionError(
                    f"{text!r}: unexpected character {ch!r} at column {col} (a model sum has "
                    "names, numbers, '+', '-' and '*')"
                )
            word = m.group()
            if word.lower() in _NON_FINITE:
                raise ModelExpressionError(
                    f"{text!r}: the weight {word} at column {col} is not finite"
                )
            i += _resolve(text, word, i, spellings, out)
    return out


def _resolve(
    text: str, word: str, start: int, spellings: Mapping[str, str], out: list[_Token]
) -> int:
    """Append the name tokens (and the '-' between them) that ``word`` reads as; return the
    number of characters consumed (all of ``word``)."""
    pieces = word.split("-")
    pos = start
    k = 0
    while k < len(pieces):
        # the longest accepted spelling made of pieces[k:j]
        for j in range(len(pieces), k, -1):
            candidate = "-".join(pieces[k:j])
            if candidate in spellings:
                break
        else:
            unknown = "-".join(pieces[k:])
            names = ", ".join(dict.fromkeys(spellings.values()))
            where = "" if unknown == text.strip() else f" in {text!r}"
            raise ModelExpressionError(
                f"must be one of {names}; got {unknown!r}{where}", unknown=unknown
            )
        out.append(_Token("name", candidate, pos + 1, spellings[candidate]))
        pos += len(candidate)
        if j < len(pieces):
            out.append(_Token("-", "-", pos + 1))
            pos += 1
        k = j
    return pos - start


class _Parser:
    """Recursive descent over the tokens (one method per rule of the grammar)."""

    def __init__(self, text: str, tokens: list[_Token]) -> None:
        self.text = text
        self.tokens = tokens
        self.i = 0

    def fail(self, what: str) -> ModelExpressionError:
        return ModelExpressionError(f"{self.text!r}: {what}")

    def peek(self) -> _Token | None:
        return self.tokens[self.i] if self.i < len(self.tokens) else None

    def take(self) -> _Token:
        tok = self.tokens[self.i]
        self.i += 1
        return tok

    def expression(self) -> list[tuple[float, _Token]]:
        sign = 1.0
        first = self.peek()
        if first is not None and first.kind == "-":
            self.take()
            sign = -1.0
        terms = [self.term(sign, first if sign < 0 else None)]
        while (tok := self.peek()) is not None:
            if tok.kind not in "+-":
                raise self.fail(
                    f"expected '+' or '-' before {tok.text!r} at column {tok.column} "
                    "(a term is NAME, NUMBER*NAME or NAME*NUMBER)"
                )
            self.take()
            terms.append(self.term(1.0 if tok.kind == "+" else -1.0, tok))
        return terms

    def term(self, sign: float, operator: _Token | None) -> tuple[float, _Token]:
        tok = self.peek()
        if tok is None or tok.kind in "+-*":
            if operator is not None:
                what = f"{operator.text!r} at column {operator.column} is not followed by a term"
            elif tok is None:
                what = "empty; give a model name or a weighted sum such as 0.7*erf-play + 0.3*pi"
            else:
                what = f"{tok.text!r} at column {tok.column} does not start a term"
            raise self.fail(what)
        self.take()
        if tok.kind == "number":
            star = self.peek()
            if star is None or star.kind != "*":
                raise self.fail(
                    f"the weight {tok.text} at column {tok.column} has no model name "
                    f"(write {tok.text}*NAME)"
                )
            self.take()
            name = self.peek()
            if name is not None and name.kind == "number":
                raise self.fail(f"two weights in a row at column {name.column}")
            if name is None or name.kind != "name":
                raise self.fail(f"'*' at column {star.column} is not followed by a model name")
            self.take()
            self.no_second_weight(name)
            return sign * float(tok.value), name  # type: ignore[arg-type]
        star = self.peek()
        if star is None or star.kind != "*":
            return sign, tok
        self.take()
        number = self.peek()
        if number is None or number.kind != "number":
            raise self.fail(f"'*' at column {star.column} is not followed by a number")
        self.take()
        self.no_second_weight(tok)
        return sign * float(number.value), tok  # type: ignore[arg-type]

    def no_second_weight(self, name: _Token) -> None:
        tok = self.peek()
        if tok is not None and tok.kind == "*":
            raise self.fail(f"the term of {name.text!r} has two weights (column {tok.column})")


def parse_model_expression(text: str, spellings: Mapping[str, str]) -> ModelExpression:
    """Read ``text`` as a weighted sum of model names (see the module docstring).

    Parameters
    ----------
    text:
        The expression, e.g. ``"0.7*erf-play + 0.3*preisach"`` or a single name.
    spellings:
        Every accepted spelling -> its canonical name (canonical names map to themselves).

    Raises
    ------
    TypeError
        ``text`` is not a string.
    ModelExpressionError
        (a ``ValueError``) anything that is not such a sum, in one line saying what and where.
    """
    if not isinstance(text, str):
        raise TypeError(f"model must be a str, got {type(text).__name__}")
    tokens = _tokens(text, spellings)
    parser = _Parser(text, tokens)
    terms: list[ModelTerm] = []
    seen: dict[str, str] = {}
    for weight, tok in parser.expression():
        name = str(tok.value)
        if name in seen:
            spelled = "" if seen[name] == tok.text else f" (as {seen[name]!r} and {tok.text!r})"
            raise parser.fail(
                f"{name!r} appears twice{spelled}; every part is built from the same "
                "parameters, so give it once with the weights' sum"
            )
        if weight == 0.0:
            raise parser.fail(
                f"the weight of {tok.text!r} (column {tok.column}) is 0; leave the term out"
            )
        seen[name] = tok.text
        terms.append(ModelTerm(name, weight, tok.text))
    return ModelExpression(tuple(terms))
