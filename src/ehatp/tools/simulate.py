"""Deprecated (goes in the next release): the simulation is :mod:`ehatp.run.simulate`, its command
:mod:`ehatp.cli.simulate`."""

from .._deprecated import moved, register_from

moved(__name__, "ehatp.run.simulate", "ehatp.cli.simulate")
register = register_from("ehatp.cli.simulate")
