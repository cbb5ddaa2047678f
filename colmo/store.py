"""The durable program store: one SQLite file per run that records every sample as it lands.

Each generated sample gets one row, keyed by its sample index: evaluated programs with code,
skeleton, initial and tuned constants, score, per-episode returns, island, parents,
generator and timings, and also failures, duplicates and unusable outputs with their reason.
Rows are committed one at a time in WAL mode, so a run killed at any moment keeps every
program it finished; the primary key makes a sample impossible to count twice. `resume=`
rebuilds the search state by reading the rows back in order.
"""

from __future__ import annotations

import json
import sqlite3
import threading
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any, Iterator, Optional

from colmo.config import ConfigError

STORE_FILE = "programs.db"

_SCHEMA = """
CREATE TABLE IF NOT EXISTS run (name TEXT PRIMARY KEY, value TEXT NOT NULL);
CREATE TABLE IF NOT EXISTS samples (
    sample INTEGER PRIMARY KEY,
    batch INTEGER NOT NULL,
    status TEXT NOT NULL,            -- evaluated | failed | duplicate | invalid
    island INTEGER NOT NULL,
    parent_keys TEXT NOT NULL,       -- JSON list
    generator TEXT NOT NULL,
    raw TEXT NOT NULL,               -- the generator's output as it came
    key TEXT,
    skeleton TEXT,
    code TEXT,                       -- readable code with the tuned constants inlined
    initial_params TEXT,             -- JSON list
    params TEXT,                     -- JSON list
    initial_score REAL,
    score REAL,
    returns TEXT,                    -- JSON list, per episode
    evaluations INTEGER,
    failure TEXT,
    generation_seconds REAL,
    evaluation_seconds REAL,
    prompt_tokens INTEGER,
    completion_tokens INTEGER,
    created REAL NOT NULL
);
CREATE INDEX IF NOT EXISTS samples_key ON samples(key);
"""


@dataclass
class SampleRecord:
    sample: int
    batch: int
    status: str
    island: int
    parent_keys: list[str]
    generator: str
    raw: str
    key: Optional[str] = None
    skeleton: Optional[str] = None
    code: Optional[str] = None
    initial_params: Optional[list[float]] = None
    params: Optional[list[float]] = None
    initial_score: Optional[float] = None
    score: Optional[float] = None
    returns: Optional[list[float]] = None
    evaluations: Optional[int] = None
    failure: Optional[str] = None
    generation_seconds: float = 0.0
    evaluation_seconds: float = 0.0
    prompt_tokens: int = 0
    completion_tokens: int = 0
    created: float = field(default_factory=time.time)


_JSON_FIELDS = ("parent_keys", "initial_params", "params", "returns")


class ProgramStore:
    def __init__(self, path: Path | str):
        self.path = Path(path)
        self.connection = sqlite3.connect(self.path, timeout=30, check_same_thread=False)
        # Program threads store their results as they finish: one writer at a time.
        self._lock = threading.Lock()
        self.connection.execute("PRAGMA journal_mode=WAL")
        self.connection.execute("PRAGMA synchronous=NORMAL")
        self.connection.executescript(_SCHEMA)
        self.connection.commit()

    def set_meta(self, **values: Any) -> None:
        with self.connection:
            self.connection.executemany(
                "INSERT OR REPLACE INTO run(name, value) VALUES (?, ?)",
                [(name, json.dumps(value)) for name, value in values.items()],
            )

    def meta(self) -> dict[str, Any]:
        return {name: json.loads(value) for name, value in self.connection.execute("SELECT name, value FROM run")}

    def add(self, record: SampleRecord) -> None:
        row = asdict(record)
        for name in _JSON_FIELDS:
            if row[name] is not None:
                row[name] = json.dumps(row[name])
        columns = ", ".join(row)
        with self._lock, self.connection:
            self.connection.execute(
                f"INSERT INTO samples({columns}) VALUES ({', '.join('?' * len(row))})", tuple(row.values())
            )

    def records(self) -> Iterator[SampleRecord]:
        cursor = self.connection.execute("SELECT * FROM samples ORDER BY sample")
        names = [column[0] for column in cursor.description]
        for values in cursor:
            row = dict(zip(names, values))
            for name in _JSON_FIELDS:
                if row[name] is not None:
                    row[name] = json.loads(row[name])
            yield SampleRecord(**row)

    def close(self) -> None:
        self.connection.close()


def open_for_resume(run_dir: Path, task: str) -> ProgramStore:
    """The store of an earlier run of `task`; `ConfigError` if `run_dir` is not one."""
    path = Path(run_dir) / STORE_FILE
    if not path.is_file():
        raise ConfigError(f"resume={run_dir} is not a colmo run directory (no {STORE_FILE} in it)")
    store = ProgramStore(path)
    made_with = store.meta().get("task")
    if made_with != task:
        store.close()
        raise ConfigError(f"resume={run_dir} was made with task={made_with}; pass task={made_with} to resume it")
    return store
