"""Defect variants for the simulation probes (DAE801-DAE805).

Each entry must trigger exactly its rule (plus ``also``); see tests/probes/test_defects.py. The
simulation runs to the stop time (DefaultExperiment, else start + 1): these scenes stop at 1.

The ``DEFECT_LATE_*`` hooks are framework-level (tests/scenes/common/fmi3_framework.c) and switch
on only for t > 0.5, where the trajectory goes and the sampled points of the point probes (near
t = 0: for seed 0 all below t = 0.1) do not: these are the faults only a simulation
finds. The other two are scenes of their own: the Van der Pol oscillator in its DAE limit, whose
dg/dw vanishes at t* = 1.5 - ln 2, and Akzo Nobel without its CO2 feed, which drives a state
below zero where sqrt() is undefined and the FMU returns fmi3Discard.
"""
from __future__ import annotations

from tests.probes.variants import Defect

DEFECTS: list[Defect] = [
    Defect("DAE801", "HelloWorldDAE", defines=("DEFECT_LATE_JUMP",),
           note="g1 jumps by 1 at t = 0.5 without an event indicator: IDA stalls there"),
    Defect("DAE802", "VanDerPolDAE",
           note="dg/dy2 = 1 - y1^2 reaches 0 at t* = 1.5 - ln 2 = 0.806853 (impasse point); "
                "the run stops there with the time instead of crawling on"),
    Defect("DAE803", "Akzo", defines=("AKZO_NO_CO2_FEED",),
           note="y2 is used up near t = 0.184 and driven below 0: fmi3Discard at every step "
                "IDA tries; the solver stalls on them"),
    Defect("DAE804", "HelloWorldDAE", defines=("DEFECT_LATE_FAST",),
           note="der(x) gains 1e5*cos(1e5*t) from t = 0.5: 20000 steps end near t = 0.53"),
    Defect("DAE805", "HelloWorldDAE", defines=("DEFECT_LATE_ODE_DRIFT",),
           note="from t = 0.5 ODE mode solves g = 0.05: the states drift apart, by the same "
                "amount at 100 and 10000 times tighter tolerances"),
]
