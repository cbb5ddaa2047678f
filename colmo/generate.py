"""Producing candidate programs from a prompt: the embedded mutation baseline, OpenAI-compatible
servers, in-process vLLM, behind one interface and a registry.

A `Generator` turns one `Prompt` into `n` raw texts (`Generation`s, `n` = `llm.batch_size`);
pulling the policy out of a model's answer is the search loop's job (`colmo.extract`).
`make_generator(cfg.llm, seed)` builds the one named by `llm.name` from `GENERATORS`.

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
its siblings', and it passes the `probe` it was given: in a search, `colmo.sandbox.ProgramProbe`
runs it for the first control steps of the task in a sandbox worker (programs never run in this
process) and wants valid actions. After `_ATTEMPTS` redraws the child is a parent with its
constants perturbed by a relative gaussian of `constant_sigma`, a duplicate the search skips.

openai talks to any OpenAI-compatible chat-completions endpoint (vllm serve, Ollama, llama.cpp,
OpenAI) with the official client. It asks for `n` choices in one request when `use_n`; a
server that returns fewer is asked one completion per request from then on, in parallel.
Retries are its own (visible in the log, configurable): connection errors, timeouts, HTTP 408,
409, 429, 5xx and unusable answers are retried with exponential backoff and full jitter, up to
`max_retries` times per request; a request that runs out of retries is dropped, so a batch can
come back short. Requests go round robin over `base_url`, skipping a server for
`max_backoff_s` after it fails. `max_consecutive_failures` failed attempts in a row, over all
servers, or any other HTTP error (a wrong model name, a bad key), raise `GeneratorError`.

vllm runs `vllm.LLM` in this process (`pip install 'colmo[vllm]'`) and samples the batch as the
`n` outputs of one request through the model's chat template.
"""

from __future__ import annotations

import abc
import ast
import copy
import itertools
import logging
import os
import random
import re
import threading
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Callable, Optional, Sequence

import numpy as np
import openai

from colmo.config import ConfigError, GeneratorConfig, MutateConfig, OpenAIConfig, VLLMConfig, one_line
from colmo.program import ProgramError, instantiate, parametrize

if TYPE_CHECKING:
    from colmo.prompt import Prompt

logger = logging.getLogger("colmo.generate")


@dataclass(frozen=True)
class Generation:
    text: str  # raw output: code from mutate, a model's whole answer otherwise
    generator: str  # "mutate", "openai:<model>@<url>", "vllm:<model>"
    prompt_tokens: int = 0
    completion_tokens: int = 0
    seconds: float = 0.0


class GeneratorError(RuntimeError):
    """The generator cannot go on (no server answers, a request is refused, a library is
    missing); the message is one line."""


class Generator(abc.ABC):
    @abc.abstractmethod
    def generate(self, prompt: Prompt, n: int) -> list[Generation]:
        """Up to `n` candidate programs for `prompt`."""

    def close(self) -> None:
        """Release connections, threads or GPU memory."""


def _batch(
    texts: Sequence[str], generator: str, prompt_tokens: int, completion_tokens: Sequence[int], seconds: float
) -> list[Generation]:
    """The generations of one request. Its prompt is counted on the first only and its time is
    split evenly, so that sums over generations are the request's totals."""
    return [
        Generation(text, generator, prompt_tokens if i == 0 else 0, completion, seconds / len(texts))
        for i, (text, completion) in enumerate(zip(texts, completion_tokens))
    ]


# --------------------------------------------------------------------------------------------
# mutate: genetic operators on the program AST

