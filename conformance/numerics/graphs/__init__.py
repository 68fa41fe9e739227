"""Structural graph algorithms on sparsity patterns: the residual/algebraic-variable graph.

``bipartite`` (a pattern as a bipartite graph), ``matching`` (maximum matching, structural rank)
and ``dulmage_mendelsohn`` (why a matching falls short). Plain functions of patterns, tested on
their own; they import nothing from the package outside ``numerics/graphs``.
"""
