"""omsd's words for what pydantic finds wrong in a configuration (:mod:`omsd.config.schema`).

Pydantic reports an error as a type (``int_type``, ``missing``, ``extra_forbidden``...) at a
``loc``, a path of keys and indices. The wording is omsd's own, kept from before the schema:
:class:`Says` wraps a type's validation and words any error in the value itself ("expected a
number (motor steps)"); :class:`Table`, the base of every table of the schema, words the errors
of a table (an unknown key with the keys allowed, a missing key, a value that is not a table);
rules that need several keys are model validators that raise :func:`problem`. Every worded
error has the type ``omsd``; its ``ctx`` holds the text, and ``at``, a key path below the place
pydantic reports it at. The tags of the unions (``<list>``, ``<table>``) in a ``loc`` are not
keys: :func:`config_error` keeps the steps the document has and makes the one line of
:class:`omsd.config_errors.ConfigError`.
"""

import difflib
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Annotated, Any, NoReturn, Self

from pydantic import (
    BaseModel,
    ConfigDict,
    Field,
    GetCoreSchemaHandler,
    GetJsonSchemaHandler,
    ValidationError,
    model_validator,
)
from pydantic.functional_validators import ModelWrapValidatorHandler
from pydantic.json_schema import JsonSchemaValue
from pydantic_core import ErrorDetails, InitErrorDetails, PydanticCustomError, core_schema

from omsd.config_errors import ConfigError, Key, KeyPath, board_label, key_text, show

OMSD = "omsd"  # the type of every error worded here


# -- errors in omsd's words ---------------------------------------------------------------------


def problem(
    *,
    expected: str | None = None,
    detail: str | None = None,
    at: KeyPath = (),
    got: str | None = None,
    also: KeyPath | None = None,
) -> PydanticCustomError:
    """An error in omsd's words: ``expected <expected>, got <the value>`` (``got`` replaces the
    value shown), or ``detail`` as it is; ``at`` the key path below the place it is raised at,
    ``also`` another key of the document the error is about (a duplicate)."""
    text = detail if detail is not None else f"expected {expected}"
    ctx: dict[str, Any] = {"text": text, "at": at}
    if detail is not None:
        ctx["detail"] = detail
    if expected is not None:
        ctx["expected"] = expected
    if got is not None:
        ctx["got"] = got
    if also is not None:
        ctx["also"] = also
    return PydanticCustomError(OMSD, "{text}", ctx)


def _reraise(errors: Iterable[ErrorDetails]) -> NoReturn:
    """Raise ``errors`` again from a validator (pydantic puts them below its place)."""
    details: list[InitErrorDetails] = []
    for error in errors:
        ctx = error.get("ctx")
        if error["type"] == OMSD:
            assert ctx is not None
            details.append(
                InitErrorDetails(
                    type=PydanticCustomError(OMSD, "{text}", ctx),
                    loc=error["loc"],
                    input=error["input"],
                )
            )
        elif ctx is not None:
            details.append(
                InitErrorDetails(
                    type=error["type"], loc=error["loc"], input=error["input"], ctx=ctx
                )
            )
        else:
            details.append(
                InitErrorDetails(type=error["type"], loc=error["loc"], input=error["input"])
            )
    raise ValidationError.from_exception_data(OMSD, details)


def _is_tag(step: Key, value: Any) -> bool:
    """Whether a step of a ``loc`` is a union's tag rather than a key or an index of ``value``."""
    if isinstance(value, dict):
        return step not in value
    if isinstance(value, list):
        return not isinstance(step, int)
    return True


