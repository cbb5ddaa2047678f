"""The durable program store of a run, and the run directory's files and lock.

A run directory holds `programs.db` (this store), `summary.json`, `best_policy.py`, and a lock
file. The store is one SQLite file with one row per generated sample, keyed by its sample
index. A batch's samples are committed as `pending` as soon as they are generated (the model's
output, its prompt's island and parents, tokens and timings), in sample order and all or none,
so the sample numbers in the store never have a gap; each row is then replaced by its outcome
as it lands: code, skeleton, initial and final constants, scores, per-episode returns, sizes,
or the reason of a failure, a duplicate, an unusable output. WAL mode and one commit per row:
a run killed at any moment keeps every program it finished and every output it generated, and
the primary key makes a sample impossible to count twice. `resume=` rebuilds the search state
by reading the rows back and evaluates the `pending` and `interrupted` ones again.

`open_run` opens (and locks) the store of a new or resumed run: a second search into the same
directory, a resume with settings that change scores, a corrupt or empty store, or a directory
that cannot be written are each one `ConfigError` line naming the path.
"""

from __future__ import annotations

import contextlib
import fcntl
import json
import logging
import os
import sqlite3
import threading
from dataclasses import asdict, fields
from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable, Iterator, Mapping, Optional

from colmo.coverage import annotate, counts_of
from colmo.errors import ConfigError, RunError
from colmo.provenance import provenance
from colmo.record import TO_EVALUATE_AGAIN, Elapsed, SampleRecord, Summary

log = logging.getLogger("colmo.store")

if TYPE_CHECKING:
    from colmo.config import SearchConfig

STORE_FILE = "programs.db"
SUMMARY_FILE = "summary.json"
BEST_POLICY_FILE = "best_policy.py"
SIMPLIFIED_POLICY_FILE = "simplified_policy.py"
RETUNED_POLICY_FILE = "retuned_policy.py"
BEST_SO_FAR_PLOT = "best_so_far.png"  # the best score so far per model call: an MLflow run's figure, a report's
LOCK_FILE = ".colmo.lock"

_SQL_TYPES = {"int": "INTEGER", "float": "REAL", "str": "TEXT", "bool": "INTEGER"}
_JSON_FIELDS = ("parent_keys", "initial_params", "params", "returns", "coverage")
# The run table holds the run's settings, and under these names the time the run has taken
# (`Elapsed`) and the version of the structure keys in its rows (`colmo.program.STRUCTURE_KEY_VERSION`).
_ELAPSED = "elapsed"
_KEY_VERSION = "structure_key_version"


def _column(name: str, annotation: str) -> str:
    if name in _JSON_FIELDS:
        return f"{name} TEXT"
    kind = next((sql for python, sql in _SQL_TYPES.items() if annotation.removeprefix("Optional[").startswith(python)), "TEXT")
    return f"{name} {kind}{'' if annotation.startswith('Optional') else ' NOT NULL'}"


_COLUMNS = [(f.name, _column(f.name, str(f.type))) for f in fields(SampleRecord)]
_SCHEMA = f"""
CREATE TABLE IF NOT EXISTS run (name TEXT PRIMARY KEY, value TEXT NOT NULL);
CREATE TABLE IF NOT EXISTS samples ({', '.join(column if name != 'sample' else 'sample INTEGER PRIMARY KEY' for name, column in _COLUMNS)});
CREATE INDEX IF NOT EXISTS samples_key ON samples(key);
"""
# Columns added since the first stores, with the value an older row means: a store written
# before them is given them when it is opened (resumed or read), its rows keeping their meaning.
_ADDED_COLUMNS = {
    "model_calls": "INTEGER NOT NULL DEFAULT 1",  # one model call per sample then
    "prompt_shown": "TEXT NOT NULL DEFAULT ''",  # chat answers were read without the shown code then
    "coverage": "TEXT",  # branches were not counted then
}


class StoreError(RunError):
    """The store cannot be written (a full disk, an I/O error); what it holds is intact."""


