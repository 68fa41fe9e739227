"""``lsdae fix``: repairs derived exactly from the files, as minimal byte edits.

:mod:`.edits` applies byte-range edits to the original XML (never a re-serialisation),
:mod:`.xmltext` finds start tags and attributes in the bytes, :mod:`.fixers` turns findings into
changes, one fixer per concern, and :mod:`.archive` writes the result: every other member of a
zip copied raw (same order, names, compression and bytes), an unpacked folder changed only in the
files fixed. :mod:`.apply` runs the fixers one at a time and keeps a change only when the re-check
shows it fixed what it claimed and made nothing worse.

The re-check is passed in from above (``commands.fix``). It imports ``intake``, ``model`` (the
drafts' migration), ``report`` and ``numerics``; never ``run`` or ``commands``.
"""
