"""What every command returns or raises: the exit codes and :class:`UsageError`.

Exit codes: 0 no finding at the ``--fail-on`` severity (default error) or above, 1 at least one
(findings accepted by ``--baseline`` do not count), 2 usage or internal error, 130 interrupted
(Ctrl-C; the reports of the FMUs already checked are written, marked as interrupted).
"""
from __future__ import annotations

EXIT_OK, EXIT_FINDINGS, EXIT_USAGE = 0, 1, 2
EXIT_INTERRUPTED = 130   # 128 + SIGINT, as shells report it


class UsageError(Exception):
    pass
