"""Deprecated (goes in the next release): the py_trees behaviours are
:mod:`ehatp.formats.bt_py_trees`."""

from .._deprecated import moved

moved(__name__, "ehatp.formats.bt_py_trees")
