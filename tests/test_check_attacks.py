"""The static check against the red-team passes of issue 24 (part 6): a builtin's name is the
builtin only where the program leaves it unbound, every part of a call is visited, byte views
of array buffers and arrays over them are refused; the well-behaved policies still pass."""

from __future__ import annotations

from pathlib import Path

import pytest

from colmo.sandbox.check import ForbiddenProgram, check_program
from colmo.specs import load_task_spec

ALLOWED = ["numpy", "math"]
ROOT = Path(__file__).parent.parent

# isinstance rebound hands out np.ndarray, which builds an object array over a chosen buffer.
ISINSTANCE_REBOUND = {
    "assignment": "isinstance = lambda a, b: b",
    "def": "def isinstance(a, b):\n    return b",
    "import_as": "from numpy import ndim as isinstance",
    "for_target": "for isinstance in [lambda a, b: b]:\n    pass",
    "with_as": "with np.errstate() as isinstance:\n    pass",
    "walrus": "(isinstance := lambda a, b: b)",
    "except_as": "try:\n    pass\nexcept ValueError as isinstance:\n    pass",
    "match_capture": "match 1:\n    case isinstance:\n        pass",
    "comprehension": "[0 for isinstance in [lambda a, b: b]]",
}
ATTACK = """
import numpy as np
{binding}
def policy(obs, isinstance=isinstance):
    kind = np.array([None]).dtype
    cls = isinstance(obs, np.ndarray)
    leak = cls((1,), kind, bytes(8))
    return 0.0
"""


@pytest.mark.parametrize("binding", ISINSTANCE_REBOUND.values(), ids=ISINSTANCE_REBOUND.keys())
def test_a_rebound_isinstance_does_not_unlock_ndarray(binding):
    with pytest.raises(ForbiddenProgram, match=r"forbidden: \.ndarray"):
        check_program(ATTACK.format(binding=binding), ALLOWED)


def test_an_isinstance_parameter_does_not_unlock_ndarray():
    code = "import numpy as np\ndef policy(obs, isinstance=None):\n    return isinstance(obs, np.ndarray)"
    with pytest.raises(ForbiddenProgram, match=r"forbidden: \.ndarray"):
        check_program(code, ALLOWED)


@pytest.mark.parametrize("view", ["a.data.cast('B')", "a.data", "memoryview(a)", "a.tobytes()", "a.view().data.cast('B', (8,))"])
def test_byte_views_of_an_object_array_are_refused(view):
    code = f"import numpy as np\ndef policy(obs):\n    a = np.array([None, obs])\n    b = {view}\n    return 0.0"
    with pytest.raises(ForbiddenProgram, match="forbidden"):
        check_program(code, ALLOWED)


# An array over an object array's buffer is a writable array of its pointers (numpy exports the
# buffer): writing an address there and reading the element back hands out any object.
POINTER_ARRAYS = {
    "frombuffer": ("import numpy as np", "np.frombuffer(a, np.uint64)"),
    "frombuffer imported": ("from numpy import frombuffer", "frombuffer(a, 'u8')"),
    "ndarray imported": ("from numpy import ndarray", "ndarray((2,), 'u8', a)"),
    "ndarray imported as": ("from numpy import ndarray as view", "view((2,), 'u8', a)"),
    "ndarray from a star import": ("from numpy import *", "ndarray((2,), 'u8', a)"),
    "ndarray as a default": ("from numpy import *", "(lambda ndarray=ndarray: ndarray((2,), 'u8', a))()"),
}


@pytest.mark.parametrize("imports, view", POINTER_ARRAYS.values(), ids=POINTER_ARRAYS.keys())
def test_an_array_over_an_object_arrays_pointers_is_refused(imports, view):
    code = f"{imports}\nimport numpy as np\ndef policy(obs):\n    a = np.array([None, obs])\n    b = {view}\n    return 0.0"
    with pytest.raises(ForbiddenProgram, match=r"forbidden: (\.frombuffer|import numpy\.(frombuffer|ndarray)|ndarray)"):
        check_program(code, ALLOWED)


def test_a_star_import_of_numpy_stays_allowed():
    check_program("from numpy import *\ndef policy(obs):\n    return float(sin(obs[0]) * pi)", ALLOWED)


@pytest.mark.parametrize("keyword", ["key=open", "key=__import__", "key=np.ndarray", "key=np.load"])
def test_keyword_arguments_of_isinstance_are_checked(keyword):
    code = f"import numpy as np\ndef policy(obs):\n    return float(isinstance(obs, np.ndarray, {keyword}))"
    with pytest.raises(ForbiddenProgram, match="forbidden"):
        check_program(code, ALLOWED)


def test_the_builtin_isinstance_with_ndarray_stays_allowed():
    check_program("import numpy as np\ndef policy(obs):\n    return float(isinstance(obs, (np.ndarray, float)))", ALLOWED)


@pytest.mark.parametrize("path", sorted((ROOT / "examples").glob("*.py")), ids=lambda p: p.name)
def test_the_examples_pass(path):
    check_program(path.read_text(), ALLOWED)


@pytest.mark.parametrize("task", ["pendulum", "ball_in_cup", "cheetah", "quadruped", "a1"])
def test_the_starters_pass(task):
    spec = load_task_spec(f"{task}.py")
    check_program(spec.starter_code, spec.allowed_imports)
