"""The embedded baseline generator, `llm=mutate` (no model, no GPU, no network).

mutate (the default: no model, no GPU, no network) is genetic programming on the AST of the
prompt's programs: the paper's view of generation as a genetic operator (Sec. IV-B) made
literal. A child starts as a copy of one prompt program (the better ones more often) or, with
probability `crossover_rate`, as a crossover of two:
  - merge: run both bodies, then return a blend `0.5 * r1 + 0.5 * r2` of their results or switch
    `r1 if <condition> else r2` between them (swing up with one, balance with the other);
  - splice a statement, or a subexpression, of the second program into the first;
then takes 1..`max_mutations` of these mutations (0.. after a crossover):
  - insert a term: `e` -> `e + c * f`, where a feature `f` is an observation entry `obs[i]`, a
    local variable, a product `obs[i] * obs[j]`, an energy-like `obs[i] ** 2`, an angle
    `np.arctan2(obs[i], obs[j])` or `np.sin/cos/tanh/sign/abs(obs[i])`;
  - where the action is a vector ("Action (shape (K,))" or "return shape is (K,)" in the prompt), insert an actuator
    term into what the policy returns: `e` -> `e + np.array([c1, ..., cK]) * f`, a gain per
    actuator (every other term gives all actuators the same value); with `llm.joint_terms=true`
    also a joint term `e + c * np.eye(K)[j] * f`, one actuator's gain (one constant where the
    other has K, for a search capped by `database.max_constants`);
  - replace a subexpression with a new term: `c * f`, or linear (PD) feedback
    `c1 * obs[i] + c2 * obs[j]`;
  - wrap a subexpression: `np.sin/cos/tanh/sign/abs(e)` or `np.clip(e, -c1, c2)`;
  - hoist: replace a subexpression with one of its own (the counterweight to growth);
  - add a branch: `x = e` -> `if <condition>: x = e else: x = e'` (also for `return`), where the
    condition thresholds an observation entry, a feature or its absolute value, and `e'` is a
    new term or `e` with a term inserted;
  - remove a branch (keep its `if` or its `else` side), delete or swap statements;
  - change an arithmetic operator (+ - * /) or flip a comparison (< to >, <= to >=, == to !=);
  - redraw one constant (log-uniform from 0.1 to 10).
New constants get random signs and plausible magnitudes: the GFO tunes them afterwards.
Observation indices stay below the observation size, read from "obs size is N" or "Observation
(size N)" in the prompt, else from the indices the programs read. A candidate is redrawn unless
its structure key (`colmo.program`: the search's duplicate test) differs from its parents' and
its siblings', and it passes the `probe` it was given: in a search, `colmo.generate.probe.ProgramProbe`
runs it for the first control steps of the task in a sandbox worker (programs never run in this
process) and wants valid actions. After `llm.attempts` redraws the child is a parent with its
constants perturbed by a relative gaussian of `constant_sigma`, a duplicate the search skips.
"""

from __future__ import annotations

import ast
import copy
import re
import time
from typing import Optional

import numpy as np

from colmo import astutil
from colmo.config import MutateConfig
from colmo.generate.base import GENERATORS, Generation, Generator, GeneratorError, Probe, logger
from colmo.generate.operators import ACTUATOR_MUTATIONS, CROSSOVERS, JOINT_MUTATIONS, MUTATIONS, Pieces, policy_function
from colmo.program import DISPLAY_DIGITS, ProgramError, instantiate, parametrize
from colmo.prompt import Prompt

_OBS_SIZE = re.compile(r"obs\w*\s*(?:size is|\(size)\s*(\d+)", re.IGNORECASE)
# A task's text says "Action (shape (6,))", a starter's docstring "return shape is (6,)".
_ACTION_SIZE = re.compile(r"(?:return shape is|action \(shape) \((\d+),\)", re.IGNORECASE)


class _Parent:
    """A prompt program, parsed."""

    def __init__(self, code: str):
        self.code = code
        self.key = parametrize(code).key  # ProgramError unless it parses and defines `policy`
        self.tree = astutil.parse(code)
        self.fn = policy_function(self.tree)
        if not any(a.name == "numpy" for n in self.tree.body if isinstance(n, ast.Import) for a in n.names):
            self.tree.body.insert(0, astutil.parse("import numpy as np").body[0])  # for the new terms' np.*


