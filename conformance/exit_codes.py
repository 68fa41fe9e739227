"""What every command returns or raises: the exit codes and :class:`UsageError`.

Exit codes: 0 no finding at the ``--fail-on`` severity (default error) or above, 1 at least one
(findings accepted by ``--baseline`` do not count), 2 usage or internal error.
"""
from __future__ import annotations

EXIT_OK, EXIT_FINDINGS, EXIT_USAGE = 0, 1, 2


class UsageError(Exception):
    pass
