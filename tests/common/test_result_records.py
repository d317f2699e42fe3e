"""Result records (common/result_records.py): what a bench appends is read back whole, with its
provenance; a file that is not whole is refused with one line naming the file and line, and a
failed write leaves the old file as it was."""
import json

import numpy as np
import pytest

from common import result_records
from common.result_records import RecordError, append_records, changed_code, latest, read_records, recording


@pytest.fixture
def tree(tmp_path, monkeypatch):
    """A repository of its own: one measured source file, a lock, an empty results folder."""
    (tmp_path / "models").mkdir()
    (tmp_path / "models" / "forest.py").write_text("DEPTH = 3\n")
    (tmp_path / "requirements.lock").write_text("numpy==2.4.6 --hash=sha256:00\n")
    monkeypatch.setattr(result_records, "ROOT", tmp_path)
    monkeypatch.setattr(result_records, "RESULTS", tmp_path / "results")
    monkeypatch.setattr(result_records, "LOCK", tmp_path / "requirements.lock")
    return tmp_path


def test_a_record_carries_raw_values_and_its_provenance(tree):
    with recording("forest", measured_code=["models/"], command="python bench/forest.py") as record:
        record.add("scores", {"r2_by_seed": np.array([0.91, 0.88, 0.9]), "nan_seed": float("nan")}, seeds=[0, 1, 2])
    [stored] = read_records(tree / "results" / "forest.jsonl")
    assert stored["values"]["r2_by_seed"] == [0.91, 0.88, 0.9]        # raw per seed, numpy made plain
    assert stored["values"]["nan_seed"] is None                        # JSON holds no NaN
    assert stored["seeds"] == [0, 1, 2] and stored["command"] == "python bench/forest.py"
    assert stored["lock_sha256"] == result_records.file_sha256(tree / "requirements.lock")
    assert set(stored["versions"]) >= {"python", "torch", "numpy", "scikit-learn", "onnxruntime"}
    assert stored["machine"]["cores"] >= 1 and stored["machine"]["cpu"]
    assert stored["load_before"] >= 0 and stored["load_after"] >= 0 and stored["date"].startswith("20")
    assert latest("forest", "scores")["values"] == stored["values"]


def test_records_append_and_the_newest_wins(tree):
    for value in (1, 2):
        with recording("forest", ["models/forest.py"], command="c") as record:
            record.add("scores", {"value": value})
    assert [r["values"]["value"] for r in read_records(tree / "results" / "forest.jsonl")] == [1, 2]
    assert latest("forest", "scores")["values"]["value"] == 2


def test_a_failed_bench_records_nothing(tree):
    with pytest.raises(RuntimeError):
        with recording("forest", ["models/"], command="c") as record:
            record.add("scores", {"value": 1})
            raise RuntimeError("the bench broke half-way")
    assert not (tree / "results" / "forest.jsonl").exists()


def test_changed_measured_code_makes_a_record_stale(tree):
    with recording("forest", ["models/", "models/forest.py"], command="c") as record:
        record.add("scores", {"value": 1})
    stored = latest("forest", "scores")
    assert changed_code(stored) == []
    (tree / "models" / "forest.py").write_text("DEPTH = 4\n")
    assert changed_code(stored) == ["models/", "models/forest.py"]