@dataclass(frozen=True)
class Says:
    """A type as omsd's errors and reference name it: what a value of it is (``expected``),
    with other words for some of pydantic's error types (``by_type``: ``finite_number`` "a
    finite number"). As metadata of ``Annotated``, it wraps the type's validation: an error
    pydantic finds in the value itself becomes ``expected <words>, got <value>``; an error in a
    table inside the value (``holds_tables``), or one already worded, passes through.

    ``accepts`` is what the file may write when it is not the annotated type (an address
    ``int | str`` read as a :class:`~omsd.config.TcpEndpoint`), and ``convert`` makes the
    annotated type of it (it may raise ``ValueError`` or :func:`problem`; ``with_info`` gives it
    pydantic's ``ValidationInfo``, whose ``context`` holds the directory paths are relative to).
    ``json`` replaces the JSON Schema pydantic derives."""

    expected: str
    by_type: tuple[tuple[str, str], ...] = ()
    holds_tables: bool = False
    accepts: Any = None
    convert: Callable[..., Any] | None = None
    with_info: bool = False
    json: Mapping[str, Any] | None = None
    secret: bool = False  # the value is not shown (a password)

    def __get_pydantic_core_schema__(
        self, source: Any, handler: GetCoreSchemaHandler
    ) -> core_schema.CoreSchema:
        inner = handler(source) if self.accepts is None else handler.generate_schema(self.accepts)
        if self.convert is not None and self.with_info:
            inner = core_schema.with_info_after_validator_function(self.convert, inner)
        elif self.convert is not None:
            inner = core_schema.no_info_after_validator_function(self.convert, inner)
        return core_schema.no_info_wrap_validator_function(self._validate, inner)

    def __get_pydantic_json_schema__(
        self, schema: core_schema.CoreSchema, handler: GetJsonSchemaHandler
    ) -> JsonSchemaValue:
        if self.json is not None:
            return dict(self.json)
        return handler(schema)

    def _validate(self, value: Any, handler: core_schema.ValidatorFunctionWrapHandler) -> Any:
        try:
            return handler(value)
        except ValidationError as exc:
            errors = exc.errors()
            if not any(self._here(e, value) for e in errors):
                raise
            _reraise(self._word(e) if self._here(e, value) else e for e in errors)

    def _here(self, error: ErrorDetails, value: Any) -> bool:
        if error["type"] in (OMSD, "missing"):
            return False
        if not self.holds_tables:
            return True
        return all(_is_tag(step, value) for step in error["loc"])

    def _word(self, error: ErrorDetails) -> ErrorDetails:
        expected = dict(self.by_type).get(error["type"], self.expected)
        got = "none" if error["type"] == "too_short" else None
        if self.secret:
            custom = problem(detail=f"expected {expected}")
        else:
            custom = problem(expected=expected, got=got)
        return ErrorDetails(
            type=OMSD, loc=(), msg=custom.message(), input=error["input"], ctx=custom.context or {}
        )


@dataclass(frozen=True)
class Required:
    """A key that must be written, and what its error says when it is not (``expected
    <what>, got none``), at the key or, ``at_table``, at its table."""

    what: str
    at_table: bool = False


@dataclass(frozen=True)
class Default:
    """The default as the reference shows it, where the field's own is not it (computed)."""

    text: str


@dataclass(frozen=True)
class Option:
    """The command-line option that gives this key of the single board (``--tcp``)."""

    flag: str


class Table(BaseModel):
    """A TOML table: unknown keys are errors, values are taken as TOML types them (no "5" for
    5), nothing changes after validation."""

    model_config = ConfigDict(extra="forbid", strict=True, frozen=True)

    @model_validator(mode="wrap")
    @classmethod
    def _worded(cls, data: Any, handler: ModelWrapValidatorHandler[Self]) -> Self:
        try:
            return handler(data)
        except ValidationError as exc:
            _reraise(cls._word(error) for error in exc.errors())

    @classmethod
    def key_names(cls) -> list[str]:
        """The keys of the table, in order."""
        return [info.alias or name for name, info in cls.model_fields.items()]

    @classmethod
    def _word(cls, error: ErrorDetails) -> ErrorDetails:
        loc, kind = error["loc"], error["type"]
        if kind in ("model_type", "model_attributes_type") and not loc:
            custom = problem(expected="a table")
        elif kind == "extra_forbidden" and len(loc) == 1:
            key = str(loc[0])
            close = difflib.get_close_matches(key, cls.key_names(), n=1)
            hint = f" (did you mean {close[0]!r}?)" if close else ""
            detail = f"unknown key{hint}; expected one of {', '.join(cls.key_names())}"
            custom = problem(detail=detail, at=(key,))
        elif kind == "missing" and len(loc) == 1:
            key = str(loc[0])
            required = cls._required(key)
            at: KeyPath = () if required.at_table else (key,)
            custom = problem(detail=f"expected {required.what}, got none", at=at)
        else:
            return error
        return ErrorDetails(
            type=OMSD, loc=(), msg=custom.message(), input=error["input"], ctx=custom.context or {}
        )

    @classmethod
    def _required(cls, key: str) -> Required:
        for name, info in cls.model_fields.items():
            if key in (name, info.alias):
                found = [m for m in info.metadata if isinstance(m, Required)]
                if found:
                    return found[0]
        return Required(f"a value for {key}")


def _any_case(text: str) -> str:
    """A regular expression (ECMA 262 as JSON Schema has them) matching ``text`` in any case."""
    out = []
    for ch in text:
        if ch.isalpha():
            out.append(f"[{ch.upper()}{ch.lower()}]")
        elif ch.isalnum() or ch in "-_ ":
            out.append(ch)
        else:
            out.append("\\" + ch)
    return "".join(out)


