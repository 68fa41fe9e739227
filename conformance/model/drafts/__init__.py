"""fmi-ls-dae manifest drafts: recognition in :mod:`.detect`, migration hints in :mod:`.migrate`."""
