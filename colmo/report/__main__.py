"""`colmo-report experiment=... [sweep=...] [axis=...] [out=DIR]` (or `python -m colmo.report`): the
report of one sweep (`colmo.report`), a Hydra app like the other tools: `key=value` overrides of
`colmo.config.ReportConfig`, `--help`, and every error one line with exit code 2. It prints
the path of `report.md`.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

from colmo.cli import hydra_app
from colmo.config import ReportConfig
from colmo.errors import ConfigError
from colmo.report import AXES, default_out, write_report
from colmo.track import connect, default_tracking_uri, sqlite_path


def _tracking_uri(cfg: ReportConfig) -> str:
    return cfg.tracking_uri or default_tracking_uri(Path.cwd())


def check_inputs(cfg: ReportConfig) -> None:
    """The axes are the report's, and the tracking database exists (a report never creates one)."""
    if not set(cfg.axis) <= set(AXES):
        raise ConfigError(f"axis must be one or more of {', '.join(AXES)}, got {','.join(cfg.axis)!r}")
    database = sqlite_path(_tracking_uri(cfg))
    if database is not None and not database.is_file():
        raise ConfigError(f"no tracking database at {database}: run a search first, or pass tracking_uri=")


def make_report(cfg: ReportConfig, command: str = "") -> Path:
    """Write the report `cfg` asks for (`colmo.report.write_report`) and return its `report.md`;
    `ConfigError` for an experiment or sweep that does not exist, no usable run, or an `out`
    that already holds a report."""
    os.environ.setdefault("MLFLOW_ENABLE_ARTIFACTS_PROGRESS_BAR", "false")  # one bar per policy file is noise
    out = Path(cfg.out) if cfg.out else default_out(cfg.experiment)
    try:
        return write_report(connect(_tracking_uri(cfg)), cfg.experiment, out, cfg.axis, command, cfg.sweep)
    except ValueError as error:
        raise ConfigError(str(error)) from None


@hydra_app("report", check=check_inputs, example="experiment=pendulum axis=seconds")
def main(cfg: ReportConfig) -> None:
    """Compare the search variants of one sweep: Table I, the best-so-far figures and each variant's best policy."""
    invoked = Path(sys.argv[0]).name
    print(make_report(cfg, f"{invoked if invoked == 'colmo-report' else 'python -m colmo.report'} {' '.join(sys.argv[1:])}"))


if __name__ == "__main__":
    main()
