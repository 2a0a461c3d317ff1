"""Deprecated (goes in the next release): the example registry is
:mod:`ehatp.experiments.examples`."""

from .._deprecated import moved

moved(__name__, "ehatp.experiments.examples")
