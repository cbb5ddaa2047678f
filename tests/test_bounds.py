"""Comparisons the code decides (`colmo.bounds`): found from literals, functions with known ranges
and a spec's observation bounds, each decision checked against the policy run on observations
within the bounds; what is not certain is never flagged; the best policy's header lists them."""

import ast
import dataclasses

import numpy as np
import pytest

from colmo.bounds import decided_comparisons
from colmo.readability import describe, report
from colmo.record import Summary
from colmo.specs import SpecError, load_spec
from colmo.store import write_outputs

PENDULUM = load_spec("pendulum.py").observation_bounds


def policy(*lines: str) -> str:
    return "import numpy as np\n\ndef policy(obs):\n" + "".join(f"    {line}\n" for line in lines)


def observations(count: int = 5000) -> np.ndarray:
    rng = np.random.default_rng(0)
    theta = rng.uniform(-np.pi, np.pi, count)
    velocity = np.concatenate([rng.normal(0, 5, count - 4), [0.0, -1e6, 1e6, 3.0]])
    return np.stack([np.cos(theta), np.sin(theta), velocity], axis=1)


# The programs and their kin: each test decided, whatever the episode.
DECIDED = [
    (policy("angle = obs[0]", "if abs(angle) < -0.73:", "    return 1.0", "return 0.0"), False, "`abs(angle)` is in [0, 1]"),
    (policy("angle = obs[0]", "if angle < -1.507:", "    return 1.0", "return 0.0"), False, "`angle` is in [-1, 1]"),
    (policy("cos_theta, sin_theta, w = obs", "if cos_theta > 1.5:", "    return 1.0", "return 0.0"), False, "`cos_theta` is in [-1, 1]"),
    (policy("u = np.clip(obs[2], 1.744, -0.8026)", "return 1.0 if u > 0.5 else 0.0"), False, "`u` is always -0.8026"),
    (policy("e = 0.5 * obs[2] ** 2 + 2.0 * (1.0 - obs[0])", "return 1.0 if e >= 0 else 0.0"), True, "`e` is in [0, inf]"),
    (policy("return 1.0 if np.tanh(obs[2]) + np.sin(obs[2]) < 2.5 else 0.0"), True, "is in [-2, 2]"),
    (policy("k = np.sqrt(obs[2] ** 2 + 1.0)", "return 1.0 if k < 0.9 else 0.0"), False, "`k` is in [1, inf]"),
    (policy("return 1.0 if max(obs[1], 2.0) > 1.5 else 0.0"), True, "`max(obs[1], 2.0)` is always 2"),
    (policy("return 1.0 if -0.5 <= obs[0] / 2.0 <= 0.5 else 0.0"), True, "`obs[0] / 2.0` is in [-0.5, 0.5]"),
    (policy("return 1.0 if 2.0 < obs[0] < 5.0 else 0.0"), False, "`obs[0]` is in [-1, 1]"),  # one link never true
]


@pytest.mark.parametrize("code, outcome, why", DECIDED)
def test_a_comparison_the_code_decides_is_found_and_holds_on_every_observation(code, outcome, why):
    (decided,) = decided_comparisons(code, PENDULUM)
    assert decided.outcome is outcome and why in decided.why
    assert str(decided).startswith(f"`{decided.text}` is {'always' if outcome else 'never'} true (") and decided.line >= 4
    namespace: dict = {}
    exec(code, namespace)
    assert {float(namespace["policy"](obs)) for obs in observations()} == {float(outcome)}


# Tests the code does not decide, or that nothing here can bound: never flagged.
UNDECIDED = [
    policy("if obs[0] > 0.5:", "    return 1.0", "return 0.0"),  # a real test within the bounds
    policy("return 1.0 if obs[2] > 100.0 else 0.0"),  # the velocity has no bound
    policy("x = obs[0]", "x = x * 3.0", "return 1.0 if x > 1.5 else 0.0"),  # bound twice: no one value
    policy("obs[0] = 5.0", "return 1.0 if obs[0] > 1.5 else 0.0"),  # written into: the spec's bounds no longer hold
    policy("obs = obs * 4.0", "return 1.0 if obs[0] > 1.5 else 0.0"),  # the observation rebound
    policy("return 1.0 if obs[1] / obs[0] > 1e9 else 0.0"),  # a divisor that can be 0
    policy("return 1.0 if abs(obs[2]) == -1.0 else 0.0"),  # equality: not an ordering
    policy("return 1.0 if -2.0 < obs[0] < 0.5 else 0.0"),  # a chain: one link always true, the other not decided
    policy("return 1.0 if 2.0 > 1.0 else 0.0"),  # literals only: constant folding's, not the program's
    "def cos(x):\n    return 5.0 * x\n\ndef policy(obs):\n    return 1.0 if cos(obs[2]) > 1.5 else 0.0\n",  # not numpy's cos
    policy("np = Helper()", "return 1.0 if np.cos(obs[2]) > 1.5 else 0.0"),  # `np` is not numpy here
    "x = 3.0\n\ndef policy(obs):\n    global x\n    if x > 5.0:\n        return 1.0\n    x = obs[0]\n    return 0.0\n",  # a global
]


@pytest.mark.parametrize("code", UNDECIDED)
def test_what_is_not_certain_is_never_flagged(code):
    assert decided_comparisons(code, PENDULUM) == []


