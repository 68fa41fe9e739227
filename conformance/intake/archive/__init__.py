"""The FMU archive: a zip file or an unpacked folder read as one inventory of members.

``base`` (members, limits and the archive findings), ``zipped`` and ``folder`` (the two readers),
``inventory`` (names, sizes, duplicates), ``scan`` (one pass over the members), ``source`` (the
bytes of a member on demand). Imports only ``report`` outside ``intake``.
"""