class ProgramStore:
    """One run's samples in SQLite; `add` may be called from several threads."""

    def __init__(self, path: Path | str):
        self.path = Path(path)
        try:
            # Private from the start: it holds programs' failure messages and the run's settings.
            # SQLite creates its -wal and -shm files with the database's mode.
            os.close(os.open(self.path, os.O_RDONLY | os.O_CREAT, 0o600))
            self.connection = sqlite3.connect(self.path, timeout=30, check_same_thread=False)
            self.connection.execute("PRAGMA journal_mode=WAL")
            self.connection.execute("PRAGMA synchronous=NORMAL")
            self.connection.executescript(_SCHEMA)
            present = {row[1] for row in self.connection.execute("PRAGMA table_info(samples)")}
            for name, column in _ADDED_COLUMNS.items():
                if name not in present:
                    self.connection.execute(f"ALTER TABLE samples ADD COLUMN {name} {column}")
            self.connection.commit()
        except sqlite3.DatabaseError as error:
            raise ConfigError(f"{self.path} is not a colmo program store ({error})") from None
        except OSError as error:
            raise ConfigError(f"cannot open the program store {self.path}: {error.strerror}") from None
        # Program threads store their results as they finish: one writer at a time.
        self._lock = threading.Lock()

    def set_meta(self, values: Mapping[str, Any]) -> None:
        with self._writing():
            _put_run_values(self.connection, values)

    def set_heldout(self, sample: int, score: Optional[float]) -> None:
        with self._writing():
            self.connection.execute("UPDATE samples SET heldout_score = ? WHERE sample = ?", (score, sample))

    def meta(self) -> dict[str, Any]:
        return _run_settings_in(self.connection)

    def elapsed(self) -> Elapsed:
        """The time the run's earlier processes took (nothing for a new run)."""
        return _elapsed_in(self.connection) or Elapsed()

    def set_elapsed(self, elapsed: Elapsed) -> None:
        """Record the time the run has taken so far, for a resumed run to add to."""
        self.set_meta({_ELAPSED: asdict(elapsed)})

    def key_version(self) -> Optional[int]:
        """The version of the structure keys in the rows; None for a store older than the record."""
        return _run_value(self.connection, _KEY_VERSION)

    def rekey(self, key_of: Callable[[SampleRecord], str], version: int) -> int:
        """Give every row that holds a program (its skeleton) the key `key_of` computes, and record
        that the keys are of `version`; all or none. Returns how many rows' keys changed."""
        changed = [(key, record.sample) for record in self.records() if record.skeleton is not None and (key := key_of(record)) != record.key]
        with self._writing():
            self.connection.executemany("UPDATE samples SET key = ? WHERE sample = ?", changed)
            _put_run_values(self.connection, {_KEY_VERSION: version})
        return len(changed)

    def add(self, *records: SampleRecord) -> None:
        """Store samples, all or none; a sample's pending or interrupted row is replaced by its
        outcome."""
        with self._writing():
            for record in records:
                row = record.as_row()
                for name in _JSON_FIELDS:
                    if row[name] is not None:
                        row[name] = json.dumps(list(row[name]))
                self.connection.execute(
                    f"DELETE FROM samples WHERE sample = ? AND status IN ({', '.join('?' * len(TO_EVALUATE_AGAIN))})",
                    (record.sample, *TO_EVALUATE_AGAIN),
                )
                self.connection.execute(f"INSERT INTO samples({', '.join(row)}) VALUES ({', '.join('?' * len(row))})", tuple(row.values()))

    @contextlib.contextmanager
    def _writing(self) -> Iterator[None]:
        with self._lock:
            try:
                with self.connection:
                    yield
            except sqlite3.OperationalError as error:  # a full disk, an I/O error
                raise StoreError(f"cannot write to {self.path}: {error}") from None

    def records(self) -> Iterator[SampleRecord]:
        cursor = self.connection.execute("SELECT * FROM samples ORDER BY sample")
        names = [column[0] for column in cursor.description]
        for values in cursor:
            row = dict(zip(names, values))
            for name in _JSON_FIELDS:
                if row[name] is not None:
                    row[name] = tuple(json.loads(row[name]))
            if row["coverage"] is not None:  # a site's counts are a tuple too
                row["coverage"] = tuple(map(tuple, row["coverage"]))
            row["cut_short"] = bool(row["cut_short"])
            yield SampleRecord(**row)

    def close(self) -> None:
        self.connection.close()


