"""The one place pybullet is imported: its C module writes a build-time banner to stderr on
import, which would land in front of every error message and in scripts' logs."""

from __future__ import annotations

import importlib

from mobot_cli.common.streams import silenced

with silenced(2):
    p = importlib.import_module("pybullet")