def choices_json(values: Sequence[str], padded: bool = False) -> dict[str, Any]:
    """The JSON Schema of a case-insensitive choice: the values (what an editor completes), or
    the same in any case."""
    space = r"\s*" if padded else ""
    pattern = f"^{space}(?:{'|'.join(_any_case(v) for v in values)}){space}$"
    return {"anyOf": [{"enum": list(values)}, {"type": "string", "pattern": pattern}]}


def _lower(value: Any) -> Any:
    return value.lower() if isinstance(value, str) else value


@dataclass(frozen=True)
class Choice(Says):
    """One of ``values``, in any case (``"RAW"`` is ``"raw"``)."""

    values: tuple[str, ...] = ()

    def __get_pydantic_core_schema__(
        self, source: Any, handler: GetCoreSchemaHandler
    ) -> core_schema.CoreSchema:
        inner = core_schema.no_info_before_validator_function(
            _lower, core_schema.literal_schema(list(self.values))
        )
        return core_schema.no_info_wrap_validator_function(self._validate, inner)

    def __get_pydantic_json_schema__(
        self, schema: core_schema.CoreSchema, handler: GetJsonSchemaHandler
    ) -> JsonSchemaValue:
        return choices_json(self.values)


def choice(values: Sequence[str]) -> Choice:
    return Choice(" or ".join(show(v) for v in values), values=tuple(values))


def integer(lo: int, hi: int | None = None) -> Says:
    """An integer ``lo..hi`` (or ``>= lo``)."""
    words = f"an integer {lo}..{hi}" if hi is not None else f"an integer >= {lo}"
    return Says(words, accepts=Annotated[int, Field(ge=lo, le=hi)])


# -- one line per error -------------------------------------------------------------------------


def config_error(
    exc: ValidationError,
    document: Any,
    source: str,
    options: Mapping[KeyPath, str] | None = None,
) -> ConfigError:
    """The first of pydantic's errors as one line: the key path (a board named by its name) or,
    for the command line, the option; what was expected and the value found."""
    error = exc.errors(include_url=False)[0]
    ctx = error.get("ctx") or {}
    path = (*_document_path(error["loc"], document), *ctx.get("at", ()))
    if error["type"] == OMSD:
        detail = ctx.get("detail")
        if detail is None:
            got = ctx.get("got") or show(_value_at(document, path))
            detail = f"{ctx['text']}, got {got}"
    else:  # not worded here: pydantic's own words
        detail = f"{error['msg'][:1].lower()}{error['msg'][1:]}, got {show(error['input'])}"
    also: KeyPath | None = ctx.get("also")
    if options is not None:
        option = _option_of(path, options)
        if also is not None and _option_of(also, options) == option:
            return ConfigError(option, None, f"{detail} twice", path=path)
        return ConfigError(option, None, detail, path=path)
    labels = _labels(document)
    return ConfigError(
        source,
        key_text(path, labels),
        detail,
        path=path,
        also=None if also is None else key_text(also, labels),
        also_path=also,
    )


def _document_path(loc: Sequence[Key], document: Any) -> KeyPath:
    """The steps of a ``loc`` that are keys and indices of the document (not union tags)."""
    path: list[Key] = []
    node = document
    for step in loc:
        if _is_tag(step, node):
            continue
        path.append(step)
        node = node[step]
    return tuple(path)


def _value_at(document: Any, path: KeyPath) -> Any:
    node = document
    for step in path:
        if _is_tag(step, node) or (isinstance(step, int) and step >= len(node)):
            return None
        node = node[step]
    return node


def _labels(document: Any) -> dict[KeyPath, str]:
    """Each ``[[board]]`` named by its name as written, or the name it is given."""
    boards = document.get("board") if isinstance(document, dict) else None
    if not isinstance(boards, list):
        return {}
    return {
        ("board", i): board_label(b.get("name") if isinstance(b, dict) else None, i)
        for i, b in enumerate(boards)
    }


def _option_of(path: KeyPath, options: Mapping[KeyPath, str]) -> str:
    for n in range(len(path), -1, -1):
        if path[:n] in options:
            return options[path[:n]]
    return "command line"


__all__ = [
    "OMSD",
    "Choice",
    "Default",
    "Option",
    "Required",
    "Says",
    "Table",
    "choice",
    "choices_json",
    "config_error",
    "integer",
    "problem",
]
