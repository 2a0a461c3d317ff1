"""The paper's domains (``cubes``, ``cooking``), and how a domain of your own is declared so that
problem files may name it: :func:`register` from Python, or an entry point of group
``ehatp.domains`` in your package (see :mod:`ehatp.model.registry` and docs/security.md)."""

from ..model.registry import GROUP, declared, register, unregister

__all__ = ["GROUP", "declared", "register", "unregister"]
