"""Deprecated (goes in the next release): random problems are :mod:`ehatp.experiments.randomgen`."""

from .._deprecated import moved

moved(__name__, "ehatp.experiments.randomgen", "ehatp.experiments.agreement")
