"""The scorer asks a model with torch on one thread and gives the caller's thread count back."""

from __future__ import annotations

import pytest

from pendulum_lqg.scoreboard.sb3 import one_torch_thread


def test_one_torch_thread_sets_one_and_restores_the_callers_count():
    torch = pytest.importorskip("torch", reason="the rl extra (torch) is absent")
    before = torch.get_num_threads()
    torch.set_num_threads(2)
    try:
        with one_torch_thread():
            assert torch.get_num_threads() == 1
        assert torch.get_num_threads() == 2
        with pytest.raises(RuntimeError), one_torch_thread():
            raise RuntimeError("a model's error")
        assert torch.get_num_threads() == 2          # restored on an error too
    finally:
        torch.set_num_threads(before)


def test_without_torch_loaded_the_block_runs_unchanged(monkeypatch):
    import sys

    monkeypatch.delitem(sys.modules, "torch", raising=False)
    ran = []
    with one_torch_thread():
        ran.append(True)
    assert ran == [True] and "torch" not in sys.modules
