"""Re-read the answers of finished runs that failed with "name 'policy_vN' is not defined", with
the code their prompt showed (issue 19; `colmo.extract`'s `shown=`), and say which now read and
run: a program that reads is stepped on 20 random pendulum observations, outside any sandbox
(these are this project's own stored answers; never run this on a store you did not make).

    python docs/llm-duplicates/reread_shown_versions.py docs/llm-gfo-vs-none/runs/*/s*/programs.db
"""

from __future__ import annotations

import json
import sqlite3
import sys

import numpy as np

from colmo.database import Selection, StoredProgram
from colmo.intake import read_program
from colmo.program import instantiate
from colmo.prompt import build_prompt
from colmo.specs import load_spec


def main(stores: list[str]) -> None:
    spec = load_spec("pendulum.py")
    observations = [np.array([np.cos(t), np.sin(t), v]) for t, v in np.random.default_rng(0).uniform(-3, 3, (20, 2))]
    for store in stores:
        connection = sqlite3.connect(f"file:{store}?mode=ro", uri=True)
        evaluated = {
            key: (code, score, island, sample)
            for key, code, score, island, sample in connection.execute(
                "SELECT key, code, score, island, sample FROM samples WHERE status = 'evaluated' AND score IS NOT NULL"
            )
        }
        failed = connection.execute("SELECT sample, parent_keys, raw FROM samples WHERE failure LIKE '%name ''policy_v%'").fetchall()
        running = 0
        for sample, parent_keys, raw in failed:
            shown = sorted((StoredProgram(key, *evaluated[key]) for key in json.loads(parent_keys)), key=lambda program: program.score)
            prompt = build_prompt(spec.description, Selection(shown[0].island, shown), allowed_imports=spec.allowed_imports)
            try:
                program = read_program(raw, spec.allowed_imports, shown=prompt.shown_code)
                namespace: dict = {}
                exec(instantiate(program.skeleton, program.values), namespace)
                with np.errstate(all="ignore"):
                    finite = all(np.isfinite(np.asarray(namespace["policy"](obs), dtype=float)).all() for obs in observations)
            except Exception as error:  # what the answer still does wrong
                print(f"{store} sample {sample}: still fails: {type(error).__name__}: {error}")
                continue
            running += finite
            print(f"{store} sample {sample}: reads and runs, {'finite' if finite else 'NON-FINITE'} actions")
        print(f"{store}: {len(failed)} failed with an undefined policy_vN; {running} now read and run with finite actions")


if __name__ == "__main__":
    main(sys.argv[1:])
