"""What the probe families measure with, and the contract they are written against.

``api`` (the contract: a probe, its context, the facts one family leaves for another),
``common`` (instances, the layout, locations), ``sampling`` (the seeded points),
``instantiation`` (what a fresh instance holds), ``jacobian_layout`` (the rows, columns and
promises of a mode: DAE mode the manifest's, ODE mode modelDescription's), ``jacobian`` (the
survey of one mode's Jacobian), ``entry_comparison`` (the FMU's entries against finite
differences), ``event_walk`` (one walk through Event Mode per mode) and ``independence`` (the
survey behind instances-not-independent, the first cause). None of them registers a probe.

It imports ``runtime``, ``model``, ``report``, ``numerics`` and ``simulate``; never a family
and never the machinery.
"""
