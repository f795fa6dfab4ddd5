"""Print and check history: SQLite with a versioned schema, recordings on disk with a size cap.

One row per print, one per check (its full JSON as the API shows it). The
schema version lives in SQLite's ``user_version``; :data:`MIGRATIONS` take any
older database to the current one in a transaction, so a plugin update keeps
the history. Every write commits at once: an OctoPrint restart mid-print keeps
the checks so far, and :meth:`History.close_interrupted` marks that print
``interrupted`` on the next start.

Recordings (``docs/recording-format.md``) live in ``<data>/recordings/<print id>/``
and are written by the core's :class:`~octoprint_printwatch.core.recording.RecordingWriter`;
:meth:`History.enforce_limits` removes the oldest when their total passes the cap.
No OctoPrint import: unit-tested on its own.
"""
from __future__ import annotations

import json
import shutil
import sqlite3
import threading
import time
from pathlib import Path
from typing import Iterable

#: Each entry takes the schema from version i to i + 1.
MIGRATIONS: list[list[str]] = [
    # 0 -> 1: prints and checks
    [
        """CREATE TABLE prints (
            id INTEGER PRIMARY KEY AUTOINCREMENT,
            origin TEXT NOT NULL,
            path TEXT NOT NULL,
            name TEXT NOT NULL,
            started TEXT NOT NULL,
            ended TEXT,
            result TEXT NOT NULL DEFAULT 'running',
            checks_planned INTEGER NOT NULL DEFAULT 0,
            first_failure_layer INTEGER,
            failure_reason TEXT
        )""",
        """CREATE TABLE checks (
            id INTEGER PRIMARY KEY AUTOINCREMENT,
            print_id INTEGER NOT NULL REFERENCES prints(id) ON DELETE CASCADE,
            idx INTEGER NOT NULL,
            layer INTEGER NOT NULL,
            z REAL NOT NULL,
            verdict TEXT NOT NULL,
            data TEXT NOT NULL
        )""",
        "CREATE UNIQUE INDEX checks_by_print ON checks(print_id, idx)",
    ],
    # 1 -> 2: planned checks and settings per print, recording bookkeeping
    [
        "ALTER TABLE prints ADD COLUMN planned TEXT NOT NULL DEFAULT '[]'",
        "ALTER TABLE prints ADD COLUMN settings TEXT NOT NULL DEFAULT '{}'",
        "ALTER TABLE prints ADD COLUMN recording_bytes INTEGER NOT NULL DEFAULT 0",
        "CREATE INDEX prints_by_start ON prints(started)",
    ],
]
SCHEMA_VERSION = len(MIGRATIONS)

RESULTS = ("running", "done", "paused", "cancelled", "failed", "interrupted")


def utc_now() -> str:
    return time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())


def migrate(connection: sqlite3.Connection, target: int = SCHEMA_VERSION) -> int:
    """Bring the database to schema ``target``; returns the version it had before."""
    before = connection.execute("PRAGMA user_version").fetchone()[0]
    if before > SCHEMA_VERSION:
        raise RuntimeError(
            f"history database has schema {before}, newer than this plugin's {SCHEMA_VERSION}; update the plugin"
        )
    for version in range(before, target):
        with connection:  # one transaction per step: a failed step leaves the previous version intact
            for statement in MIGRATIONS[version]:
                connection.execute(statement)
            connection.execute(f"PRAGMA user_version = {version + 1}")
    return before


def folder_bytes(path: Path) -> int:
    return sum(f.stat().st_size for f in path.rglob("*") if f.is_file()) if path.exists() else 0


