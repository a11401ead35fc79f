"""Progress of long work: a tqdm bar on a terminal, nothing otherwise.

Long computations (sweeps, maps, batched fits) run as compiled chunks; between chunks they
report progress here and can be interrupted (Ctrl-C) without losing the finished chunks.
"""

from __future__ import annotations

import contextlib
import signal
import sys
import threading


class Interrupted(KeyboardInterrupt):
    """Ctrl-C during long work: ``partial`` holds what was computed before it."""

    def __init__(self, partial, where: str):
        super().__init__(f"interrupted {where}")
        self.partial = partial
        self.where = where


class _NoBar:
    def update(self, k: int = 1) -> None:
        pass

    def close(self) -> None:
        pass


def progress_bar(total: int, desc: str, unit: str = "step", enabled: bool = True,
                 initial: int = 0):
    """A tqdm bar on stderr when ``enabled`` and stderr is a terminal; else a silent one."""
    if not enabled or not sys.stderr.isatty():
        return _NoBar()
    from tqdm import tqdm

    return tqdm(total=total, initial=initial, unit=unit, desc=desc, file=sys.stderr,
                leave=False)


_requested = [False]
_depth = [0]


def interrupt_requested() -> bool:
    """Whether a Ctrl-C came inside ``ctrl_c_guard`` that has not been raised yet (long
    loops check it between chunks)."""
    return _requested[0]


def _inside_gc_callback(frame) -> bool:
    while frame is not None:
        if "gc_callback" in frame.f_code.co_name:
            return True
        frame = frame.f_back
    return False


def _redeliver() -> None:
    if _depth[0] > 0 and _requested[0]:
        signal.raise_signal(signal.SIGINT)


def _on_sigint(signum, frame):
    _requested[0] = True
    if _depth[0] < 0:  # deferred (``ctrl_c_guard(defer=True)``): raised when the block ends
        return
    if _inside_gc_callback(frame):
        # an exception raised in a garbage-collection callback (JAX registers one) is
        # printed and swallowed by Python: deliver the signal again once it has returned
        threading.Timer(0.05, _redeliver).start()
        return
    _requested[0] = False
    raise KeyboardInterrupt


@contextlib.contextmanager
def ctrl_c_guard(defer: bool = False):
    """Ctrl-C inside the block always ends it with KeyboardInterrupt: never lost in a
    garbage-collection callback (where Python swallows exceptions; the signal is delivered
    again once the callback has returned), and, as a second line, remembered for
    ``interrupt_requested``, which long loops check between chunks, and raised when the block
    ends. A Ctrl-C that came before the block (``pending``) is raised as it starts.
    ``defer``: record a Ctrl-C only (for imports, which must not stop half-way); it stays
    pending after the block. In the main thread only (elsewhere the block runs unguarded)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGINT, _on_sigint)
    saved = _depth[0]
    _depth[0] = -1 if defer else max(saved, 0) + 1
    try:
        if not defer and _requested[0]:
            _requested[0] = False
            raise KeyboardInterrupt
        yield
        if not defer and _requested[0]:
            _requested[0] = False
            raise KeyboardInterrupt
    finally:
        _depth[0] = saved
        signal.signal(signal.SIGINT, previous)


def raise_pending() -> None:
    """Raise KeyboardInterrupt for a Ctrl-C that ``ctrl_c_guard(defer=True)`` recorded."""
    if _requested[0]:
        _requested[0] = False
        raise KeyboardInterrupt


def defer_from_now() -> None:
    """Record every Ctrl-C from now on until a ``ctrl_c_guard`` raises it (the command line
    from its first import to its command, so that a Ctrl-C at any moment of its start-up
    ends it with exit status 130 and one line). Main thread only."""
    if threading.current_thread() is threading.main_thread():
        _depth[0] = -1
        signal.signal(signal.SIGINT, _on_sigint)
