"""`tribojax._parallel`: a call started in the background runs once, whether on its own thread
or (one worker) when first read."""

import threading

import pytest

from tribojax import _parallel


@pytest.mark.parametrize("workers", [1, 2])
def test_a_background_call_runs_once(monkeypatch, workers):
    monkeypatch.setattr(_parallel, "FIT_WORKERS", workers)
    runs, started = [], threading.Event()

    def call():
        runs.append(threading.current_thread().name)
        started.set()
        return 42

    fut = _parallel.in_background(call)
    if workers > 1:  # under way before it is read, on a thread of its own
        assert started.wait(10) and runs[0].startswith("tribojax-background")
    else:
        assert runs == []  # one worker: run when read, on the reader's thread
    assert fut.result() == 42 and fut.result() == 42 and len(runs) == 1
