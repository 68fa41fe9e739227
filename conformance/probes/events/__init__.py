"""The events family: event indicators in DAE mode and what fmi3UpdateDiscreteStates promises.

``indicators`` (event-indicators-failed, event-indicators-inconsistent) and ``updates``
(event-update-invalid, next-event-time-not-ahead, values-stale-after-event,
states-changed-flag-spurious, on the walk of ``..instruments.event_walk``).

It imports ``..instruments``, ``runtime``, ``model``, ``report`` and ``numerics``; never
another family.
"""
