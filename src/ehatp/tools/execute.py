"""Deprecated (goes in the next release): the JSON-lines protocol is :mod:`ehatp.run.execute`, its
command :mod:`ehatp.cli.execute`."""

from .._deprecated import moved, register_from

moved(__name__, "ehatp.run.execute", "ehatp.cli.execute")
register = register_from("ehatp.cli.execute")