def test_without_bounds_only_what_the_code_itself_fixes_is_decided():
    code = policy("angle = obs[0]", "if abs(angle) < -0.73 or angle < -1.507:", "    return 1.0", "return 0.0")
    assert [d.text for d in decided_comparisons(code)] == ["abs(angle) < -0.73"]
    assert [d.text for d in decided_comparisons(code, PENDULUM)] == ["abs(angle) < -0.73", "angle < -1.507"]
    assert decided_comparisons("def policy(obs):\n    return (", PENDULUM) == [] and decided_comparisons("x = 1", PENDULUM) == []


def test_a_spec_s_observation_bounds_are_checked(tmp_path):
    assert PENDULUM == ((-1.0, 1.0), (-1.0, 1.0), None) and load_spec("cheetah.py").observation_bounds == ()
    source = load_spec("pendulum.py").path.read_text()
    for bad in ("((1.0, -1.0), None, None)", "((-1.0, 1.0, 2.0),)", "(('a', 1.0),)", "5"):
        (tmp_path / "bad.py").write_text(source.replace("OBSERVATION_BOUNDS = ((-1.0, 1.0), (-1.0, 1.0), None)", f"OBSERVATION_BOUNDS = {bad}"))
        with pytest.raises(SpecError, match="OBSERVATION_BOUNDS must"):
            load_spec(str(tmp_path / "bad.py"))


def test_the_quadruped_s_uprightness_stays_in_its_bound_and_the_paper_s_first_branch_is_always_taken(examples):
    spec = load_spec("quadruped.py")
    environment = spec.make_environment(joint_noise=0.05)
    assert len(spec.observation_bounds) == environment.observation_size == 78
    low, high = spec.observation_bounds[47]
    rng = np.random.default_rng(0)
    for seed in range(3):  # flailing at random, tilting it: a cosine stays a cosine
        upright = [environment.reset(seed)[47]] + [environment.step(rng.uniform(-1, 1, 12))[1][47] for _ in range(300)]
        assert low <= min(upright) and max(upright) <= high and min(upright) < 0.99
    published = (examples / "paper_quadruped.py").read_text()
    assert [d.text for d in decided_comparisons(published, spec.observation_bounds)] == ["torso_upright < 1.131"]


def test_the_best_policy_lists_the_comparisons_its_code_decides(tmp_path):
    code = policy("angle = obs[0]", "if abs(angle) < -0.73:", "    return 1.0", "return 0.0")
    decided = tuple(map(str, decided_comparisons(code, PENDULUM)))
    values = dict(task="pendulum", best_score=3.0, best_heldout_score=2.5, best_key="k1", best_code=code, best_so_far=((0, 3.0),),
                  stop_reason="max_samples", run_dir=str(tmp_path), decided=decided)
    required = [f for f in dataclasses.fields(Summary) if f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING]
    summary = Summary(**{f.name: values.get(f.name, 0) for f in required}, **{k: v for k, v in values.items() if k not in {f.name for f in required}})
    write_outputs(summary, tmp_path)
    header = (tmp_path / "best_policy.py").read_text().splitlines()[:2]
    assert header[1] == "# decided by the code: `abs(angle) < -0.73` is never true (`abs(angle)` is in [0, 1])"
    readable = report(code, {}, {}, [], decided)
    assert readable["comparisons_decided"] == 1 and describe(readable).endswith("1 comparison(s) the code decides")


def _random_expression(rng: np.random.Generator, depth: int) -> str:
    if depth == 0 or rng.random() < 0.25:
        return f"obs[{rng.integers(3)}]" if rng.random() < 0.6 else f"{rng.uniform(-3, 3):.3g}"
    a, b = _random_expression(rng, depth - 1), _random_expression(rng, depth - 1)
    forms = [
        f"-({a})", f"abs({a})", f"np.cos({a})", f"np.tanh({a})", f"np.sqrt(abs({a}))", f"np.arctan2({a}, {b})",
        f"np.clip({a}, {rng.uniform(-2, 2):.3g}, {rng.uniform(-2, 2):.3g})", f"({a}) + ({b})", f"({a}) - ({b})",
        f"({a}) * ({b})", f"({a}) ** 2", f"({a}) ** 3", f"max({a}, {b})", f"np.minimum({a}, {b})", f"({a}) / 4.0",
        f"({a}) if ({b}) > 0 else ({b})",
    ]
    return forms[rng.integers(len(forms))]


def test_every_decision_on_random_expressions_holds_on_every_observation():
    rng = np.random.default_rng(1)
    samples = observations(400)
    decided_count = 0
    for _ in range(400):
        op = ["<", "<=", ">", ">="][rng.integers(4)]
        test = f"({_random_expression(rng, 3)}) {op} {rng.uniform(-3, 3):.3g}"
        if rng.random() < 0.3:  # a chain: `c < e < d`
            test = f"{rng.uniform(-3, 3):.3g} {op} {test}"
        code = policy(f"return 1.0 if {test} else 0.0")
        outer = ast.unparse(ast.parse(code).body[1].body[0].value.test)  # the returned test; inner ones may be decided too
        decided = [d for d in decided_comparisons(code, PENDULUM) if d.text == outer]
        if not decided:
            continue
        decided_count += 1
        namespace: dict = {}
        exec(code, namespace)
        with np.errstate(all="ignore"):
            outcomes = {float(namespace["policy"](obs)) for obs in samples}
        assert outcomes == {float(decided[0].outcome)}, (code, str(decided[0]))
    assert decided_count >= 40  # the check saw many decisions, not a handful