class RunLock:
    """An exclusive lock on a run directory, held while a search writes to it."""

    def __init__(self, run_dir: Path):
        path = run_dir / LOCK_FILE
        try:
            self.file = open(path, "a+")
        except OSError as error:
            raise ConfigError(f"cannot write to the run directory {run_dir}: {error.strerror}") from None
        try:
            fcntl.flock(self.file, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            self.file.seek(0)
            owner = self.file.read().strip() or "another process"
            self.file.close()
            raise ConfigError(f"the run directory {run_dir} is in use by another colmo search (pid {owner})") from None
        self.file.seek(0)
        self.file.truncate()
        self.file.write(str(os.getpid()))
        self.file.flush()

    def release(self) -> None:
        self.file.close()


def open_run(run_dir: Path, settings: Mapping[str, Any], resume: bool) -> tuple[ProgramStore, RunLock]:
    """The locked store of a new run in `run_dir` (recording `settings`), or of the earlier run
    there (whose recorded settings must equal `settings`)."""
    if resume:
        path = _existing_store(run_dir)
    else:
        path = run_dir / STORE_FILE
        try:
            run_dir.mkdir(mode=0o700, parents=True, exist_ok=True)  # private where colmo creates it
        except OSError as error:
            raise ConfigError(f"cannot create the run directory {run_dir}: {error.strerror}") from None
    lock = RunLock(run_dir)
    try:
        store = ProgramStore(path)
        if resume:
            check_settings(run_dir, store.meta(), settings)
        elif store.meta():
            raise ConfigError(f"{run_dir} already holds a colmo run; resume it with resume={run_dir}")
        else:
            store.set_meta(settings)
    except BaseException:
        lock.release()
        raise
    return store, lock


def run_settings(cfg: "SearchConfig") -> dict[str, Any]:
    """The settings a run's scores depend on; a resumed run must keep them."""
    gfo = {f"gfo.{name}": value for name, value in asdict(cfg.gfo).items()}
    # Only when on, so that runs from before task.perturb existed still resume.
    perturb = {"task.perturb": asdict(cfg.task.perturb)} if cfg.task.perturb.active else {}
    return {"task": cfg.task.name, "seed": cfg.seed, "task.episodes": cfg.task.episodes, "task.env": cfg.task.env, **perturb, **gfo}


def check_settings(run_dir: Path, recorded: Mapping[str, Any], settings: Mapping[str, Any]) -> None:
    """`ConfigError` naming every setting that differs from the run's (scores would not compare)."""
    if not recorded:
        raise ConfigError(f"{run_dir / STORE_FILE} holds no colmo run (no run settings in it)")
    changed = sorted(name for name in settings if recorded.get(name) != settings[name])
    if changed:
        was = ", ".join(f"{name}={_shown(recorded.get(name))}" for name in changed)
        now = ", ".join(f"{name}={_shown(settings[name])}" for name in changed)
        raise ConfigError(f"resume={run_dir} was made with {was}; this command has {now}: pass the same to resume it (scores would not compare)")


def _shown(value: Any) -> str:
    return value if isinstance(value, str) else json.dumps(value)


def open_for_resume(run_dir: Path, settings: Mapping[str, Any]) -> None:
    """Check, without locking or changing anything, that `run_dir` can be resumed with `settings`."""
    path = _existing_store(run_dir)
    try:
        connection = sqlite3.connect(f"file:{path}?mode=ro", uri=True)
        try:
            recorded = _run_settings_in(connection)
        finally:
            connection.close()
    except sqlite3.DatabaseError as error:
        raise ConfigError(f"{path} is not a colmo program store ({error})") from None
    check_settings(run_dir, recorded, settings)


def holds_run(run_dir: Path) -> bool:
    """Whether `run_dir` holds an earlier run's store, its settings recorded, read without
    changing anything (a run killed before it recorded them left nothing to resume)."""
    path = run_dir / STORE_FILE
    if not path.is_file() or not path.stat().st_size:
        return False
    try:
        connection = sqlite3.connect(f"file:{path}?mode=ro", uri=True)
        try:
            return bool(_run_settings_in(connection))
        finally:
            connection.close()
    except sqlite3.DatabaseError:
        return False


def _existing_store(run_dir: Path) -> Path:
    """The store file of the earlier run in `run_dir`, or `ConfigError` saying why there is none."""
    path = run_dir / STORE_FILE
    if not path.is_file():
        raise ConfigError(f"resume={run_dir} is not a colmo run directory (no {STORE_FILE} in it)")
    if path.stat().st_size == 0:
        raise ConfigError(f"{path} is empty: not a colmo program store")
    return path


def recorded_elapsed(path: Path) -> Optional[Elapsed]:
    """The time a store says its run has taken, read without changing anything; None where it
    records none (a store from before colmo recorded it). `sqlite3.DatabaseError` if `path` is
    not a program store."""
    connection = sqlite3.connect(f"file:{path}?mode=ro", uri=True)
    try:
        return _elapsed_in(connection)
    finally:
        connection.close()


def _run_value(connection: sqlite3.Connection, name: str) -> Any:
    """The run table's value under `name`; None where it has none."""
    row = connection.execute("SELECT value FROM run WHERE name = ?", (name,)).fetchone()
    return json.loads(row[0]) if row else None


def _put_run_values(connection: sqlite3.Connection, values: Mapping[str, Any]) -> None:
    connection.executemany("INSERT OR REPLACE INTO run(name, value) VALUES (?, ?)", [(name, json.dumps(value)) for name, value in values.items()])


def _elapsed_in(connection: sqlite3.Connection) -> Optional[Elapsed]:
    recorded = _run_value(connection, _ELAPSED)
    return Elapsed(**recorded) if recorded is not None else None


def _run_settings_in(connection: sqlite3.Connection) -> dict[str, Any]:
    return {name: json.loads(value) for name, value in connection.execute("SELECT name, value FROM run WHERE name NOT IN (?, ?)", (_ELAPSED, _KEY_VERSION))}


def read_summary(run_dir: Path) -> Optional[dict[str, Any]]:
    """The `summary.json` a run wrote in `run_dir`; None if it wrote none (or one cut off while written)."""
    try:
        return json.loads((run_dir / SUMMARY_FILE).read_text())
    except (OSError, ValueError):
        return None


def write_outputs(summary: Summary, run_dir: Path) -> None:
    """`summary.json` (with the run's `colmo.provenance`) and the best policy as a readable `.py`
    file with its scores, in the run directory; a file that cannot be written is logged, not
    fatal (the store holds everything)."""
    try:
        (run_dir / SUMMARY_FILE).write_text(json.dumps({**summary.as_dict(), "provenance": provenance()}, indent=2))
        if summary.best_code:
            heldout = f", held-out {summary.best_heldout_score:.2f}" if summary.best_heldout_score is not None else ""
            header = (
                f"# colmo best policy for {summary.task}: training score {summary.best_score:.2f}{heldout}"
                f" after {summary.samples} samples\n"
            ) + "".join(f"# misleading name: {line}\n" for line in summary.misnamed) + "".join(
                f"# decided by the code: {line}\n" for line in summary.decided
            )
            (run_dir / BEST_POLICY_FILE).write_text(header + _with_coverage(summary.best_code, summary.coverage))
    except OSError as error:
        log.error("cannot write the run's outputs to %s: %s", run_dir, error)


def _with_coverage(code: str, counted: dict[str, Any]) -> str:
    """The best policy's code with what each branch did as comments (`colmo.coverage`), if counted."""
    annotated = annotate(code, counts_of(counted)) if counted.get("sites") else None
    if annotated is None:
        return code
    return f"# branches counted over {counted['episodes']} training and held-out episodes (fast path)\n" + annotated
