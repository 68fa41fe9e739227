"""Defect variants for the basic probes and the isolation rules (crash, hang, memory, NaN...).

Each entry must trigger exactly its rule (plus ``also``); see tests/probes/test_defects.py.
The C side is in tests/scenes/common/fmi3_framework.c (framework-level defects, listed at its
top), tests/scenes/Robertson/model.c and tests/scenes/HelloWorldDAE/model.c.
"""
from __future__ import annotations

from tests.probes.variants import Defect

DEFECTS: list[Defect] = [
    # isolation: the runner turns these into findings and goes on
    Defect("DAE701", "HelloWorldDAE", defines=("DEFECT_SEGFAULT_GETFLOAT64",),
           note="segfault in fmi3GetFloat64 of a residual, in Continuous-Time Mode"),
    Defect("DAE701", "Robertson", defines=("DEFECT_EXIT_IN_CALL",),
           note="fmi3SetTime calls exit() once time has advanced"),
    Defect("DAE702", "SimpleDAE", defines=("DEFECT_HANG_DIRECTIONAL",),
           note="fmi3GetDirectionalDerivative never returns (the per-probe limit, 20 s)"),
    Defect("DAE703", "HelloWorldDAE", defines=("DEFECT_MEMORY_BLOWUP",),
           note="fmi3GetContinuousStateDerivatives allocates until malloc fails, then aborts"),
    Defect("DAE704", "Robertson", defines=("DEFECT_MISSING_EXPORT",),
           note="fmi3GetClock is not exported"),
    # the enable handshake and DAE-mode initialisation
    Defect("DAE710", "SimpleDAE", defines=("DEFECT_NO_RECONFIGURATION",),
           note="a tunable switch, but Reconfiguration Mode is refused"),
    Defect("DAE710", "HelloWorldDAE", defines=("DEFECT_ODE_DERIVATIVES_FAIL",),
           note="with the switch false, fmi3GetContinuousStateDerivatives fails"),
    Defect("DAE711", "HelloWorldDAE", defines=("DEFECT_DAE_INIT_REFUSED",),
           note="fmi3ExitInitializationMode refuses DAE mode (info; fixed switch: DAE probes "
                "skipped)"),
    # DAE-mode evaluation
    Defect("DAE720", "Robertson", defines=("DEFECT_W_NOT_SETTABLE",),
           note="the algebraic variable cannot be set in Continuous-Time Mode"),
    Defect("DAE721", "HelloWorldDAE", defines=("DEFECT_INCONSISTENT_INIT",),
           note="the solved algebraic variables are reset to their guess after initialisation"),
    Defect("DAE722", "Robertson", defines=("DEFECT_HIDDEN_STATE",),
           note="the residual depends on the history of evaluated points"),
    Defect("DAE723", "HelloWorldDAE", defines=("DEFECT_NAN_DERIVATIVE",),
           note="der(x) is NaN once time has advanced"),
    Defect("DAE724", "Robertson", defines=("DEFECT_EVAL_ERROR_AFTER_START",),
           note="reading the residual fails in DAE mode once time has advanced"),
]
