"""``python -m pendulum_lqg.cli``: the ``pendulum-lqg`` command."""

import sys

from pendulum_lqg.cli import main

if __name__ == "__main__":
    sys.exit(main())
