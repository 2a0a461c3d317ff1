"""Deprecated (goes in the next release): the walk of every branch is :mod:`ehatp.run.walk`."""

from .._deprecated import moved

moved(__name__, "ehatp.run.walk")
