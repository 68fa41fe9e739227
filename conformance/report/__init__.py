"""Findings and the report: the vocabulary every stage speaks, and the catalogue of rules.

``findings`` (Violation, Location, Finding, FmuReport, Report: frozen), ``catalogue`` (the rule
catalogue read from ``rules/``, the single source of truth for codes, names, severities and
options), ``baseline`` (accepted findings), ``reader`` (a JSON report read back into a Report) and
``paths`` (where the shipped catalogue and XSDs live). Rendering lives in ``reporters/``.

One floor above ``numerics``: it imports nothing else of the package.
"""