_FUNCTIONS = ("sin", "cos", "tanh", "sign", "abs")
_ARITHMETIC = (ast.Add, ast.Sub, ast.Mult, ast.Div)
_FLIPPED = {ast.Lt: ast.Gt, ast.Gt: ast.Lt, ast.LtE: ast.GtE, ast.GtE: ast.LtE, ast.Eq: ast.NotEq, ast.NotEq: ast.Eq}
_VALUE_KINDS = (ast.BinOp, ast.Call, ast.Name, ast.Attribute, ast.Subscript, ast.IfExp)
# Fields whose subtrees are not values to rewrite: indices, called functions, attribute owners.
_OPAQUE_FIELDS = {(ast.Subscript, "slice"), (ast.Subscript, "value"), (ast.Call, "func"), (ast.Attribute, "value")}
_OBS_SIZE = re.compile(r"obs\w*\s*(?:size is|\(size)\s*(\d+)", re.IGNORECASE)
_ATTEMPTS = 40


def _is_number(node: ast.AST) -> bool:
    return isinstance(node, ast.Constant) and type(node.value) in (int, float)


def _is_value(node: ast.AST, parent: ast.AST) -> bool:
    if isinstance(node, ast.Constant):
        # Integers handed to calls are sizes, counts and axes, not values.
        return _is_number(node) and not (type(node.value) is int and isinstance(parent, (ast.Call, ast.keyword)))
    if isinstance(node, ast.UnaryOp):
        return not isinstance(node.op, ast.Not)
    return isinstance(node, _VALUE_KINDS) and isinstance(getattr(node, "ctx", ast.Load()), ast.Load)


def _value_nodes(root: ast.AST) -> list[ast.expr]:
    """Expressions a mutation may rewrite, in source order: numeric values, but no indices,
    called functions, attribute owners, assignment targets or sizes."""
    found = []

    def visit(node: ast.AST) -> None:
        for field, value in ast.iter_fields(node):
            if (type(node), field) in _OPAQUE_FIELDS:
                continue
            for child in value if isinstance(value, list) else [value]:
                if isinstance(child, ast.AST):
                    if _is_value(child, node):
                        found.append(child)
                    visit(child)

    visit(root)
    return found


def _policy(tree: ast.Module) -> ast.FunctionDef:
    return next(node for node in tree.body if isinstance(node, ast.FunctionDef) and node.name == "policy")


def _replace(root: ast.AST, old: ast.AST, new: ast.AST) -> None:
    class Replace(ast.NodeTransformer):
        def visit(self, node: ast.AST) -> ast.AST:
            return new if node is old else self.generic_visit(node)

    Replace().visit(root)


def _is_docstring(statement: ast.stmt) -> bool:
    return isinstance(statement, ast.Expr) and isinstance(statement.value, ast.Constant) and isinstance(statement.value.value, str)


def _statement_lists(fn: ast.FunctionDef) -> list[list[ast.stmt]]:
    """Every block of statements in the function: its body and those of its ifs and loops."""
    return [
        block
        for node in ast.walk(fn)
        for block in (getattr(node, "body", None), getattr(node, "orelse", None))
        if isinstance(block, list) and block and isinstance(block[0], ast.stmt)
    ]


class _Parent:
    """A prompt program, parsed."""

    def __init__(self, code: str):
        self.code = code
        self.key = parametrize(code).key  # ProgramError unless it parses and defines `policy`
        self.tree = ast.parse(code)
        self.fn = _policy(self.tree)
        if not any(a.name == "numpy" for n in self.tree.body if isinstance(n, ast.Import) for a in n.names):
            self.tree.body.insert(0, ast.parse("import numpy as np").body[0])  # for the new terms' np.*


