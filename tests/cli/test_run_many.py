"""`mobot run a.yaml b.yaml ...`: the files run one after another in one process, each into its
own run folder; a bad file is reported and the next one runs; the exit code is the worst."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from PIL import Image

from mobot_cli.cli import invoke
from mobot_cli.record.folder import is_run_folder

RUN = "version: 1\nname: {name}\nduration: 0.5\nrobots:\n  - name: mobot\n"
FAILS = RUN + "expect:\n  - {{robot: mobot, distance: {{min: 1.0}}}}\n"  # it stands still


@pytest.fixture
def files(tmp_path) -> dict[str, Path]:
    made = {}
    for stem, text in (("ok", RUN), ("fails", FAILS), ("other", RUN)):
        made[stem] = tmp_path / f"{stem}.yaml"
        made[stem].write_text(text.format(name=f"{stem}_run"))
    made["bad"] = tmp_path / "bad.yaml"
    made["bad"].write_text("version: 1\nrobots: []\n")  # no duration
    return made


def complete(folder: Path) -> bool:
    return is_run_folder(folder) and (folder / "trajectory.png").is_file() and \
        json.loads((folder / "summary.json").read_text())["status"] == "ok"


def test_each_file_gets_its_folder_under_out_and_an_expectation_failure_exits_1(files, tmp_path):
    out = tmp_path / "out"
    code, stdout, stderr = invoke(["run", files["ok"], files["fails"], "--out", out, "--quiet"]).__dict__.values()
    assert code == 1 and stdout == ""
    assert sorted(p.name for p in out.iterdir()) == ["fails", "ok"]
    assert complete(out / "ok") and complete(out / "fails")
    assert "mobot: expectation failed: robot 'mobot'" in stderr


def test_a_bad_file_is_reported_in_one_line_and_the_batch_goes_on(files, tmp_path):
    out = tmp_path / "out"
    done = invoke(["run", files["bad"], files["ok"], files["fails"], "--out", out, "--quiet"])
    assert done.exit_code == 2  # bad input outranks a failed expectation
    assert done.stderr.splitlines()[0] == f"mobot: error: {files['bad']}:1, key 'duration': 'duration' is required"
    assert complete(out / "ok") and complete(out / "fails") and not (out / "bad").exists()


def test_one_ok_and_one_bad_file_exit_2_and_the_ok_folder_is_complete(files, tmp_path):
    out = tmp_path / "out"
    done = invoke(["run", files["ok"], files["bad"], "--out", out, "--quiet"])
    assert (done.exit_code, done.stdout) == (2, "")
    assert done.stderr.count("mobot: error:") == 1
    assert complete(out / "ok") and not (out / "bad").exists()


def test_all_ok_exits_0_and_prints_a_table_for_each(files, tmp_path):
    done = invoke(["run", files["ok"], files["other"], "--out", tmp_path / "out"])
    assert done.exit_code == 0
    assert done.stdout.count("run folder: ") == 2
    assert "ok_run: 0.5 s simulated" in done.stdout and "other_run: 0.5 s simulated" in done.stdout


def test_two_files_with_the_same_stem_are_refused_before_any_run(files, tmp_path):
    twin = tmp_path / "elsewhere" / "ok.yaml"
    twin.parent.mkdir()
    twin.write_text(RUN.format(name="twin"))
    out = tmp_path / "out"
    done = invoke(["run", files["ok"], twin, "--out", out])
    assert (done.exit_code, done.stdout) == (2, "")
    assert done.stderr.startswith(f"mobot: error: '{files['ok']}' and '{twin}' would both write {out / 'ok'}")
    assert not out.exists()


def test_without_out_each_run_gets_its_default_folder(files, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert invoke(["run", files["ok"], files["other"], "--quiet"]).exit_code == 0
    folders = sorted((tmp_path / "runs").iterdir())
    assert [f.name.rsplit("-", 2)[0] for f in folders] == ["ok_run", "other_run"]
    assert all(complete(f) for f in folders)


def test_json_with_several_files_prints_one_summary_a_line(files, tmp_path):
    done = invoke(["run", files["ok"], files["bad"], files["fails"], "--out", tmp_path / "out", "--json"])
    assert done.exit_code == 2
    lines = done.stdout.splitlines()
    assert [json.loads(line)["scenario"] for line in lines] == ["ok_run", "fails_run"]  # the bad file: none
    assert json.loads(lines[0]) == json.loads((tmp_path / "out" / "ok" / "summary.json").read_text())


def test_json_with_one_file_is_the_indented_document_as_before(files, tmp_path):
    done = invoke(["run", files["ok"], "--out", tmp_path / "one", "--json"])
    assert done.exit_code == 0 and done.stdout.startswith("{\n  ")
    assert json.loads(done.stdout) == json.loads((tmp_path / "one" / "summary.json").read_text())


def test_view_watches_one_run_only(files, tmp_path):
    done = invoke(["run", files["ok"], files["other"], "--view", "--out", tmp_path / "out"])
    assert (done.exit_code, done.stdout) == (2, "")
    assert "--view watches one run" in done.stderr and not (tmp_path / "out").exists()


def test_a_batch_writes_the_same_folders_as_one_run_each(tmp_path):
    """Nothing of one run carries over into the next in the same process."""
    repo = Path(__file__).resolve().parents[2]
    names = ["quickstart", "events", "square"]
    paths = [repo / "scenarios" / f"{name}.yaml" for name in names]
    assert invoke(["run", *paths, "--out", tmp_path / "batch", "--quiet", "--duration", "2"]).exit_code == 0
    for name, path in zip(names, paths):
        assert invoke(["run", path, "--out", tmp_path / "one" / name, "--quiet", "--duration", "2"]).exit_code == 0
        batch, one = tmp_path / "batch" / name, tmp_path / "one" / name
        files = sorted(p.relative_to(one) for p in one.rglob("*") if p.is_file())
        assert files == sorted(p.relative_to(batch) for p in batch.rglob("*") if p.is_file())
        for rel in files:
            if rel.name == "summary.json":
                timing = ("wall_time", "real_time_factor", "started", "finished")
                strip = lambda f: {k: v for k, v in json.loads(f.read_text()).items() if k not in timing}  # noqa: E731
                assert strip(batch / rel) == strip(one / rel), (name, rel)
            elif rel.suffix == ".png":
                assert Image.open(batch / rel).tobytes() == Image.open(one / rel).tobytes(), (name, rel)
            else:
                assert (batch / rel).read_bytes() == (one / rel).read_bytes(), (name, rel)
