"""Deprecated (goes in the next release): the benchmarks are :mod:`ehatp.experiments.bench`."""

from .._deprecated import moved

moved(__name__, "ehatp.experiments.bench")
