"""One dispatch style for every component kind (`colmo.registry`): GFO methods, executors and
trackers are picked by name from a registry filled where each is defined; bad names and
options that do not fit the name end in one `ConfigError` line listing the registered names;
`--help` lists them; `gfo=none` is a registered method that tunes nothing."""

from __future__ import annotations

import sys

import pytest
from conftest import compose

from colmo.config import ExecutorConfig, GFOConfig, TrackerConfig
from colmo.errors import ConfigError
from colmo.evaluation import Evaluation
from colmo.executor import EXECUTORS, LocalExecutor, make_executor
from colmo.help import help_text
from colmo.optimize.methods import METHODS, EvaluateOnce, tunes_constants
from colmo.optimize.tune import tune
from colmo.registry import Library, Registry
from colmo.trackers import TRACKERS, NoTracker, make_tracker


def test_every_kind_is_registered_where_it_is_defined():
    assert list(METHODS) == ["none", "oneplusone", "cma", "de", "bo"]
    assert set(EXECUTORS) == {"local", "ray"}
    assert set(TRACKERS) == {"none", "mlflow"}
    assert METHODS["none"] is EvaluateOnce and not EvaluateOnce.tunes_constants
    assert all(METHODS[name].tunes_constants for name in ("oneplusone", "cma", "de", "bo"))


def test_a_registry_refuses_an_unknown_name_listing_the_registered_ones():
    registry: Registry[type] = Registry("widget.name")
    registry.register("b")(int)
    registry.register("a")(float)
    assert registry.chosen("a") is float and list(registry) == ["b", "a"]
    with pytest.raises(ConfigError, match=r"^widget.name must be one of a, b; got 'c'$"):
        registry.chosen("c")


@pytest.mark.parametrize(
    ("make", "message"),
    [
        (lambda: GFOConfig(method="nope"), "gfo.method must be one of bo, cma, de, none, oneplusone; got 'nope'"),
        (lambda: ExecutorConfig(name="nope"), "executor.name must be one of local, ray; got 'nope'"),
        (lambda: TrackerConfig(name="nope"), "tracker.name must be one of mlflow, none; got 'nope'"),
    ],
)
def test_a_bad_component_name_is_one_line_listing_the_registry(make, message):
    with pytest.raises(ConfigError) as error:
        make()
    assert str(error.value) == message


@pytest.mark.parametrize(
    ("overrides", "message"),
    [
        (("gfo=cma", "gfo.method=bo"), "gfo.method=bo needs the bo options: use gfo=bo"),
        (("executor=local", "executor.name=ray"), "executor.name=ray needs the ray options: use executor=ray"),
        (("tracker=none", "tracker.name=mlflow"), "tracker.name=mlflow needs the mlflow options: use tracker=mlflow"),
    ],
)
def test_a_name_whose_options_the_option_file_lacks_is_refused(overrides, message):
    with pytest.raises(ConfigError, match=f"^{message}$"):
        compose("search", *overrides)


def test_a_library_loads_its_module_or_says_how_to_install_it(monkeypatch):
    json_library = Library("json", "JSON", "colmo[json]")
    assert json_library.installed() and json_library.load("x=json").dumps([1]) == "[1]"
    monkeypatch.setitem(sys.modules, "json", None)  # what an uninstalled package looks like to import
    assert not json_library.installed()
    with pytest.raises(ConfigError, match=r"^x=json needs JSON: pip install 'colmo\[json\]'$"):
        json_library.load("x=json")
    with pytest.raises(RuntimeError, match="needs JSON"):
        json_library.load("x=json", RuntimeError)
    assert not Library("colmo_no_such_module", "None", "none").installed()


def test_help_lists_the_registered_names():
    text = help_text("search", "", [])
    assert "the method the gfo option runs: one of bo, cma, de, none, oneplusone" in text
    assert "the executor the executor option runs: one of local, ray" in text


def test_the_option_picks_whether_constants_are_tuned():
    assert not tunes_constants(compose("search", "gfo=none").gfo)
    assert tunes_constants(compose("search", "gfo=de").gfo)


class CountingEvaluator:
    """Evaluations without any program, counted, by either path; every vector scores 1."""

    def __init__(self):
        self.evaluated: list[tuple[float, ...]] = []

    def fast(self, params_list, race=None):
        self.evaluated += [tuple(params) for params in params_list]
        return [Evaluation((1.0,), steps=10) for _ in params_list]

    def referee(self, params):
        return self.fast([params])[0]


def test_evaluate_once_scores_the_constants_as_written_whatever_the_budget():
    counting = CountingEvaluator()
    tuning = tune(counting, [1.5, -2.0], GFOConfig(method="none", budget=50), seed=0)
    assert counting.evaluated == [(1.5, -2.0)]
    assert tuning.params == (1.5, -2.0) and tuning.evaluations == 1 and not tuning.cut_short


def test_executors_are_built_from_their_registry_entry():
    executor = make_executor(ExecutorConfig(workers=3), max_workers=2)
    try:
        assert isinstance(executor, LocalExecutor) and executor.n_workers == 2
    finally:
        executor.close()


def test_no_tracker_records_nothing(tmp_path):
    tracker = make_tracker(TrackerConfig())
    assert isinstance(tracker, NoTracker)
    assert tracker.search_observers(compose("search"), tmp_path) == ()
    assert tracker.record_optimize(compose("optimize", "policy_file=unused.py"), {"score": 1.0}, [], 0.0) is None