class _Pieces:
    """Random code fragments for the children of one prompt, written with the names and
    observation entries its programs use."""

    def __init__(self, rng: np.random.Generator, parents: Sequence[_Parent], stated_obs_size: Optional[int]):
        self.rng = rng
        self.obs = parents[0].fn.args.args[0].arg if parents[0].fn.args.args else "obs"
        imports = [a for n in parents[0].tree.body if isinstance(n, ast.Import) for a in n.names]
        self.np = next(a.asname or a.name for a in imports if a.name == "numpy")
        seen = sorted({
            n.slice.value
            for p in parents
            for n in ast.walk(p.fn)
            if isinstance(n, ast.Subscript) and isinstance(n.value, ast.Name) and n.value.id == self.obs
            and _is_number(n.slice) and type(n.slice.value) is int  # obs[-1] is a UnaryOp: left out
        })
        self.obs_size = stated_obs_size or 1 + max(seen, default=0)
        self.indices = range(self.obs_size) if stated_obs_size else seen or [0]
        self.names = sorted({
            n.id for p in parents for n in ast.walk(p.fn) if isinstance(n, ast.Name) and isinstance(n.ctx, ast.Store)
        })

    def pick(self, items: Sequence[Any]) -> Any:
        return items[self.rng.integers(len(items))] if len(items) else None

    def magnitude(self, high: float = 1.0) -> str:
        """A positive constant from 0.1 to 10**high, log-uniform, to 3 significant digits."""
        return repr(float(f"{10 ** self.rng.uniform(-1.0, high):.3g}"))

    def entries(self, k: int) -> list[str]:
        """`k` observation entries, distinct where there are enough."""
        indices = self.rng.choice(self.indices, size=k, replace=len(self.indices) < k)
        return [f"{self.obs}[{i}]" for i in indices]

    def feature(self) -> str:
        # Weighted toward plain entries: linear feedback is the backbone of most controllers.
        kind = self.pick(["entry"] * 3 + ["function"] * 2 + ["product", "square", "angle"] + ["name"] * bool(self.names))
        first, second = self.entries(2)
        if kind == "function":
            return f"{self.np}.{self.pick(_FUNCTIONS)}({first})"
        if kind == "product":
            return f"{first} * {second}"
        if kind == "square":
            return f"{first} ** 2"
        if kind == "angle":
            return f"{self.np}.arctan2({first}, {second})"
        return self.pick(self.names) if kind == "name" else first

    def sign(self) -> str:
        return self.pick(("", "-"))

    def term(self) -> ast.expr:
        """`c * feature`, or linear feedback on two entries `c1 * obs[i] + c2 * obs[j]` (PD)."""
        if self.rng.random() < 0.4:
            first, second = self.entries(2)
            return _expression(f"{self.sign()}{self.magnitude()} * {first} {self.pick('+-')} {self.magnitude()} * {second}")
        return _expression(f"{self.sign()}{self.magnitude()} * {self.feature()}")

    def extended(self, node: ast.expr) -> ast.expr:
        """`node + c * feature` or `node - c * feature`."""
        return ast.BinOp(node, self.pick((ast.Add, ast.Sub))(), _expression(f"{self.magnitude()} * {self.feature()}"))

    def condition(self) -> ast.expr:
        """A threshold on an observation entry (half the time) or another feature, or on its
        absolute value; thresholds from 0.1 to 2, the scale of angles, cosines, velocities."""
        [entry] = self.entries(1)
        x = entry if self.rng.random() < 0.5 else self.feature()
        if self.rng.random() < 0.3:
            return _expression(f"{self.np}.abs({x}) {self.pick('<>')} {self.magnitude(high=0.3)}")
        return _expression(f"{x} {self.pick('<>')} {self.sign()}{self.magnitude(high=0.3)}")

    def wrapped(self, node: ast.expr) -> ast.expr:
        function = self.pick(_FUNCTIONS + ("clip",))
        bounds = f", -{self.magnitude()}, {self.magnitude()}" if function == "clip" else ""
        return _expression(f"{self.np}.{function}({ast.unparse(node)}{bounds})")


def _expression(source: str) -> ast.expr:
    return ast.parse(source, mode="eval").body


# Each mutation edits the policy function in place and says whether it found something to edit.

def _insert_term(fn: ast.FunctionDef, pieces: _Pieces) -> bool:
    target = pieces.pick(_value_nodes(fn))
    if target is None:
        return False
    _replace(fn, target, pieces.extended(target))
    return True


