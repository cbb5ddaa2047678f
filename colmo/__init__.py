"""colmo: interpretable control policies from program search with in-the-loop gradient-free optimization.

Data flows one way: generator (`generate`) → extraction (`extract`) → parametrize (`program`)
→ sandboxed evaluate + optimize (`sandbox`, `executor`, `optimize`, `task`) → database
(`database`, `store`) → prompt (`prompt`) → generator. `search` runs the loop;
`python -m colmo` is the search app and `python -m colmo.optimize` tunes one policy file.
"""

from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("colmo")
except PackageNotFoundError:  # running from a source tree that is not installed
    __version__ = "0.0.0"
