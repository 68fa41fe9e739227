"""The names of causes (``Violation.cause``): one spelling for every check that can see one.

Two violations that name one key are one defect (``conformance.run.causes`` folds them):

* :func:`through` -- a variable whose value or partial derivatives are wrong, or that the FMU
  does not take or give: every derivative entry names its unknown and its known, so that what a
  wrong formula or a wrong partial derivative spoils is one finding, and so does a variable the
  FMU does not let an importer set or read;
* :func:`failing` -- the FMU fails to evaluate in one state of one mode: the call that stops
  its run, and the reads refused there, are one defect;
* :data:`STALE` -- values read after a setter moved the point are the previous point's;
* :data:`FAULT` -- one fault of the FMU's that several modes, instants or probes show alike (a
  nominal it gives wrong, a flag it sets wrongly, a call it refuses, a limit it exhausts).
"""
from __future__ import annotations


#: The cause 'the FMU does not bring its evaluation to the point an importer set' (one cache
#: of the FMU's, whatever group of variables or mode shows it).
STALE = "evaluation not brought to the new point"


def through(name: str) -> str:
    """The cause 'the values or partial derivatives through variable ``name``'."""
    return f"through '{name}'"


def entry(unknown: str, known: str) -> tuple[str, str]:
    """The cause of a derivative entry d(unknown)/d(known): its unknown and its known."""
    return through(unknown), through(known)


def failing(state: str, mode: str) -> str:
    """The cause 'the FMU fails to evaluate in ``state``, ``mode``' (e.g. 'Initialization
    Mode', 'ODE mode')."""
    return f"evaluation fails in {state}, {mode}"


#: The cause 'the FMU does what the text rules out', whichever mode, instant or probe shows it
#: (one code path of the binary, one finding): ``FAULT.format("refuses a stop time")``.
FAULT = "the FMU {}"

#: The cause 'a defined nextEventTime at or before the time it is announced at', whether the
#: walk of fixed event instants or a simulation's run meets it.
NEXT_EVENT_NOT_AHEAD = FAULT.format("announces a nextEventTime that is not ahead")
