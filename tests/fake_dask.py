"""A stand-in for a dask Client that runs every submitted chunk in this process, for tests of the client side of
`scalesynth batch` (scalesynth.batch.run_tasks) without a cluster. Only the calls run_tasks makes exist."""

from collections import deque


class InlineFuture:
    def __init__(self, key, outcome):
        self.key, self.outcome = key, outcome

    def result(self):
        if isinstance(self.outcome, BaseException):
            raise self.outcome
        return self.outcome

    def release(self):
        pass


class AsCompleted:
    """distributed.as_completed for inline futures: they complete in submission order."""

    def __init__(self, loop=None):
        self.queue = deque()

    def add(self, fut):
        self.queue.append(fut)

    def __next__(self):
        return self.queue.popleft()


class InlineClient:
    """``inject(fn, args, key)`` may return an exception for the future to raise instead of running ``fn``;
    ``events`` is what get_events('all') returns (tests append scheduler events to it)."""

    loop = None

    def __init__(self, workers=("tcp://127.0.0.1:1", "tcp://127.0.0.1:2"), inject=None):
        self.workers, self.inject, self.events, self.calls = list(workers), inject, [], []

    def nthreads(self):
        return {w: 1 for w in self.workers}

    def get_events(self, topic):
        assert topic == "all"
        return tuple(self.events)

    def submit(self, fn, *args, key, **kwargs):
        self.calls.append((fn, args, key, kwargs))
        error = self.inject(fn, args, key) if self.inject else None
        return InlineFuture(key, error if error is not None else fn(*args))


def use_inline_dask(monkeypatch):
    """Make run_tasks wait on inline futures (it imports as_completed from distributed when called)."""
    monkeypatch.setattr("distributed.as_completed", AsCompleted)