class History:
    """Thread-safe history store in ``data_dir`` (``history.sqlite`` and ``recordings/``)."""

    def __init__(self, data_dir: str | Path) -> None:
        self.data_dir = Path(data_dir)
        self.data_dir.mkdir(parents=True, exist_ok=True)
        self.recordings_dir = self.data_dir / "recordings"
        self.recordings_dir.mkdir(exist_ok=True)
        self.db_path = self.data_dir / "history.sqlite"
        self._lock = threading.RLock()
        self._db = sqlite3.connect(str(self.db_path), check_same_thread=False, isolation_level=None)
        self._db.row_factory = sqlite3.Row
        self._db.execute("PRAGMA foreign_keys = ON")
        self._db.execute("PRAGMA journal_mode = WAL")
        self.migrated_from = migrate(self._db)

    def close(self) -> None:
        with self._lock:
            self._db.close()

    # ------------------------------------------------------------ prints
    def start_print(self, origin: str, path: str, name: str, planned: Iterable[dict], settings: dict) -> int:
        planned = list(planned)
        with self._lock:
            cursor = self._db.execute(
                "INSERT INTO prints (origin, path, name, started, checks_planned, planned, settings)"
                " VALUES (?, ?, ?, ?, ?, ?, ?)",
                (origin, path, name, utc_now(), len(planned), json.dumps(planned), json.dumps(settings)),
            )
            return int(cursor.lastrowid)

    def recording_dir(self, print_id: int) -> Path:
        return self.recordings_dir / str(int(print_id))

    def add_check(self, print_id: int, check: dict) -> None:
        with self._lock:
            self._db.execute(
                "INSERT OR REPLACE INTO checks (print_id, idx, layer, z, verdict, data) VALUES (?, ?, ?, ?, ?, ?)",
                (print_id, int(check["index"]), int(check["layer"]), float(check["z"]), check["verdict"], json.dumps(check)),
            )
            if check["verdict"] == "fail":
                self._db.execute(
                    "UPDATE prints SET first_failure_layer = ?, failure_reason = ?"
                    " WHERE id = ? AND first_failure_layer IS NULL",
                    (int(check["layer"]), "; ".join(check.get("reasons") or []) or None, print_id),
                )

    def update_check(self, print_id: int, check: dict) -> None:
        """Replace a stored check (a deferred check that got its verdict later)."""
        self.add_check(print_id, check)

    def end_print(self, print_id: int, result: str) -> None:
        if result not in RESULTS:
            raise ValueError(f"unknown print result {result!r}")
        with self._lock:
            self._db.execute(
                "UPDATE prints SET ended = ?, result = ?, recording_bytes = ? WHERE id = ? AND ended IS NULL",
                (utc_now(), result, folder_bytes(self.recording_dir(print_id)), print_id),
            )

    def set_result(self, print_id: int, result: str) -> None:
        """Result of a print that is still running (``paused`` by us, back to ``running`` on resume)."""
        with self._lock:
            self._db.execute("UPDATE prints SET result = ? WHERE id = ? AND ended IS NULL", (result, print_id))

    def close_interrupted(self) -> list[int]:
        """Prints still 'running' when OctoPrint (re)starts were cut off by the restart."""
        with self._lock:
            ids = [r[0] for r in self._db.execute("SELECT id FROM prints WHERE ended IS NULL")]
            for print_id in ids:
                self.end_print(print_id, "interrupted")
            return ids

    # ------------------------------------------------------------ reading
    def _print_row(self, row: sqlite3.Row, checks_done: int) -> dict:
        bytes_ = row["recording_bytes"] if row["ended"] else folder_bytes(self.recording_dir(row["id"]))
        available = (self.recording_dir(row["id"]) / "session.json").exists()
        return {
            "id": row["id"],
            "file": {"origin": row["origin"], "path": row["path"], "name": row["name"]},
            "started": row["started"],
            "ended": row["ended"],
            "result": row["result"],
            "checks_planned": row["checks_planned"],
            "checks_done": checks_done,
            "first_failure_layer": row["first_failure_layer"],
            "failure_reason": row["failure_reason"],
            "recording": {
                "available": available,
                "bytes": bytes_ if available else 0,
                "url": f"prints/{row['id']}/recording.zip" if available else None,
            },
        }

    def list_prints(self, limit: int = 50, offset: int = 0) -> tuple[list[dict], int]:
        with self._lock:
            total = self._db.execute("SELECT COUNT(*) FROM prints").fetchone()[0]
            rows = self._db.execute(
                "SELECT p.*, (SELECT COUNT(*) FROM checks c WHERE c.print_id = p.id) AS n"
                " FROM prints p ORDER BY p.id DESC LIMIT ? OFFSET ?",
                (int(limit), int(offset)),
            ).fetchall()
            return [self._print_row(r, r["n"]) for r in rows], int(total)

    def get_print(self, print_id: int) -> dict | None:
        with self._lock:
            row = self._db.execute("SELECT * FROM prints WHERE id = ?", (int(print_id),)).fetchone()
            if row is None:
                return None
            checks = [json.loads(r["data"]) for r in self._db.execute(
                "SELECT data FROM checks WHERE print_id = ? ORDER BY idx", (int(print_id),))]
            detail = self._print_row(row, len(checks))
            detail["checks"] = checks
            detail["planned_checks"] = json.loads(row["planned"])
            detail["settings"] = json.loads(row["settings"])
            return detail

    def get_check(self, print_id: int, index: int) -> dict | None:
        with self._lock:
            row = self._db.execute(
                "SELECT data FROM checks WHERE print_id = ? AND idx = ?", (int(print_id), int(index))
            ).fetchone()
            return json.loads(row["data"]) if row else None

    # ------------------------------------------------------------ clean-up
    def delete_print(self, print_id: int) -> bool:
        with self._lock:
            cursor = self._db.execute("DELETE FROM prints WHERE id = ?", (int(print_id),))
            self._db.execute("DELETE FROM checks WHERE print_id = ?", (int(print_id),))
        shutil.rmtree(self.recording_dir(print_id), ignore_errors=True)
        return cursor.rowcount > 0

    def enforce_limits(self, max_bytes: int, keep_prints: int, running: int | None = None) -> list[int]:
        """Delete the oldest prints beyond ``keep_prints`` and the oldest recordings beyond ``max_bytes``.

        The running print (``running``) is never touched. Returns the ids whose recording was removed.
        """
        removed: list[int] = []
        with self._lock:
            ids = [r[0] for r in self._db.execute("SELECT id FROM prints ORDER BY id DESC")]
            for print_id in ids[max(int(keep_prints), 1):]:
                if print_id != running:
                    self.delete_print(print_id)
                    removed.append(print_id)
            sizes = {}
            for folder in self.recordings_dir.iterdir():
                if folder.is_dir() and folder.name.isdigit():
                    sizes[int(folder.name)] = folder_bytes(folder)
            total = sum(sizes.values())
            for print_id in sorted(sizes):  # oldest first
                if total <= max_bytes:
                    break
                if print_id == running:
                    continue
                shutil.rmtree(self.recording_dir(print_id), ignore_errors=True)
                self._db.execute("UPDATE prints SET recording_bytes = 0 WHERE id = ?", (print_id,))
                total -= sizes[print_id]
                removed.append(print_id)
        return removed
