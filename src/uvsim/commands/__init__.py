"""Sub-commands of the ``uvsim`` CLI (one module each, see :mod:`uvsim.cli`)."""
