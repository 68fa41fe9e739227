"""Simulation of an fmi-ls-dae FMU: DAE mode with IDA, ODE mode with CVODE, and the comparison.

The pieces, each usable on its own (the integrators also take pure-Python systems, which is how
the tests exercise them without a binary):

    settings.py   Settings (tolerances, horizon, output times, budgets) and the Trajectory result
    limits.py     our own limits (steps, wall clock, stalls, dg/dw condition) and the step loop
    system.py     the FMU as a DAE residual or an ODE right-hand side, with coloured Jacobians
    dae.py        consistent initialisation and IDA in DAE mode
    ode.py        CVODE in ODE mode
    compare.py    DAE against ODE trajectories at common output times
    output.py     the CSV file
    run.py        simulate one FMU from the parent process, through the probe worker
    cli.py        ``lsdae simulate``

The binary is only ever loaded in the probe worker process: ``lsdae check`` runs the simulation
as probes (``conformance/probes/simulation.py``), and ``lsdae simulate`` runs the same probes
with its own settings and reads the trajectory back from the report. Nothing here imports numpy
or SUNDIALS at package import, so the command line stays quick to start.
"""
