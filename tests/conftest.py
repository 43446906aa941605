from __future__ import annotations

import pytest

from pendulum_lqg.plant import load_plant


@pytest.fixture(scope="session")
def plant():
    return load_plant()
