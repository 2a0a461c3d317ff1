"""Deprecated (goes in the next release): sweeps are :mod:`ehatp.experiments.sweep`, the command
:mod:`ehatp.cli.sweep`."""

from .._deprecated import moved, register_from

moved(__name__, "ehatp.experiments.sweep", "ehatp.cli.sweep")
register = register_from("ehatp.cli.sweep")
