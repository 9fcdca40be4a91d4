"""The atomic writer: exact JSON format, whole files or none, no temporaries left, normal permissions."""

from __future__ import annotations

import math
import os
import stat
from pathlib import Path

import pytest

from mobot_cli.common.files import write_bytes_atomic, write_json_atomic, write_text_atomic


def test_json_format_is_what_run_folders_hold(tmp_path):
    path = tmp_path / "summary.json"
    write_json_atomic(path, {"b": 1.5, "a": [1, None], "where": Path("/x/y"), "ok": True})
    assert path.read_bytes() == (b'{\n  "b": 1.5,\n  "a": [\n    1,\n    null\n  ],\n'
                                 b'  "where": "/x/y",\n  "ok": true\n}\n')


def test_a_failed_write_keeps_the_old_file_and_leaves_no_temporary(tmp_path):
    path = tmp_path / "summary.json"
    write_text_atomic(path, "old\n")
    with pytest.raises(ValueError):
        write_json_atomic(path, {"x": math.nan})  # NaN is not JSON: refused before anything is written
    with pytest.raises(TypeError):
        write_bytes_atomic(path, "not bytes")  # type: ignore[arg-type]  # fails while writing
    assert path.read_text() == "old\n"
    assert os.listdir(tmp_path) == ["summary.json"]


def test_text_is_utf8_with_newlines_as_given_and_replaces_the_file(tmp_path):
    path = tmp_path / "a.csv"
    write_bytes_atomic(path, b"first")
    write_text_atomic(path, "t,x\r\n0,é\n")
    assert path.read_bytes() == "t,x\r\n0,é\n".encode("utf-8")
    assert os.listdir(tmp_path) == ["a.csv"]


def test_permissions_follow_the_umask_like_a_plain_open(tmp_path):
    old = os.umask(0o022)
    try:
        write_text_atomic(tmp_path / "written", "x")
        (tmp_path / "plain").write_text("x")
    finally:
        os.umask(old)
    mode = stat.S_IMODE((tmp_path / "written").stat().st_mode)
    assert mode == stat.S_IMODE((tmp_path / "plain").stat().st_mode) == 0o644