@GENERATORS.register("mutate")
class MutateGenerator(Generator):
    """The embedded baseline: genetic programming on the prompt's programs (module docstring)."""

    options = MutateConfig
    wants_probe = True

    def __init__(self, cfg: MutateConfig, seed: int, probe: Optional[Probe] = None):
        super().__init__(cfg, seed, probe)
        self.rng = np.random.default_rng(seed)
        # The operators and their probabilities for a scalar action (False) and a vector one (True).
        vector_mutations = ACTUATOR_MUTATIONS + (JOINT_MUTATIONS if cfg.joint_terms else ())
        self._mutations = {vector: _weighted(MUTATIONS + (vector_mutations if vector else ())) for vector in (False, True)}

    def cores(self) -> int:
        return 1  # it mutates, and probes its children, in the search's thread

    def generate(self, prompt: Prompt, n: int) -> list[Generation]:
        parents = []
        for code in prompt.programs:
            try:
                parents.append(_Parent(code))
            except ProgramError:
                logger.debug("mutate: skipping a prompt program without a parsable `def policy`")
        if not parents:
            raise GeneratorError("mutate: none of the prompt's programs parses with a `def policy(obs)`")
        text = "\n".join([prompt.text, *prompt.programs])
        stated, actions = _OBS_SIZE.search(text), _ACTION_SIZE.search(text)
        pieces = Pieces(self.rng, parents, int(stated.group(1)) if stated else None, int(actions.group(1)) if actions else 1)
        # Probing a child only says something if its parents pass the probe themselves.
        probe = self.probe if self.probe is not None and all(self.probe(p.code) for p in parents) else None
        seen = {parent.key for parent in parents}
        generations = []
        for _ in range(n):
            start = time.perf_counter()
            code, key = self._child(parents, pieces, seen, probe)
            seen.add(key)
            generations.append(Generation(code, "mutate", seconds=time.perf_counter() - start))
        return generations

    def _child(
        self, parents: list[_Parent], pieces: Pieces, seen: set[str], probe: Optional[Probe]
    ) -> tuple[str, str]:
        """A child's code and structure key: a new structure that passes the probe."""
        for _ in range(self.cfg.attempts):
            parent, tree = self._offspring(parents, pieces)
            code = ast.unparse(tree) + "\n"
            key = parametrize(code).key
            if key in seen:
                continue
            if probe is None or probe(code):
                return code, key
        logger.debug("mutate: no new working structure in %d attempts; perturbing constants", self.cfg.attempts)
        parent = self._choose(parents, 1)[0]
        return self._perturbed(parent), parent.key

    def _offspring(self, parents: list[_Parent], pieces: Pieces) -> tuple[_Parent, ast.Module]:
        """A crossover or a copy of a parent, then mutated; also the parent whose action shape
        the child must keep."""
        mutations = int(self.rng.integers(1, self.cfg.max_mutations + 1))
        if len(parents) > 1 and self.rng.random() < self.cfg.crossover_rate:
            first, second = self._choose(parents, 2)
            tree = copy.deepcopy(first.tree)
            if pieces.pick(CROSSOVERS)(policy_function(tree), second.fn, pieces):
                mutations = int(self.rng.integers(0, self.cfg.max_mutations + 1))
        else:
            first = self._choose(parents, 1)[0]
            tree = copy.deepcopy(first.tree)
        fn = policy_function(tree)
        operators, weights = self._mutations[pieces.action_size > 1]
        for _ in range(mutations):
            # Operators in a weighted random order: the first one that applies does.
            for i in self.rng.choice(len(operators), size=len(operators), replace=False, p=weights):
                if operators[i](fn, pieces):
                    break
        return first, tree

    def _choose(self, parents: list[_Parent], k: int) -> list[_Parent]:
        """`k` distinct parents, favouring the better ones (the prompt lists them worst first)."""
        weights = np.arange(1, len(parents) + 1, dtype=float)
        return [parents[i] for i in self.rng.choice(len(parents), size=k, replace=False, p=weights / weights.sum())]

    def _perturbed(self, parent: _Parent) -> str:
        program = parametrize(parent.code)
        values = np.array(program.values) * (1.0 + self.cfg.constant_sigma * self.rng.standard_normal(program.n_params))
        return instantiate(program.skeleton, values, digits=DISPLAY_DIGITS) + "\n"


def _weighted(mutations: tuple) -> tuple[tuple, np.ndarray]:
    """The operators of `(operator, weight)` pairs and their probabilities."""
    operators, weights = zip(*mutations)
    return operators, np.array(weights) / sum(weights)
