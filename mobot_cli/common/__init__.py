"""Shared code at the bottom of the package: maths and file helpers every layer may use."""
