"""The README's first lines: the install-and-run and the test commands, each a whole line that works
on a fresh Debian 12 / Ubuntu 24.04 (in a virtual environment), and CI runs exactly the second.

Every other example of the README and the docs runs in tests/test_docs.py."""

from __future__ import annotations

import re
import shlex
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
README = (REPO / "README.md").read_text()
VENV = "python3 -m venv .venv && . .venv/bin/activate && "


def first_block() -> list[str]:
    return re.search(r"```bash\n(.*?)```", README, re.S).group(1).splitlines()


def test_first_lines_are_the_install_and_run_and_the_test_commands():
    assert first_block() == [
        VENV + "pip install -e . && mobot run scenarios/quickstart.yaml",
        VENV + 'pip install -e ".[test]" && python -m pytest -q',
    ]
    assert README.index("```bash") < README.index("\n## "), "the two commands come first"


def test_ci_runs_exactly_the_readme_test_command_and_fails_when_it_fails():
    ci = (REPO / ".ci" / "run").read_text()
    line = first_block()[1]
    ran = [text for text in ci.splitlines() if line in text]
    assert len(ran) == 1, ".ci/run must run exactly the README's test command"
    # set -e does not stop a script for a failure inside an && list: a failed install or a pytest
    # exit code (1, or 5 when no test was collected) must end CI with that code.
    assert ran[0].startswith(line) and ran[0][len(line):].strip() == "|| exit $?"
    assert "set -euo pipefail" in ci
    assert "mkdocs build --strict" in ci and 'pip install -e ".[docs]"' in ci


def test_the_commands_are_whole_shell_lines_that_name_real_files():
    for line in first_block():
        words = shlex.split(line)
        assert words[:4] == ["python3", "-m", "venv", ".venv"]  # a fresh system's pip refuses otherwise
    assert (REPO / "scenarios" / "quickstart.yaml").is_file()
    pyproject = (REPO / "pyproject.toml").read_text()
    assert re.search(r'^test = \[.*"pytest', pyproject, re.M)
    assert re.search(r'^docs = \[.*mkdocs-material', pyproject, re.M)
    ignored = (REPO / ".gitignore").read_text().split()
    assert ".venv/" in ignored and "/site/" in ignored


def test_the_corpus_is_explained_under_the_commands():
    head = README[:README.index("\n## ")]
    assert "MOBOT_CORPUS" in head and "../shared/corpus" in head and "skip" in head
    conftest = (REPO / "tests" / "conftest.py").read_text()
    assert 'os.environ.get("MOBOT_CORPUS"' in conftest
