"""Deprecated: the policy format is :mod:`ehatp.formats.policy` (this path goes in the next
release)."""

from typing import TYPE_CHECKING

from ._deprecated import moved

if TYPE_CHECKING:
    from .formats.policy import *  # noqa: F403

moved(__name__, "ehatp.formats.policy")
