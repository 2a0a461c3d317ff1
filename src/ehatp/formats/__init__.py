"""Files in and out: the problem TOML, the policy JSON, HDDL, drawings (DOT, SVG, the HTML
explorer), the text of ``ehatp show`` and behaviour trees. Importing this package loads none of
them: each module is imported on its own (docs/architecture.md)."""
