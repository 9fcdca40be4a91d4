"""Code every layer shares: rotations and poses, atomic file writes, the cache folder.

Nothing here imports from mobot_cli but ``mobot_cli.errors``; the import rule is a test
(tests/test_layers.py).
"""