def test_an_edited_comment_or_docstring_leaves_a_record_current(tree):
    """Only what the code does makes a record stale: git's copy at the record's commit (whose hash
    is the recorded one) is compared with today's without comments and docstrings."""
    import subprocess
    (tree / "configs").mkdir()
    (tree / "configs" / "forest.yaml").write_text("depth: 3  # measured\n")
    (tree / "models" / "forest.py").write_text('"""A forest."""\nDEPTH = 3  # three levels\n')
    git = ["git", "-c", "user.name=t", "-c", "user.email=t@t"]
    for command in (["init", "-q"], ["add", "."], ["commit", "-qm", "measured"]):
        subprocess.run(git + command, cwd=tree, check=True)
    with recording("forest", ["models/", "models/forest.py", "configs/"], command="c") as record:
        record.add("scores", {"value": 1})
    stored = latest("forest", "scores")
    (tree / "models" / "forest.py").write_text('"""A forest of depth three."""\nDEPTH = 3  # see the paper\n')
    (tree / "configs" / "forest.yaml").write_text("# the depth\ndepth: 3\n")
    assert changed_code(stored) == []
    (tree / "configs" / "forest.yaml").write_text("depth: 4\n")
    assert changed_code(stored) == ["configs/"]
    (tree / "models" / "forest.py").write_text('"""A forest."""\nDEPTH = 4\n')
    assert changed_code(stored) == ["models/", "models/forest.py", "configs/"]


@pytest.mark.parametrize("damage, message", [
    (lambda line: line[: len(line) // 2], "forest.jsonl:2: not a whole JSON record"),
    (lambda line: json.dumps({k: v for k, v in json.loads(line).items() if k != "commit"}),
     "forest.jsonl:2: missing field(s) commit"),
    (lambda line: json.dumps({**json.loads(line), "seeds": "0-2"}), "forest.jsonl:2: field 'seeds' should be list"),
])
def test_a_damaged_line_is_refused_with_its_file_and_line(tree, damage, message):
    with recording("forest", ["models/"], command="c") as record:
        record.add("scores", {"value": 1})
        record.add("latency", {"value": 2})
    path = tree / "results" / "forest.jsonl"
    first, second = path.read_text().splitlines()
    path.write_text(first + "\n" + damage(second) + "\n")
    with pytest.raises(RecordError) as refused:
        read_records(path)
    assert message in str(refused.value) and "\n" not in str(refused.value)
    before = path.read_text()
    with pytest.raises(RecordError):           # no writer appends to a file it cannot read
        append_records("forest", [json.loads(first)], tree / "results")
    assert path.read_text() == before


def test_a_record_from_another_lock_is_refused(tree):
    with recording("forest", ["models/"], command="c") as record:
        record.add("scores", {"value": 1})
    (tree / "requirements.lock").write_text("numpy==2.5.0 --hash=sha256:11\n")
    with pytest.raises(RecordError, match="measured under lock .* re-measure"):
        latest("forest", "scores")


def test_a_lock_that_only_adds_packages_keeps_the_records(tree):
    """Every pin of the record's lock (git's copy at its commit) kept, one package added: the
    record stands; a pin moved or dropped: refused."""
    import subprocess
    lock = tree / "requirements.lock"
    lock.write_text("numpy==2.4.6 \\\n    --hash=sha256:00\n    # via -r requirements.txt\n")
    git = ["git", "-c", "user.name=t", "-c", "user.email=t@t"]
    for command in (["init", "-q"], ["add", "."], ["commit", "-qm", "measured"]):
        subprocess.run(git + command, cwd=tree, check=True)
    with recording("forest", ["models/"], command="c") as record:
        record.add("scores", {"value": 1})
    lock.write_text(lock.read_text() + "pyserial==3.5 \\\n    --hash=sha256:22\n")
    assert latest("forest", "scores")["values"] == {"value": 1}
    lock.write_text("numpy==2.4.6 \\\n    --hash=sha256:01\npyserial==3.5 \\\n    --hash=sha256:22\n")
    with pytest.raises(RecordError, match="measured under lock"):
        latest("forest", "scores")


def test_a_missing_record_or_file_is_named(tree):
    with pytest.raises(RecordError, match="no such results file"):
        latest("forest", "scores")
    with recording("forest", ["models/"], command="c") as record:
        record.add("scores", {"value": 1})
    with pytest.raises(RecordError, match="no record named 'latency'"):
        latest("forest", "latency")


def test_a_measured_path_that_does_not_exist_is_refused(tree):
    with pytest.raises(RecordError, match="measured code 'models/missing.py' does not exist"):
        with recording("forest", ["models/missing.py"], command="c"):
            pass