def _replace_subtree(fn: ast.FunctionDef, pieces: _Pieces) -> bool:
    target = pieces.pick(_value_nodes(fn))
    if target is None:
        return False
    _replace(fn, target, pieces.term())
    return True


def _wrap(fn: ast.FunctionDef, pieces: _Pieces) -> bool:
    target = pieces.pick([node for node in _value_nodes(fn) if not isinstance(node, ast.Constant)])
    if target is None:
        return False
    _replace(fn, target, pieces.wrapped(target))
    return True


def _hoist(fn: ast.FunctionDef, pieces: _Pieces) -> bool:
    """Replace an expression with one of its own subexpressions: the counterweight to growth."""
    nodes = [(node, inner) for node in _value_nodes(fn) if (inner := _value_nodes(node))]
    if not nodes:
        return False
    node, inner = pieces.pick(nodes)
    _replace(fn, node, pieces.pick(inner))
    return True


def _add_branch(fn: ast.FunctionDef, pieces: _Pieces) -> bool:
    blocks = [
        (block, i) for block in _statement_lists(fn)
        for i, s in enumerate(block) if isinstance(s, (ast.Assign, ast.AugAssign, ast.Return)) and s.value
    ]
    if not blocks:
        return False
    block, i = pieces.pick(blocks)
    other = copy.deepcopy(block[i])
    other.value = pieces.term() if pieces.rng.random() < 0.5 else pieces.extended(other.value)
    block[i] = ast.If(pieces.condition(), [block[i]], [other])
    return True


def _remove_branch(fn: ast.FunctionDef, pieces: _Pieces) -> bool:
    branches = [(block, i) for block in _statement_lists(fn) for i, s in enumerate(block) if isinstance(s, ast.If)]
    if not branches:
        return False
    block, i = pieces.pick(branches)
    sides = [side for side in (block[i].body, block[i].orelse) if side]
    block[i:i + 1] = pieces.pick(sides)
    return True


def _delete_statement(fn: ast.FunctionDef, pieces: _Pieces) -> bool:
    candidates = [
        (block, i) for block in _statement_lists(fn) if len(block) > 1
        for i, s in enumerate(block) if not isinstance(s, ast.Return) and not _is_docstring(s)
    ]
    if not candidates:
        return False
    block, i = pieces.pick(candidates)
    del block[i]
    return True


def _swap_statements(fn: ast.FunctionDef, pieces: _Pieces) -> bool:
    pairs = [
        (block, i) for block in _statement_lists(fn) for i in range(len(block) - 1)
        if not any(isinstance(s, ast.Return) or _is_docstring(s) for s in block[i:i + 2])
    ]
    if not pairs:
        return False
    block, i = pieces.pick(pairs)
    block[i], block[i + 1] = block[i + 1], block[i]
    return True


def _change_operator(fn: ast.FunctionDef, pieces: _Pieces) -> bool:
    nodes = [n for n in ast.walk(fn) if isinstance(n, (ast.BinOp, ast.AugAssign)) and isinstance(n.op, _ARITHMETIC)]
    if not nodes:
        return False
    node = pieces.pick(nodes)
    node.op = pieces.pick([op for op in _ARITHMETIC if not isinstance(node.op, op)])()
    return True


def _flip_comparison(fn: ast.FunctionDef, pieces: _Pieces) -> bool:
    nodes = [n for n in ast.walk(fn) if isinstance(n, ast.Compare) and type(n.ops[0]) in _FLIPPED]
    if not nodes:
        return False
    node = pieces.pick(nodes)
    node.ops[0] = _FLIPPED[type(node.ops[0])]()
    return True


def _redraw_constant(fn: ast.FunctionDef, pieces: _Pieces) -> bool:
    constant = pieces.pick([node for node in _value_nodes(fn) if _is_number(node)])
    if constant is None:
        return False
    constant.value = float(pieces.magnitude())
    return True


