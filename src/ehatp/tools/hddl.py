"""Deprecated (goes in the next release): the HDDL import is :mod:`ehatp.formats.hddl` (its sidecar
:mod:`ehatp.formats.hddl_sidecar`), the report :mod:`ehatp.experiments.hddl_report`, the command
:mod:`ehatp.cli.import_hddl`."""

from .._deprecated import moved, register_from

moved(__name__,
      "ehatp.formats.hddl",
      "ehatp.formats.hddl_sidecar",
      "ehatp.experiments.hddl_report",
      "ehatp.cli.import_hddl")
register = register_from("ehatp.cli.import_hddl")
