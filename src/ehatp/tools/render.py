"""Deprecated (goes in the next release): the renderer is :mod:`ehatp.formats.render`, its command
:mod:`ehatp.cli.render`."""

from .._deprecated import moved, register_from

moved(__name__, "ehatp.formats.render", "ehatp.cli.render")
register = register_from("ehatp.cli.render")