# (operator, weight): terms and branches build controllers; hoisting and deleting keep them short.
_MUTATIONS = (
    (_insert_term, 3.0),
    (_replace_subtree, 2.0),
    (_add_branch, 2.0),
    (_wrap, 1.0),
    (_hoist, 1.5),
    (_remove_branch, 1.0),
    (_delete_statement, 1.0),
    (_swap_statements, 0.5),
    (_change_operator, 1.0),
    (_flip_comparison, 1.0),
    (_redraw_constant, 0.5),
)


# Each crossover edits a copy of the first program's policy, taking material from the second's.

def _merge(fn: ast.FunctionDef, other: ast.FunctionDef, pieces: _Pieces) -> bool:
    """Run both bodies (the second's variables renamed where they clash), then blend or switch
    between the two results."""
    def single_return(f: ast.FunctionDef) -> bool:
        returns = [n for n in ast.walk(f) if isinstance(n, ast.Return)]
        return len(returns) == 1 and f.body[-1] is returns[0] and returns[0].value is not None

    if not (single_return(fn) and single_return(other)):
        return False
    used = {n.id for n in ast.walk(fn) if isinstance(n, ast.Name)}
    clashes = used & {n.id for n in ast.walk(other) if isinstance(n, ast.Name) and isinstance(n.ctx, ast.Store)}
    body = copy.deepcopy(other.body)
    for node in ast.walk(ast.Module(body, [])):
        if isinstance(node, ast.Name) and node.id in clashes:
            node.id += "_b"
    first, second = fn.body[-1].value, body[-1].value
    if pieces.rng.random() < 0.5:
        result = _expression(f"0.5 * ({ast.unparse(first)}) + 0.5 * ({ast.unparse(second)})")
    else:
        result = ast.IfExp(pieces.condition(), first, second)
    fn.body[-1:] = [s for s in body[:-1] if not _is_docstring(s)] + [ast.Return(result)]
    return True


def _splice_statement(fn: ast.FunctionDef, other: ast.FunctionDef, pieces: _Pieces) -> bool:
    statements = [s for s in other.body if not isinstance(s, ast.Return) and not _is_docstring(s)]
    if not statements:
        return False
    block = pieces.pick(_statement_lists(fn))
    first, end = int(_is_docstring(block[0])), len(block) - isinstance(block[-1], ast.Return)
    block.insert(int(pieces.rng.integers(first, end + 1)), copy.deepcopy(pieces.pick(statements)))
    return True


def _splice_expression(fn: ast.FunctionDef, other: ast.FunctionDef, pieces: _Pieces) -> bool:
    target, donor = pieces.pick(_value_nodes(fn)), pieces.pick(_value_nodes(other))
    if target is None or donor is None:
        return False
    _replace(fn, target, copy.deepcopy(donor))
    return True


_CROSSOVERS = (_merge, _splice_statement, _splice_expression)


