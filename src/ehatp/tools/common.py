"""Deprecated (goes in the next release): what commands share is :mod:`ehatp.cli.common`; reading a
policy file checked, :mod:`ehatp.formats.policy_check`."""

from .._deprecated import moved

moved(__name__, "ehatp.cli.common", "ehatp.formats.policy_check")
