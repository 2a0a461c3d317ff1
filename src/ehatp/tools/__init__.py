"""Deprecated: the old home of the command line, the formats, execution and experiments, kept for
one release. Each module here warns and stands for its new home (:mod:`ehatp._deprecated`):
``ehatp.formats``, ``ehatp.run``, ``ehatp.experiments`` and ``ehatp.cli``."""