class MutateGenerator(Generator):
    """The embedded baseline: genetic programming on the prompt's programs (module docstring)."""

    def __init__(self, cfg: MutateConfig, seed: int, probe: Optional[Callable[[str], bool]] = None):
        self.cfg = cfg
        self.probe = probe
        self.rng = np.random.default_rng(seed)
        operators, weights = zip(*_MUTATIONS)
        self._mutations = operators
        self._weights = np.array(weights) / sum(weights)

    def generate(self, prompt: Prompt, n: int) -> list[Generation]:
        parents = []
        for code in prompt.programs:
            try:
                parents.append(_Parent(code))
            except ProgramError:
                logger.debug("mutate: skipping a prompt program without a parsable `def policy`")
        if not parents:
            raise GeneratorError("mutate: none of the prompt's programs parses with a `def policy(obs)`")
        stated = _OBS_SIZE.search("\n".join([prompt.text, *prompt.programs]))
        pieces = _Pieces(self.rng, parents, int(stated.group(1)) if stated else None)
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
        self, parents: list[_Parent], pieces: _Pieces, seen: set[str], probe: Optional[Callable[[str], bool]]
    ) -> tuple[str, str]:
        """A child's code and structure key: a new structure that passes the probe."""
        for _ in range(_ATTEMPTS):
            parent, tree = self._offspring(parents, pieces)
            code = ast.unparse(tree) + "\n"
            key = parametrize(code).key
            if key in seen:
                continue
            if probe is None or probe(code):
                return code, key
        logger.debug("mutate: no new working structure in %d attempts; perturbing constants", _ATTEMPTS)
        parent = self._choose(parents, 1)[0]
        return self._perturbed(parent), parent.key

    def _offspring(self, parents: list[_Parent], pieces: _Pieces) -> tuple[_Parent, ast.Module]:
        """A crossover or a copy of a parent, then mutated; also the parent whose action shape
        the child must keep."""
        mutations = int(self.rng.integers(1, self.cfg.max_mutations + 1))
        if len(parents) > 1 and self.rng.random() < self.cfg.crossover_rate:
            first, second = self._choose(parents, 2)
            tree = copy.deepcopy(first.tree)
            if pieces.pick(_CROSSOVERS)(_policy(tree), second.fn, pieces):
                mutations = int(self.rng.integers(0, self.cfg.max_mutations + 1))
        else:
            first = self._choose(parents, 1)[0]
            tree = copy.deepcopy(first.tree)
        fn = _policy(tree)
        for _ in range(mutations):
            # Operators in a weighted random order: the first one that applies does.
            for i in self.rng.choice(len(self._mutations), size=len(self._mutations), replace=False, p=self._weights):
                if self._mutations[i](fn, pieces):
                    break
        return first, tree

    def _choose(self, parents: list[_Parent], k: int) -> list[_Parent]:
        """`k` distinct parents, favouring the better ones (the prompt lists them worst first)."""
        weights = np.arange(1, len(parents) + 1, dtype=float)
        return [parents[i] for i in self.rng.choice(len(parents), size=k, replace=False, p=weights / weights.sum())]

    def _perturbed(self, parent: _Parent) -> str:
        program = parametrize(parent.code)
        values = np.array(program.values) * (1.0 + self.cfg.constant_sigma * self.rng.standard_normal(program.n_params))
        return instantiate(program.skeleton, values, digits=4) + "\n"


# --------------------------------------------------------------------------------------------
# openai: any OpenAI-compatible chat-completions server

_RETRYABLE_STATUS = frozenset({408, 409, 429})


class _UnusableAnswer(ValueError):
    """A 200 answer with no completion text in it."""


def _texts(response: Any) -> list[str]:
    """The non-empty completion texts of an answer; `_UnusableAnswer` if there are none (servers
    and proxies can answer 200 with HTML, an error object or empty choices)."""
    choices = getattr(response, "choices", None) or []
    texts = [getattr(getattr(choice, "message", None), "content", None) for choice in choices]
    texts = [text for text in texts if isinstance(text, str) and text.strip()]
    if not texts:
        raise _UnusableAnswer(f"no completion text in the answer ({len(choices)} choices)")
    return texts


