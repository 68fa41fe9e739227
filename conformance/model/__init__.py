"""The parsed FMU: modelDescription.xml and the fmi-ls-dae manifest as frozen objects.

``description`` (ModelDescription: variables, types, units, ModelStructure; ``parts`` holds its
pieces), ``manifest`` (the fmi-ls-dae manifest), ``unknowns`` (ModelStructure elements read in one
loop), ``attributes``, ``definitions``, ``structured_names`` (the FMI 3.0 name grammar), ``layer``
(whether an FMU declares the fmi-ls-dae layer) and ``drafts/`` (every manifest shape found in the
wild: names, detection, migration to 1.0.0-alpha.1).

It reads trees that ``intake`` parsed; it imports only ``report`` (the findings vocabulary) and
``numerics`` below it.
"""
