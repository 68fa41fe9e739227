"""The mutation campaign: how much of what goes wrong in FMU code lsdae sees (issue 20).

universalmutator mutates the C code of the scenes (each ``model.c``, ``FourBar/fourbar.h`` and
the mode, event, derivative, get/set and reset functions of ``scenes/common/fmi3_framework.c``),
one line per mutant. Each sampled mutant is built with ``scenes.build.build_scene(...,
overrides=...)`` (a mutant that does not compile is *stillborn*), observed with fmpy alone at fixed
points in ODE and DAE mode (a mutant observed exactly like the original is *equivalent*), and
checked with ``lsdae check``: *killed* when the report has an error or warning (rule, subject)
that the original's has not, else *survived*. Every survivor carries a recorded verdict
(``verdicts.toml``: consistent-model-change, missed-defect or undetectable) backed by
independent evidence (``promises.py``). ``python -m bench.mutation`` runs it; ``make mutation``
writes ``reports/mutation/``; ``docs/mutation.md`` explains it.

Floors, bottom up: ``fmu_view`` (the scene's XML and an fmpy session), ``oracle`` and
``promises`` with its helpers ``promise_jacobian`` and ``promise_calls`` (fmpy only; the oracle
and the promises are also subprocess entry points), ``targets`` and ``generate``
(what is mutated), ``checking`` (lsdae runs and the kill criterion), ``verdicts``, ``campaign``,
``sweep``, ``report``, ``cli``. Nothing in ``conformance/`` imports this package.
"""