def _split(total: int, parts: int) -> list[int]:
    return [total // parts + (i < total % parts) for i in range(parts)]


def _describe(error: BaseException) -> str:
    cause = f" ({one_line(error.__cause__)})" if error.__cause__ else ""
    return f"{type(error).__name__}: {one_line(error)}{cause}"


class _Server:
    def __init__(self, url: str, client: openai.OpenAI):
        self.url = url
        self.client = client
        self.failed_at = -float("inf")


class OpenAIGenerator(Generator):
    """Chat completions from OpenAI-compatible servers, with our own retries and failover."""

    def __init__(self, cfg: OpenAIConfig, seed: int):
        self.cfg = cfg
        api_key = os.environ.get(cfg.api_key_env) or "EMPTY"  # local servers want no key, the client wants one
        self._servers = [
            _Server(url, openai.OpenAI(base_url=url, api_key=api_key, timeout=cfg.timeout_s, max_retries=0))
            for url in cfg.base_url
        ]
        self._turn = itertools.count()
        self._lock = threading.Lock()
        self._failures = 0  # consecutive failed attempts, all servers together
        self._use_n = cfg.use_n
        self._seeds = random.Random(seed)
        self._pool = ThreadPoolExecutor(max_workers=cfg.batch_size, thread_name_prefix="colmo-openai")

    def generate(self, prompt: Prompt, n: int) -> list[Generation]:
        generations = self._complete(prompt.messages, n, self._seeds.randrange(2**31)) if self._use_n and n > 1 else []
        seeds = [self._seeds.randrange(2**31) for _ in range(n - len(generations))]
        for batch in self._pool.map(lambda seed: self._complete(prompt.messages, 1, seed), seeds):
            generations += batch
        return generations

    def close(self) -> None:
        self._pool.shutdown(wait=False, cancel_futures=True)
        for server in self._servers:
            server.client.close()

    def _complete(self, messages: list[dict[str, str]], n: int, seed: int) -> list[Generation]:
        """One request, retried; its generations, or none once its retries are spent."""
        cfg = self.cfg
        for attempt in range(cfg.max_retries + 1):
            server = self._pick_server()
            start = time.perf_counter()
            try:
                response = server.client.chat.completions.create(
                    model=cfg.model, messages=messages, temperature=cfg.temperature, top_p=cfg.top_p,
                    max_tokens=cfg.max_tokens, seed=seed, **({"n": n} if n > 1 else {}),
                )
                texts = _texts(response)
            except openai.APIStatusError as error:
                if error.status_code not in _RETRYABLE_STATUS and error.status_code < 500:
                    message = f"{server.url} refused the request: HTTP {error.status_code}: {one_line(error)}"
                    raise GeneratorError(message) from None
                reason = self._failed(server, error)
            except (openai.APIConnectionError, openai.APIResponseValidationError, ValueError) as error:
                # ValueError: a body that is not JSON, or `_UnusableAnswer`.
                reason = self._failed(server, error)
            else:
                return self._succeeded(server, response, texts, n, time.perf_counter() - start)
            if attempt < cfg.max_retries:
                # Full jitter: requests that failed together do not all come back together.
                delay = random.uniform(0.0, min(cfg.max_backoff_s, cfg.backoff_s * 2**attempt))
                logger.warning(
                    "openai: %s failed (%s); retry %d/%d in %.3fs", server.url, reason, attempt + 1, cfg.max_retries, delay
                )
                time.sleep(delay)
        logger.warning("openai: dropping a request after %d attempts; the last failed with %s", cfg.max_retries + 1, reason)
        return []

    def _pick_server(self) -> _Server:
        """Round robin over the servers that have not failed in the last `max_backoff_s`; if all
        have, the one that failed longest ago."""
        with self._lock:
            now = time.monotonic()
            for _ in range(len(self._servers)):
                server = self._servers[next(self._turn) % len(self._servers)]
                if now - server.failed_at >= self.cfg.max_backoff_s:
                    return server
            return min(self._servers, key=lambda s: s.failed_at)

    def _failed(self, server: _Server, error: BaseException) -> str:
        """Record a failed attempt; its reason, or `GeneratorError` once too many failed in a row."""
        reason = _describe(error)
        with self._lock:
            server.failed_at = time.monotonic()
            self._failures += 1
            failures = self._failures
        if failures >= self.cfg.max_consecutive_failures:
            raise GeneratorError(f"no OpenAI-compatible server answered after {failures} attempts: {reason}") from error
        return reason

    def _succeeded(self, server: _Server, response: Any, texts: list[str], n: int, seconds: float) -> list[Generation]:
        with self._lock:
            self._failures = 0
            server.failed_at = -float("inf")
            if n > 1 and len(response.choices) < n and self._use_n:
                self._use_n = False
                logger.warning(
                    "openai: %s returned %d choices for n=%d; asking for one completion per request from now on",
                    server.url, len(response.choices), n,
                )
        usage = getattr(response, "usage", None)
        prompt_tokens = getattr(usage, "prompt_tokens", 0) or 0
        completion_tokens = getattr(usage, "completion_tokens", 0) or 0
        logger.info(
            "openai: %s: %d completions, %d prompt + %d completion tokens, %.1fs",
            server.url, len(texts), prompt_tokens, completion_tokens, seconds,
        )
        name = f"openai:{self.cfg.model}@{server.url}"
        return _batch(texts, name, prompt_tokens, _split(completion_tokens, len(texts)), seconds)


# --------------------------------------------------------------------------------------------
# vllm: in-process batched generation on local GPUs

class VLLMGenerator(Generator):
    """`vllm.LLM` in this process; the batch is the `n` outputs of one chat request."""

    def __init__(self, cfg: VLLMConfig, seed: int):
        try:
            import vllm
        except ImportError:
            raise GeneratorError("llm=vllm needs vLLM: pip install 'colmo[vllm]'") from None
        self.cfg = cfg
        self.name = f"vllm:{cfg.model}"
        self._sampling_params = vllm.SamplingParams
        # The engine seed is the config's; each request gets its own seed, or the same prompt
        # would be answered with the same batch every time.
        self._seeds = random.Random(seed)
        try:
            self._llm = vllm.LLM(
                model=cfg.model, quantization=cfg.quantization, dtype=cfg.dtype,
                tensor_parallel_size=cfg.tensor_parallel_size, pipeline_parallel_size=cfg.pipeline_parallel_size,
                gpu_memory_utilization=cfg.gpu_memory_utilization, max_model_len=cfg.max_model_len, seed=cfg.seed,
            )
        except Exception as error:  # CUDA, download, memory and argument errors all end the run
            raise GeneratorError(f"vLLM could not load {cfg.model}: {_describe(error)}") from error

    def generate(self, prompt: Prompt, n: int) -> list[Generation]:
        cfg = self.cfg
        params = self._sampling_params(
            n=n, temperature=cfg.temperature, top_p=cfg.top_p, max_tokens=cfg.max_tokens, seed=self._seeds.randrange(2**31)
        )
        start = time.perf_counter()
        [output] = self._llm.chat(prompt.messages, sampling_params=params, use_tqdm=False)
        seconds = time.perf_counter() - start
        prompt_tokens = len(output.prompt_token_ids or ())
        completion_tokens = [len(completion.token_ids) for completion in output.outputs]
        logger.info(
            "vllm: %d completions, %d prompt + %d completion tokens, %.1fs",
            len(output.outputs), prompt_tokens, sum(completion_tokens), seconds,
        )
        return _batch([completion.text for completion in output.outputs], self.name, prompt_tokens, completion_tokens, seconds)

    def close(self) -> None:
        self._llm = None  # the engine frees its GPU memory when collected


GENERATORS: dict[str, Callable[[Any, int], Generator]] = {
    "mutate": MutateGenerator,
    "openai": OpenAIGenerator,
    "vllm": VLLMGenerator,
}


def make_generator(cfg: GeneratorConfig, seed: int, probe: Optional[Callable[[str], bool]] = None) -> Generator:
    """The generator `cfg.name` names, configured by `cfg` (the `llm` config group). `probe(code)`
    says whether a program runs on the task (see `colmo.sandbox.ProgramProbe`); the embedded
    generator uses it to offer only working children."""
    if cfg.name not in GENERATORS:
        raise ConfigError(f"llm.name must be one of {', '.join(GENERATORS)}; got {cfg.name!r}")
    if cfg.name == "mutate":
        return MutateGenerator(cfg, seed, probe)
    return GENERATORS[cfg.name](cfg, seed)
