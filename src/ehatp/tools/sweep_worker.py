"""Deprecated (goes in the next release): a sweep's worker is
:mod:`ehatp.experiments.sweep_worker`."""

from .._deprecated import moved

moved(__name__, "ehatp.experiments.sweep_worker")
