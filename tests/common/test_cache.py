"""The cache folder and the JSON document cache: where it lives, keys, and that it never fails a run."""

from __future__ import annotations

from mobot_cli.common import cache
from mobot_cli.common.cache import cache_dir


def test_cache_dir_precedence(monkeypatch, tmp_path):
    monkeypatch.setenv("MOBOT_CACHE_DIR", str(tmp_path / "explicit"))
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    assert cache_dir() == tmp_path / "explicit"
    monkeypatch.delenv("MOBOT_CACHE_DIR")
    assert cache_dir() == tmp_path / "xdg" / "mobot"
    monkeypatch.delenv("XDG_CACHE_HOME")
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    assert cache_dir() == tmp_path / "home" / ".cache" / "mobot"


def test_documents_round_trip_and_a_broken_entry_is_a_miss(monkeypatch, tmp_path):
    monkeypatch.setenv("MOBOT_CACHE_DIR", str(tmp_path))
    key = cache.digest("kind", "text", b"bytes")
    assert cache.load("kind", key) is None
    cache.store("kind", key, {"a": [1, 2.5, None]})
    assert cache.load("kind", key) == {"a": [1, 2.5, None]}
    assert sorted(p.name for p in (tmp_path / "kind").iterdir()) == [f"{key}.json"]  # no temporaries
    (tmp_path / "kind" / f"{key}.json").write_text("{half", encoding="utf-8")
    assert cache.load("kind", key) is None


def test_keys_separate_their_parts_and_a_read_only_cache_costs_nothing(monkeypatch, tmp_path):
    assert cache.digest("ab", "c") != cache.digest("a", "bc")
    (tmp_path / "file").write_text("", encoding="utf-8")
    monkeypatch.setenv("MOBOT_CACHE_DIR", str(tmp_path / "file"))  # a file where the folder should be
    cache.store("kind", "key", {"a": 1})
    assert cache.load("kind", "key") is None


def test_keys_change_with_the_code_that_builds_documents_only(monkeypatch, tmp_path):
    for name in ("__init__.py", "common/cache.py", "assets/world/build.py", "plan.py", "cli/run.py"):
        (tmp_path / name).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / name).write_text("# v1\n", encoding="utf-8")
    monkeypatch.setattr(cache, "_PACKAGE", tmp_path)

    def key() -> str:
        cache._code_version.cache_clear()
        return cache.digest("world", "same input")

    try:
        first = key()
        (tmp_path / "cli" / "run.py").write_text("# v2\n", encoding="utf-8")
        assert key() == first  # the CLI builds no cached document
        (tmp_path / "assets" / "world" / "build.py").write_text("# v2\n", encoding="utf-8")
        assert key() != first  # a module in a subfolder of assets does
    finally:
        monkeypatch.undo()
        cache._code_version.cache_clear()
