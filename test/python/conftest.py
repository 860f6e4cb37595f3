"""Import paths of the Python tests, in one place.

pytest loads this before it collects a test; a test file that runs itself as
a child process (python test_x.py ...) imports it at its top instead, as
pytest is not there to do so. The tests see:
- `src` first, so that `semantic_exploration.sim` and `.eval` are the source
  tree under test, not an installed copy that may be stale; the generated
  `semantic_exploration.msg` / `.srv` still come from the sourced install
  space (the package's path is extended to every copy on sys.path, which is
  what catkin's own package __init__ does in a devel space);
- `scripts`, for the tools the tests drive (mission.py, report.py, ...);
- this folder, for helpers one test file takes from another."""
import os
import pkgutil
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))

for path in (HERE, os.path.join(ROOT, "scripts"), os.path.join(ROOT, "src")):
    if path in sys.path:
        sys.path.remove(path)
    sys.path.insert(0, path)

import semantic_exploration  # noqa: E402

semantic_exploration.__path__ = pkgutil.extend_path(list(semantic_exploration.__path__), "semantic_exploration")
