"""Numerical building blocks: plain functions of arrays, with no FMU, rule or report in sight.

Finite differences with error estimates (``numdiff``), measuring a Jacobian (``measure``), column
colouring of a sparsity pattern (``colouring``), consistent initialisation, the IDA/CVODE drivers
(``dae``, ``ode``), events, growth fits, comparison helpers, limits and settings; ``graphs/`` holds
the structural graph algorithms (bipartite patterns, maximum matching, Dulmage-Mendelsohn).

The ground floor: it imports only from itself (numpy, scipy, scikit-sundae outside).
"""
