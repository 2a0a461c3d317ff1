"""Deprecated (goes in the next release): the text of ``ehatp show`` is
:mod:`ehatp.formats.text`."""

from .._deprecated import moved

moved(__name__, "ehatp.formats.text")
