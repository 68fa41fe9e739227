"""Option defaults live in the catalogue only (rules/*.toml), never again as keyword defaults.

The engine calls every static check with all of its rule's options
(``check(ctx, **rule.option_values)``), so a keyword default on a check would be a second copy of
a catalogue default, free to drift from it. For each registered function of a rule with options,
every option must be a parameter, and none may have a default.
"""
from __future__ import annotations

import dataclasses
import inspect
import warnings
from collections.abc import Callable, Iterable
from typing import Any

import pytest

from conformance.report.catalogue import default_catalogue
from conformance.checks import REGISTRY
from conformance.numerics.settings import Settings
from conformance.probes.machinery.registry import PROBES
from conformance.probes.machinery.runner import RUNNER_RULES, Limits

#: What :func:`_defaults_in` reports for an option that is not a parameter of the function.
NOT_A_PARAMETER = "not a parameter"
#: The same, for a function that takes ``**kwargs`` (so the option still reaches it).
ONLY_IN_KWARGS = "only in **kwargs"


def _registered() -> list[tuple[str, Callable[..., Any]]]:
    """(code, function) of every registered static check and probe that has options in the
    catalogue."""
    catalogue = default_catalogue()
    return [(code, function) for code, function in sorted({**REGISTRY, **PROBES}.items())
            if catalogue[code].options]


def _defaults_in(function: Callable[..., Any], option_names: Iterable[str]) -> dict[str, Any]:
    """The options that ``function`` does not take as parameters without a default.

    Maps the option name to the parameter's default in the code, or to :data:`NOT_A_PARAMETER`
    (:data:`ONLY_IN_KWARGS` when the function takes ``**kwargs``) when there is no such parameter.
    """
    parameters = inspect.signature(function).parameters
    takes_kwargs = any(p.kind is inspect.Parameter.VAR_KEYWORD for p in parameters.values())
    found: dict[str, Any] = {}
    for name in option_names:
        parameter = parameters.get(name)
        if parameter is None or parameter.kind is inspect.Parameter.VAR_KEYWORD:
            found[name] = ONLY_IN_KWARGS if takes_kwargs else NOT_A_PARAMETER
        elif parameter.default is not inspect.Parameter.empty:
            found[name] = parameter.default
    return found


def test_some_registered_rule_has_options() -> None:
    assert _registered(), "no registered rule has options: the test below checks nothing"


@pytest.mark.parametrize("code, function", _registered(), ids=[c for c, _ in _registered()])
def test_option_defaults_are_only_in_the_catalogue(code: str, function: Callable[..., Any]
                                                   ) -> None:
    options = default_catalogue()[code].option_values
    where = f"{code}: {function.__module__}.{function.__qualname__}"
    problems = []
    for name, default in _defaults_in(function, options).items():
        if default is ONLY_IN_KWARGS:
            warnings.warn(f"{where} takes the option {name!r} only through **kwargs", stacklevel=1)
        elif default is NOT_A_PARAMETER:
            problems.append(f"{where} has no parameter for the option {name!r} "
                            f"(catalogue default {options[name]!r})")
        else:
            problems.append(f"{where} gives the option {name!r} the default {default!r}; the "
                            f"catalogue's is {options[name]!r}: remove the one in the code")
    assert not problems, "\n".join(problems)


@pytest.mark.parametrize("holder, rules", [
    (Settings, ("simulation-failed",)),   # the options of every simulation rule
    (Limits, RUNNER_RULES),               # the runner's time, memory and restart limits
], ids=["Settings", "Limits"])
def test_option_holders_have_no_defaults_of_their_own(holder: type, rules: tuple[str, ...]
                                                      ) -> None:
    """Dataclasses built from catalogue options carry no second copy of their defaults."""
    catalogue = default_catalogue()
    options = {k: v for name in rules for k, v in catalogue[name].option_values.items()}
    fields = {f.name: f for f in dataclasses.fields(holder)}
    assert set(options) <= set(fields), f"options {set(options) - set(fields)} reach no field"
    copies = [f"{holder.__name__}.{name} = {fields[name].default!r} (catalogue {value!r})"
              for name, value in options.items()
              if fields[name].default is not dataclasses.MISSING]
    assert not copies, "defaults written twice: " + "; ".join(copies)
