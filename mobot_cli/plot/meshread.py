"""Kept for importers of the old name: the reader lives in ``mobot_cli.common.meshfile``."""

from mobot_cli.common.meshfile import read_mesh

__all__ = ["read_mesh"]
