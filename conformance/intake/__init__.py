"""Opening an FMU and reading its XML without trusting either.

``fmu`` (open_fmu: a .fmu archive or an unpacked folder, into an inventory of members and the
archive findings), ``archive/`` (the zip and folder readers, the inventory, the member scan and
its limits against zip bombs, traversal, symlinks and duplicates), ``xmlsafe`` (XML parsed with
entity expansion, DTDs and network access off; ``xml_encoding`` sniffs the encoding,
``element_path`` names an element) and ``schemas`` (validation against the FMI 3.0 XSDs shipped
with fmpy and our per-draft XSDs; ``schema_loader``, ``schema_messages``).

It imports ``model`` (the drafts, to pick a manifest's schema), ``report`` and ``numerics`` only.
"""
