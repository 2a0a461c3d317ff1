"""Deprecated (goes in the next release): the executor is :mod:`ehatp.run.executor`."""

from .._deprecated import moved

moved(__name__, "ehatp.run.executor")
