"""Static checks: variable and alias names under the FMI 3.0 naming conventions (DAE533-DAE534).

Every name is non-empty and free of carriage return, line feed and tab, whatever the convention
(FMI 3.0.2 §2.4.7.5.1: the flat convention is xs:normalizedString, and the structured grammar has
no such characters). XML turns a literal tab or line break in an attribute into a space, so these
characters only arrive as character references (``&#9;``, ``&#10;``, ``&#13;``); they still reach
the importer, which then shows or writes a name that breaks its lines and tables. Under
``variableNamingConvention="structured"`` every name must also follow the grammar of
:mod:`conformance.model.structured_names`. A name with a forbidden character is reported by
``variable-name-invalid`` only, not again as a structured-name fault.

Cost: one search over all names joined for the forbidden characters, and one compiled regular
expression per name under the structured convention.
"""
from __future__ import annotations

from collections.abc import Iterator
from operator import attrgetter

from .context import Check, CheckContext
from ..report.findings import Location, Violation, evidence
from ..model.description import ModelDescription, Variable
from ..model.structured_names import all_structured, is_structured_name, name_problem
from .model_analysis import analyse

_FORBIDDEN = {"\r": "carriage return (U+000D)", "\n": "line feed (U+000A)",
              "\t": "tab (U+0009)"}
_SHOWN = str.maketrans({"\r": "\\r", "\n": "\\n", "\t": "\\t"})
_ALIASES = attrgetter("aliases")


def shown_name(name: str) -> str:
    """A name with its forbidden characters written as escapes, so a report stays one line."""
    return name.translate(_SHOWN)


def _all_names(ctx: CheckContext) -> list[str]:
    """Every variable and alias name (memoised: both rules read it)."""
    def compute() -> list[str]:
        assert ctx.model is not None
        variables = ctx.model.variables
        names = [var.name for var in variables]
        if any(d.aliases for d in analyse(ctx.model).details):  # few distinct: no pass if none
            names.extend(alias for var in filter(_ALIASES, variables) for alias in var.aliases)
        return names
    return ctx.memo("model_names.names", compute)


def _names(model: ModelDescription) -> Iterator[tuple[str, Variable, bool]]:
    """(name, variable, is_alias) for every variable and alias name, in document order."""
    for var in model.variables:
        yield var.name, var, False
        for alias in var.aliases:
            yield alias, var, True


def _flawed(name: str) -> bool:
    return not name or "\r" in name or "\n" in name or "\t" in name


def _location(model: ModelDescription, var: Variable) -> Location:
    return Location(file=model.file, line=var.line, path=var.path.translate(_SHOWN))


def variable_name_invalid(ctx: CheckContext) -> Iterator[Violation]:
    """DAE533 MV-02, MD-06: names are non-empty and contain no CR, LF or TAB."""
    if (model := ctx.model) is None:
        return
    names = _all_names(ctx)
    joined = "\x00".join(names)
    if "\r" not in joined and "\n" not in joined and "\t" not in joined and all(names):
        return  # the usual case, decided in C: no empty name, no forbidden character
    for name, var, is_alias in _names(model):
        if not _flawed(name):
            continue
        found = [label for char, label in _FORBIDDEN.items() if char in name]
        yield Violation(
            "name that is empty or contains a carriage return, line feed or tab: {subject}; "
            "give every variable and alias a non-empty name without these characters",
            _location(model, var),
            evidence(name=shown_name(name), alias=is_alias, characters=found or ["(empty name)"],
                     variable=shown_name(var.name), value_reference=var.vr),
            subject=shown_name(name) or f"(empty {'alias' if is_alias else 'variable'} name)",
            part="empty" if not name else None)


def variable_name_not_structured(ctx: CheckContext) -> Iterator[Violation]:
    """DAE534 MD-06: under the structured convention every name follows the FMI grammar."""
    if (model := ctx.model) is None or model.naming_convention.strip() != "structured":
        return
    if all_structured(_all_names(ctx)):
        return  # the usual case
    for name, var, is_alias in _names(model):
        if is_structured_name(name) or _flawed(name):
            continue  # legal, or variable-name-invalid's
        problem = name_problem(name)
        index = problem.index if problem is not None else 0
        yield Violation(
            "name that breaks the structured naming convention: {subject}; write it as dotted "
            "parts of letters, digits and '_' (not starting with a digit), quote any other part "
            "as '...', and use [i,j] for array elements and der(name) for derivatives, or "
            "declare variableNamingConvention=\"flat\"",
            _location(model, var),
            evidence(name=name, alias=is_alias, position=index + 1,
                     found=name[index] if index < len(name) else "(end of name)",
                     expected=problem.expected if problem is not None else None,
                     value_reference=var.vr),
            subject=name)


CHECKS: dict[str, Check] = {
    "DAE533": variable_name_invalid,
    "DAE534": variable_name_not_structured,
}
