"""Deprecated (goes in the next release): behaviour trees are :mod:`ehatp.formats.bt`, the command
:mod:`ehatp.cli.export`."""

from .._deprecated import moved, register_from

moved(__name__, "ehatp.formats.bt", "ehatp.cli.export")
register = register_from("ehatp.cli.export")
