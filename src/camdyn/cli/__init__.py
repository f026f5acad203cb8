"""The ``camdyn`` command line."""
