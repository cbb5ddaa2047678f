"""Every option of every config group composes into the search's config and builds the component
it names (issue 36 part 5): a task's simulator steps, a GFO method asks and is told, a generator
answers a prompt, an executor evaluates a program, a tracker is made, a database
selects a prompt's programs. A new option file that does not compose, or whose component cannot
be built from it, fails here.

Built here where nothing outside the process is needed: the OpenAI-compatible client needs a
server (tests/test_generate.py runs it against one), vLLM its library and a GPU, Ray a cluster
(tests/test_ray.py starts one), and what a tracker records needs a run's Hydra context
(tests/test_track.py): for those, the composed option is checked against the component
its registry holds (the schema it needs), which is what a run does before it starts."""

from __future__ import annotations

import os
from importlib import resources

import numpy as np
import pytest
from conftest import compose, unavailable

from colmo.config.fields import check_component
from colmo.config.schemas import CONFIG_MODULE

GROUPS = ("task", "gfo", "llm", "executor", "tracker", "database")
OPTIONS = [
    (group, entry.name.removesuffix(".yaml"))
    for group in GROUPS
    for entry in sorted(resources.files(CONFIG_MODULE).joinpath(group).iterdir(), key=lambda entry: entry.name)
    if entry.name.endswith(".yaml")
]
NOT_BUILT_HERE = {("llm", "openai"), ("llm", "vllm"), ("executor", "ray")}
COMPONENT_FIELD = {"gfo": "method", "llm": "name", "executor": "name", "tracker": "name"}
STARTER = "import numpy as np\n\ndef policy(obs):\n    return np.clip(-1.5 * obs[2], -1.0, 1.0)\n"


def test_every_group_has_options():
    assert {group for group, _ in OPTIONS} == set(GROUPS) and len(OPTIONS) >= 18


@pytest.mark.parametrize(("group", "option"), OPTIONS, ids=[f"{group}={option}" for group, option in OPTIONS])
def test_every_option_composes_and_builds_its_component(group, option, tmp_path):
    overrides = [f"{group}={option}"]
    if (group, option) == ("llm", "llamacpp"):
        model = os.environ.get("COLMO_TEST_MODEL")
        if not model:
            unavailable("llm=llamacpp is built with the test model: set COLMO_TEST_MODEL (scripts/fetch_test_model.py)", "every option is built in CI")
        overrides += [f"llm.model_path={model}", "llm.max_tokens=16"]  # an answer, however short: built, not judged
    cfg = compose("search", *overrides)
    options = getattr(cfg, group)
    if group in COMPONENT_FIELD:
        check_component(options, COMPONENT_FIELD[group])
    if (group, option) not in NOT_BUILT_HERE:
        BUILD[group](options, tmp_path)


def build_task(cfg, tmp_path) -> None:
    from colmo.specs import load_spec

    env = load_spec(cfg.spec).make_environment(**cfg.env)
    obs = env.reset(0)
    reward, after = env.step(np.zeros(env.action_size))
    assert np.isfinite(reward) and after.shape == obs.shape and np.isfinite(after).all()


def build_gfo(cfg, tmp_path) -> None:
    from colmo.optimize.methods import METHODS

    method = METHODS.chosen(cfg.method)(3, cfg, 0)
    for score in (1.0, 2.0, None):
        token, z = method.ask()
        assert z.shape == (3,)
        method.tell(token, score)


def build_llm(cfg, tmp_path) -> None:
    from colmo.database import ProgramDatabase, StoredProgram
    from colmo.generate import make_generator
    from colmo.prompt import build_prompt

    database = ProgramDatabase(compose("search").database, StoredProgram("starter", STARTER, 1.0, 0, 0), seed=0)
    generator = make_generator(cfg, seed=0, probe=lambda code: True)
    try:
        [generation] = generator.generate(build_prompt("Swing the pole up.", database.select()), 1)
    finally:
        generator.close()
    assert generation.text and generation.generator.startswith(cfg.name)


def build_executor(cfg, tmp_path) -> None:
    from colmo.evaluation import EvalRequest
    from colmo.executor import make_executor

    with make_executor(cfg, max_workers=1) as executor:
        [evaluation] = executor.evaluate([EvalRequest("pendulum.py", (), (0,), "def policy(obs):\n    return 0.0\n", ("numpy", "math"), (), steps=10)])
    assert evaluation.failure is None and len(evaluation.returns) == 1


def build_tracker(cfg, tmp_path) -> None:
    from colmo.trackers import TRACKERS, make_tracker

    assert type(make_tracker(cfg)) is TRACKERS[cfg.name]  # what it records needs a run: tests/test_track.py


def build_database(cfg, tmp_path) -> None:
    from colmo.database import ProgramDatabase, StoredProgram

    database = ProgramDatabase(cfg, StoredProgram("starter", STARTER, 1.0, 0, 0), seed=0)
    database.register(StoredProgram("better", STARTER.replace("1.5", "2.5"), 2.0, 0, 1))
    assert database.select().programs


BUILD = {"task": build_task, "gfo": build_gfo, "llm": build_llm, "executor": build_executor, "tracker": build_tracker, "database": build_database}
