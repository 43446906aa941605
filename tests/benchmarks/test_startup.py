"""benchmarks/startup.py: the import-time breakdown charges each module to the library import
that brought it in (the figures of docs/performance.md's start-up section rest on it)."""

from __future__ import annotations

from conftest import load_benchmark_script

# `python -X importtime` prints children before their parent, two spaces deeper per level.
IMPORTTIME = """\
import time: self [us] | cumulative | imported package
import time:       100 |        100 |   encodings
import time:        10 |        110 | site
import time:         5 |          5 | numpy
import time:        50 |         50 |       scipy._lib._util
import time:       200 |        250 |     scipy.stats
import time:        30 |         30 |     numpy.ma
import time:       400 |        680 |   scipy.signal
import time:        40 |         40 |   argparse
import time:         7 |          7 |     scipy._lib._ccallback
import time:        60 |         67 |   scipy.linalg
import time:        20 |        807 | pendulum_lqg.design
"""


def test_each_module_is_charged_to_the_library_import_that_brought_it_in() -> None:
    startup = load_benchmark_script("startup", "startup_benchmark")
    shares = startup.import_shares(IMPORTTIME)
    assert shares == {
        "pendulum_lqg": 20 + 40,            # the package's own module and the stdlib it imports
        "scipy.signal": 400 + 30 + 200 + 50,  # numpy.ma and scipy.stats load with scipy.signal
        "scipy.linalg": 60 + 7,
        "scipy": 0,
        "mujoco": 0,
        "numpy": 5,
        "other": 10 + 100,                  # the interpreter's own start (site, encodings)
    }
    assert sum(shares.values()) == 922
