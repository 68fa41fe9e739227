"""Simulation of an fmi-ls-dae FMU instance: DAE mode with IDA, ODE mode with CVODE.

    integrate.py  simulate_instance: one run of an instance in its mode (the public function)
    system.py     the FMU as a DAE residual or an ODE right-hand side, with coloured Jacobians,
                  event indicators and the event calls
    jacobian_check.py  whether the run may use the FMU's directional derivatives (confirmed)
    output.py     the CSV file of a trajectory

The integrators, their settings and limits, and the comparison of two runs are plain numerics
(``conformance.numerics``: settings, limits, events, dae, ode, compare), tested without a
binary. The
simulation probes (``conformance.probes.simulation.verdicts``) call
:func:`~conformance.simulate.integrate.simulate_instance` inside the worker process; the
``lsdae simulate`` command (``conformance.commands.simulate``) runs those probes through the
engine and reads the trajectories back from the report. Nothing is imported at package import,
so the command line stays quick to start.

It imports ``runtime``, ``model``, ``report`` and ``numerics``; never ``probes`` or above.
"""
