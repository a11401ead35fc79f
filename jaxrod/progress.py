"""Progress of long work: a tqdm bar on a terminal, nothing otherwise.

Long computations (sweeps, maps, batched fits) run as compiled chunks; between chunks they
report progress here and can be interrupted (Ctrl-C) without losing the finished chunks.
"""

from __future__ import annotations

import sys


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
