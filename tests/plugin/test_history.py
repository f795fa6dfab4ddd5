"""History store: what a user sees in the history survives upgrades, restarts and the size cap."""
import json
import sqlite3

import pytest

from octoprint_printwatch.plugin.history import MIGRATIONS, SCHEMA_VERSION, History, migrate


def check(index, layer, verdict="ok", reasons=()):
    return {"index": index, "layer": layer, "z": layer * 0.2, "verdict": verdict, "reasons": list(reasons),
            "shape_error_pct": {"cam0": 3.0}, "cameras": {}}


def test_a_version_1_database_is_migrated_and_keeps_its_prints(tmp_path):
    db = sqlite3.connect(tmp_path / "history.sqlite", isolation_level=None)
    migrate(db, target=1)
    db.execute("INSERT INTO prints (origin, path, name, started, result, checks_planned) "
               "VALUES ('local', 'old.gcode', 'old.gcode', '2026-01-01T00:00:00Z', 'done', 3)")
    db.execute("INSERT INTO checks (print_id, idx, layer, z, verdict, data) VALUES (1, 0, 30, 6.0, 'ok', ?)",
               (json.dumps(check(0, 30)),))
    db.close()

    history = History(tmp_path)
    assert history.migrated_from == 1
    version = history._db.execute("PRAGMA user_version").fetchone()[0]
    assert version == SCHEMA_VERSION == len(MIGRATIONS)
    detail = history.get_print(1)
    assert detail["file"]["name"] == "old.gcode"
    assert [c["layer"] for c in detail["checks"]] == [30]
    assert detail["planned_checks"] == []  # column added by migration 2 with its default


def test_a_database_from_a_newer_plugin_is_refused_with_a_clear_message(tmp_path):
    db = sqlite3.connect(tmp_path / "history.sqlite", isolation_level=None)
    db.execute(f"PRAGMA user_version = {SCHEMA_VERSION + 5}")
    db.close()
    with pytest.raises(RuntimeError, match="newer than this plugin"):
        History(tmp_path)


def test_a_restart_mid_print_keeps_the_checks_and_marks_the_print_interrupted(tmp_path):
    history = History(tmp_path)
    print_id = history.start_print("local", "a.gcode", "a.gcode", [{"layer": 10, "z": 2.0}, {"layer": 20, "z": 4.0}], {})
    history.add_check(print_id, check(0, 10))
    history.close()  # OctoPrint goes away without ending the print

    reopened = History(tmp_path)
    assert reopened.close_interrupted() == [print_id]
    detail = reopened.get_print(print_id)
    assert detail["result"] == "interrupted"
    assert detail["ended"] is not None
    assert [c["layer"] for c in detail["checks"]] == [10]
    assert detail["checks_planned"] == 2


def test_the_first_failure_and_its_reason_are_kept_on_the_print(tmp_path):
    history = History(tmp_path)
    print_id = history.start_print("local", "a.gcode", "a.gcode", [], {})
    history.add_check(print_id, check(0, 20))
    history.add_check(print_id, check(1, 40, "fail", ["cam0: shape error 14.0 % > 7.0 %"]))
    history.add_check(print_id, check(2, 60, "fail", ["later"]))
    row = history.list_prints()[0][0]
    assert row["first_failure_layer"] == 40
    assert row["failure_reason"] == "cam0: shape error 14.0 % > 7.0 %"
    assert row["checks_done"] == 3


def test_size_cap_removes_the_oldest_recordings_but_never_the_running_print(tmp_path):
    history = History(tmp_path)
    ids = [history.start_print("local", f"{i}.gcode", f"{i}.gcode", [], {}) for i in range(4)]
    for print_id in ids:
        folder = history.recording_dir(print_id)
        folder.mkdir(parents=True)
        (folder / "session.json").write_text("{}")
        (folder / "frame.jpg").write_bytes(b"x" * 100_000)
    for print_id in ids[:3]:
        history.end_print(print_id, "done")
    # room for two recordings; the running one (the last) must stay even though it counts
    removed = history.enforce_limits(max_bytes=210_000, keep_prints=100, running=ids[3])
    assert removed == [ids[0], ids[1]]
    remaining = {p["id"]: p["recording"]["available"] for p in history.list_prints()[0]}
    assert remaining == {ids[0]: False, ids[1]: False, ids[2]: True, ids[3]: True}


def test_only_the_newest_prints_are_kept(tmp_path):
    history = History(tmp_path)
    ids = [history.start_print("local", f"{i}.gcode", f"{i}.gcode", [], {}) for i in range(5)]
    history.enforce_limits(max_bytes=10**9, keep_prints=2)
    prints, total = history.list_prints()
    assert total == 2
    assert [p["id"] for p in prints] == [ids[4], ids[3]]
    assert history.get_print(ids[0]) is None
